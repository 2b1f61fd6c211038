#include "meshcol/narrowphase.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/epa.hpp"
#include "meshcol/gjk.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/sat.hpp"
#include "rescale.hpp"

namespace meshcol {

ShapeView ConvexSetView::shape(std::int64_t h) const {
    ShapeView s;
    s.kind = static_cast<ShapeKind>(kinds[h]);
    const std::int64_t begin = offsets[h];
    s.vertices = reinterpret_cast<const Vec3*>(vertices + 3 * begin);
    s.vertex_count = static_cast<int>(offsets[h + 1] - begin);
    if (s.vertex_count == 0) s.vertices = nullptr;
    if (adjacency_offsets != nullptr && adjacency != nullptr) {
        s.adjacency_offsets = adjacency_offsets + begin;
        s.adjacency = adjacency;
        if (climb_list_offsets != nullptr && climb_list_offsets[h + 1] > climb_list_offsets[h])
            s.climb_lists = climb_lists + climb_list_offsets[h];
    }
    if (face_offsets != nullptr && edge_pair_offsets != nullptr) {
        s.has_features = true;
        s.face_normals = reinterpret_cast<const Vec3*>(face_normals + 3 * face_offsets[h]);
        s.face_count = static_cast<int>(face_offsets[h + 1] - face_offsets[h]);
        // Edge classes when SAT needs them (no edges: none to compute).
        if (edge_pair_offsets[h + 1] > edge_pair_offsets[h]) {
            s.set = this;
            s.set_index = h;
        }
    }
    for (int k = 0; k < 4; ++k) s.params[k] = params[4 * h + k];
    return s;
}

ClimbLists::ClimbLists(const ConvexSetView& set, int threads) {
    const std::int64_t h_count = set.shape_count;
    if (set.adjacency_offsets == nullptr || set.adjacency == nullptr || h_count == 0) return;
    std::vector<std::int64_t> offsets(static_cast<size_t>(h_count) + 1, 0);
    for (std::int64_t h = 0; h < h_count; ++h) {
        const ShapeView s = set.shape(h);
        const std::int64_t rows = climbs(s) ? s.vertex_count * climb_rows(s.vertex_count) : 0;
        offsets[h + 1] = offsets[h] + rows;
    }
    if (offsets.back() == 0) return;
    std::unique_ptr<ClimbList[]> lists(new ClimbList[static_cast<size_t>(offsets.back())]);
    std::vector<char> made(static_cast<size_t>(h_count), 0);
    const int n_threads = resolve_threads(threads, h_count, defaults::min_shapes_per_thread);
    parallel_for(h_count, n_threads, [&](long long begin, long long end) {
        for (long long h = begin; h < end; ++h)
            if (offsets[h + 1] > offsets[h])
                made[h] = make_climb_lists(set.shape(h), lists.get() + offsets[h]);
    });
    // A shape whose lists do not fit keeps none (it climbs on the CSR arrays): the lists
    // after it move down.
    std::int64_t kept = 0;
    for (std::int64_t h = 0; h < h_count; ++h) {
        const std::int64_t first = offsets[h], count = made[h] ? offsets[h + 1] - first : 0;
        offsets[h] = kept;
        if (count > 0 && first != kept)
            std::copy(lists.get() + first, lists.get() + first + count, lists.get() + kept);
        kept += count;
    }
    offsets[h_count] = kept;
    if (kept == 0) return;
    offsets_ = std::move(offsets);
    lists_ = std::move(lists);
}

void ClimbLists::attach(ConvexSetView& set) const {
    set.climb_list_offsets = offsets_.empty() ? nullptr : offsets_.data();
    set.climb_lists = lists_.get();
}

struct EdgeClasses::Entry {
    std::vector<double> directions;  // (count, 3)
    std::vector<GaussArc> arcs;      // one per true edge, or none
};

// The entries are zeroed by calloc, not written: a large allocation's pages stay unmapped
// until a shape's classes are stored (an atomic pointer or int of zero bytes is null or 0:
// they are lock-free and hold their value's bytes).
EdgeClasses::EdgeClasses(std::int64_t shape_count)
    : shape_count_(std::max<std::int64_t>(shape_count, 0)),
      entries_(static_cast<std::atomic<Entry*>*>(
          std::calloc(static_cast<size_t>(shape_count_) + 1, sizeof(std::atomic<Entry*>)))),
      lower_(static_cast<std::atomic<int>*>(
          std::calloc(static_cast<size_t>(shape_count_) + 1, sizeof(std::atomic<int>)))) {
    static_assert(std::atomic<Entry*>::is_always_lock_free && std::atomic<int>::is_always_lock_free);
    static_assert(sizeof(std::atomic<Entry*>) == sizeof(Entry*));
    static_assert(sizeof(std::atomic<int>) == sizeof(int));
    if (entries_ == nullptr || lower_ == nullptr) {
        std::free(entries_);
        std::free(lower_);
        throw std::bad_alloc();
    }
}

EdgeClasses::~EdgeClasses() {
    for (std::int64_t h = 0; h < shape_count_; ++h)
        delete entries_[h].load(std::memory_order_relaxed);
    std::free(entries_);
    std::free(lower_);
}

namespace {

const Vec3* shape_vertices(const ConvexSetView& set, std::int64_t h) {
    return reinterpret_cast<const Vec3*>(set.vertices + 3 * set.offsets[h]);
}

}  // namespace

EdgeClasses::List EdgeClasses::get(const ConvexSetView& set, std::int64_t h) {
    Entry* entry = entries_[h].load(std::memory_order_acquire);
    if (entry == nullptr) {
        auto made = std::make_unique<Entry>();
        const std::int64_t first = set.edge_pair_offsets[h];
        const auto count = static_cast<size_t>(set.edge_pair_offsets[h + 1] - first);
        const std::int32_t* pairs = set.edge_pairs + 2 * first;
        std::vector<std::int32_t> class_of(count);
        edge_direction_classes(shape_vertices(set, h), pairs, count, made->directions,
                               class_of.data());
        const std::int64_t face_first = set.face_offsets[h];
        gauss_arcs(shape_vertices(set, h), static_cast<int>(set.offsets[h + 1] - set.offsets[h]),
                   reinterpret_cast<const Vec3*>(set.face_normals + 3 * face_first),
                   static_cast<int>(set.face_offsets[h + 1] - face_first), pairs, class_of.data(),
                   count, made->arcs);
        // The first list published is every thread's (a thread that lost frees its own).
        Entry* seen = nullptr;
        if (entries_[h].compare_exchange_strong(seen, made.get(), std::memory_order_acq_rel,
                                                std::memory_order_acquire))
            entry = made.release();
        else
            entry = seen;
    }
    return {reinterpret_cast<const Vec3*>(entry->directions.data()),
            static_cast<int>(entry->directions.size() / 3),
            entry->arcs.empty() ? nullptr : entry->arcs.data(),
            static_cast<int>(entry->arcs.size())};
}

int EdgeClasses::lower_bound(const ConvexSetView& set, std::int64_t h, int wanted) {
    if (const Entry* entry = entries_[h].load(std::memory_order_acquire))
        return static_cast<int>(entry->directions.size() / 3);
    const int known = std::max(lower_[h].load(std::memory_order_relaxed) - 1, 0);  // 0: none yet
    if (known >= wanted) return known;
    const std::int64_t first = set.edge_pair_offsets[h];
    const std::int64_t count = set.edge_pair_offsets[h + 1] - first;
    const std::int64_t prefix = std::max<std::int64_t>(wanted, defaults::sat_edge_class_prefix);
    // Most of the edges: the classes themselves, kept, cost about what the bound would.
    if (4 * prefix >= 3 * count) return get(set, h).count;
    const auto bound = static_cast<int>(edge_direction_class_count(
        shape_vertices(set, h), set.edge_pairs + 2 * first, static_cast<size_t>(prefix)));
    // Any bound found is one (a thread's smaller one may replace a larger: still a bound).
    if (bound > known) lower_[h].store(bound + 1, std::memory_order_relaxed);
    return std::max(bound, known);
}

void attach_edges(ShapeView& shape) {
    if (shape.set == nullptr) return;
    const EdgeClasses::List list = shape.set->edge_classes->get(*shape.set, shape.set_index);
    shape.edge_directions = list.directions;
    shape.edge_count = list.count;
    shape.arcs = list.arcs;
    shape.arc_count = list.arc_count;
    shape.set = nullptr;
    shape.set_index = -1;
}

int edge_count_upper_bound(const ShapeView& shape) {
    if (shape.set == nullptr) return shape.edge_count;
    const std::int64_t* offsets = shape.set->edge_pair_offsets;
    return static_cast<int>(offsets[shape.set_index + 1] - offsets[shape.set_index]);
}

int edge_count_lower_bound(const ShapeView& shape, int wanted) {
    if (shape.set == nullptr) return shape.edge_count;
    return shape.set->edge_classes->lower_bound(*shape.set, shape.set_index, wanted);
}

namespace {

PairResult to_world(PairResult r, const Pose& pose_a) {
    r.point_a = pose_a.apply(r.point_a);
    r.point_b = pose_a.apply(r.point_b);
    r.normal = pose_a.rotate(r.normal);
    return r;
}

Status worse(Status x, Status y) {
    return static_cast<int>(x) >= static_cast<int>(y) ? x : y;
}

}  // namespace

namespace {

// The penetration result from EPA's (a's frame), checked by exact SAT on small polytopes:
// SAT verifies EPA's depth and replaces it when they disagree.
PairResult penetration_result(PairResult r, const EpaResult& e, const ShapeView& a,
                              const Pose& pose_a, const ShapeView& b, const Pose& pose_b,
                              double touch) {
    const double ma = margin(a), mb = margin(b);
    r.intersects = true;
    r.distance = 0.0;
    r.iterations += e.iterations;
    r.status = worse(r.status, e.status);
    r.depth = e.depth + (ma + mb);
    r.normal = e.normal;
    r.point_a = e.point_a + e.normal * ma;
    r.point_b = e.point_b - e.normal * mb;
    PairResult world = to_world(r, pose_a);

    const SatResult sat = sat_penetration(a, pose_a, b, pose_b);
    if (sat.ran) {
        const bool agree = e.status == Status::CONVERGED &&
                           std::fabs(e.depth - sat.depth) <=
                               defaults::sat_agreement_relative_depth *
                                   std::fmax(sat.depth, touch) &&
                           dot(world.normal, sat.normal) >=
                               1.0 - defaults::sat_agreement_normal_cosine;
        world.status = Status::CONVERGED;
        if (agree) {
            world.depth = sat.depth;
        } else {
            // SAT is exact: take its depth and axis, and find witness points by bringing the
            // shapes into contact along the axis (b moved by depth * normal) and asking GJK
            // for a common point.
            world.depth = sat.depth;
            world.normal = sat.normal;
            Pose moved = pose_b;
            moved.translation += sat.normal * sat.depth;
            MinkowskiDifference contact(a, pose_a, b, moved, true);
            const GjkResult gc = gjk_run(contact, GjkOptions{});
            world.iterations += gc.iterations;
            world.point_a = pose_a.apply(gc.point_a);
            world.point_b = pose_a.apply(gc.point_b) - sat.normal * sat.depth;
        }
    }
    return world;
}

// The pipeline (as coal and parry): GJK on the cores (sphere and capsule radii are margins,
// added exactly afterwards); EPA on the full shapes only when the cores overlap; for small
// polytopes an exact SAT that verifies EPA's depth and replaces it when they disagree. The
// pair's lengths must be within rescale::kSafeLow..kSafeHigh (`query_pair` sees to it).
PairResult query_in_range(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, QueryKind kind, double radius_a, double radius_b) {
    PairResult r;
    MinkowskiDifference core(a, pose_a, b, pose_b, false, radius_a, radius_b);
    const double touch = defaults::contact_tolerance * core.scale;
    EpaOptions eopt;
    const auto curved = [](const ShapeView& s) {
        return s.kind == ShapeKind::CYLINDER || s.kind == ShapeKind::ELLIPSOID;
    };
    if (curved(a) || curved(b))
        eopt.relative_tolerance = defaults::epa_curved_relative_tolerance;
    // Two polytopes whose supports along and around the centre line lie well past the origin
    // overlap deeply, as a rule: EPA then starts from those supports and GJK is not run. The
    // first is GJK's first, so a pair left to GJK loses only the supports the attempt took.
    // Only for polytopes that climb: on small ones (a scan a support) GJK is cheap and EPA
    // short, and the attempt saved less than it cost on touching pairs.
    SimplexVertex first;
    bool have_first = false;
    const Vec3 line = core.translation_b;
    if (kind == QueryKind::PENETRATION && core.climb_both && squared_norm(line) > 0.0) {
        first = core.support(line);
        have_first = true;
        const int hint_a = core.hint_a, hint_b = core.hint_b;
        const Vec3 last_direction = core.last_direction;
        const EpaResult e = epa_penetration_deep(core, first, eopt);
        if (e.status != Status::NOT_RUN) {
            r.status = Status::CONVERGED;
            return penetration_result(r, e, a, pose_a, b, pose_b, touch);
        }
        // GJK goes on from its first support as if the attempt had not been made.
        core.hint_a = hint_a;
        core.hint_b = hint_b;
        core.last_direction = last_direction;
    }
    GjkOptions opt;
    opt.stop_when_separated = kind == QueryKind::INTERSECTS;
    const GjkResult g = gjk_run(core, opt, have_first ? &first : nullptr);
    const double ma = margin(a), mb = margin(b), msum = ma + mb;
    r.status = g.status;
    r.iterations = g.iterations;
    if (!g.overlap) {
        const double d = g.distance - msum;
        const Vec3 n = g.normal;  // a's frame, a to b
        r.normal = n;
        r.point_a = g.point_a + n * ma;
        r.point_b = g.point_b - n * mb;
        if (d > touch) {
            r.distance = d;
            r.intersects = false;
        } else {
            // The cores are apart but the radii overlap: the depth is exact.
            r.intersects = true;
            r.distance = 0.0;
            if (kind == QueryKind::PENETRATION) r.depth = std::fmax(0.0, -d);
            else if (kind == QueryKind::DISTANCE) r.normal = Vec3{};
        }
        return to_world(r, pose_a);
    }
    r.intersects = true;
    r.distance = 0.0;
    r.point_a = g.point_a;
    r.point_b = g.point_a;
    if (kind != QueryKind::PENETRATION) return to_world(r, pose_a);
    if (squared_norm(g.contact_direction) > 0.0) {
        // A support of GJK's lay within the contact distance of the origin along its
        // direction: the shapes overlap along it by at most that distance, so it is a valid
        // normal of this touching pair and EPA is not needed.
        const double length = norm(g.contact_direction);
        EpaResult e;
        e.status = Status::CONVERGED;
        e.normal = g.contact_direction * (1.0 / length);
        e.depth = std::fmax(0.0, g.contact_support / length);
        e.point_a = g.point_a;
        e.point_b = g.point_b;
        return penetration_result(r, e, a, pose_a, b, pose_b, touch);
    }

    // EPA on the cores: for swept shapes the depth of (core_a + ball) - (core_b + ball) is the
    // core depth plus both radii (the support function gains the radii in every direction),
    // so spheres and capsules stay exact and EPA only meets curved surfaces on cylinders and
    // ellipsoids.
    const EpaResult e = epa_penetration(core, g.simplex, eopt);
    return penetration_result(r, e, a, pose_a, b, pose_b, touch);
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

PairResult query_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                      const Pose& pose_b, QueryKind kind, double radius_a, double radius_b) {
    if (a.kind == ShapeKind::HALFSPACE || b.kind == ShapeKind::HALFSPACE)
        return half_space_pair(a, pose_a, b, pose_b, kind);
    // The climbs' reads are dependent loads; fetched up front, their misses overlap.
    prefetch(a);
    prefetch(b);
    if (radius_a < 0.0) radius_a = bounding_radius(a);
    if (radius_b < 0.0) radius_b = bounding_radius(b);
    double half = std::fmax(0.5 * radius_a, 0.5 * radius_b);
    rescale::reach(half, pose_a.translation, pose_b.translation);
    const rescale::Frame f = rescale::choose(pose_a.translation, half);
    if (!f.active && f.finite) return query_in_range(a, pose_a, b, pose_b, kind, radius_a, radius_b);
    PairResult r;
    if (!f.finite) {
        r.status = Status::OUT_OF_RANGE;
        r.distance = r.depth = kNaN;
        r.normal = r.point_a = r.point_b = Vec3{kNaN, kNaN, kNaN};
        return r;
    }
    // Far out of range (see rescale.hpp): the same query, moved and scaled by a power of two.
    std::vector<Vec3> storage_a, storage_b;
    const ShapeView sa = rescale::scaled(a, f, storage_a), sb = rescale::scaled(b, f, storage_b);
    Pose pa = pose_a, pb = pose_b;
    pa.translation = Vec3{};
    pb.translation = f.point(pose_b.translation);
    r = query_in_range(sa, pa, sb, pb, kind, f.length(radius_a), f.length(radius_b));
    r.distance = f.world_length(r.distance);
    r.depth = f.world_length(r.depth);
    r.point_a = f.world_point(r.point_a);
    r.point_b = f.world_point(r.point_b);
    if (!std::isfinite(r.distance) || !std::isfinite(r.depth) || !is_finite(r.point_a) ||
        !is_finite(r.point_b))
        r.status = Status::OUT_OF_RANGE;
    return r;
}

ShapeRadii::ShapeRadii(std::int64_t shape_count)
    : radius_(new std::atomic<double>[static_cast<size_t>(shape_count)]) {
    for (std::int64_t h = 0; h < shape_count; ++h)
        radius_[h].store(kUnchecked, std::memory_order_relaxed);
}

void run_batch(const ConvexSetView& set, const double* poses, const std::int64_t* pairs,
               long long pair_count, QueryKind kind, int threads, const BatchOutput& out,
               ShapeRadii* radii) {
    const std::int64_t h_count = set.shape_count;
    // Each shape and pose a pair uses is checked once, not once per pair, on every thread;
    // a shape no pair uses is not read at all (a big set queried for a few pairs pays for
    // those few: the checks read every vertex, and the per-shape state is kept for the
    // batch's shapes only, `BatchShapes`). Poses are checked up front; a shape's vertices
    // (validity and bounding radius, one pass) by the first pair that uses it, just before
    // its query reads them again: in broad-phase output most shapes are in only a few pairs,
    // and a separate pass over them all would bring each shape from memory twice. The set's
    // owner keeps the radii between batches (`radii`); else they last this batch.
    BatchShapes shapes(h_count, pairs, pair_count);
    const std::int64_t slots = shapes.size();
    std::vector<char> ok = shapes.take_used();
    // Slots a pair of this batch has met (`read_vertices` on the first; a thread that meets
    // one at the same moment as another reads it twice, harmlessly).
    std::unique_ptr<std::atomic<char>[]> met(new std::atomic<char>[static_cast<size_t>(slots)]);
    for (std::int64_t k = 0; k < slots; ++k) met[k].store(0, std::memory_order_relaxed);
    const auto first_meeting = [&](std::int64_t slot) {
        if (met[slot].load(std::memory_order_relaxed) != 0) return false;
        met[slot].store(1, std::memory_order_relaxed);
        return true;
    };
    std::vector<Pose> pose(static_cast<size_t>(poses == nullptr ? 0 : slots));
    std::unique_ptr<ShapeRadii> batch_radii;
    if (radii == nullptr) {
        batch_radii = std::make_unique<ShapeRadii>(h_count);
        radii = batch_radii.get();
    }
    if (poses != nullptr) {
        const int pose_threads = resolve_threads(threads, slots, defaults::min_shapes_per_thread);
        parallel_for(slots, pose_threads, [&](long long begin, long long end) {
            for (long long k = begin; k < end; ++k) {
                if (!ok[k]) continue;
                const double* m = poses + 16 * shapes.shape(k);
                if (!is_rigid_matrix4(m, defaults::rigid_tolerance)) ok[k] = 0;
                else pose[k] = Pose::from_matrix4(m);
            }
        });
    }
    const Pose identity{};
    const int n_threads = resolve_threads(threads, pair_count, defaults::min_pairs_per_thread);
    parallel_for(pair_count, n_threads, [&](long long begin, long long end) {
        for (long long i = begin; i < end; ++i) {
            const std::int64_t ia = pairs[2 * i], ib = pairs[2 * i + 1];
            const std::int64_t ka = shapes.slot_of(2 * i), kb = shapes.slot_of(2 * i + 1);
            PairResult r;
            const double ra = ok[ka] ? radii->get(set, ia) : kNaN;
            const double rb = ok[kb] ? radii->get(set, ib) : kNaN;
            if (std::isnan(ra) || std::isnan(rb)) {
                r.status = Status::INVALID_INPUT;
                r.distance = r.depth = kNaN;
                r.normal = r.point_a = r.point_b = Vec3{kNaN, kNaN, kNaN};
            } else {
                const ShapeView sa = set.shape(ia), sb = set.shape(ib);
                if (first_meeting(ka)) read_vertices(sa);
                if (first_meeting(kb)) read_vertices(sb);
                const Pose& pa = poses == nullptr ? identity : pose[ka];
                const Pose& pb = poses == nullptr ? identity : pose[kb];
                r = query_pair(sa, pa, sb, pb, kind, ra, rb);
            }
            if (out.distance) out.distance[i] = r.distance;
            if (out.depth) out.depth[i] = r.depth;
            store_row(out.normal, i, r.normal);
            store_row(out.point_a, i, r.point_a);
            store_row(out.point_b, i, r.point_b);
            if (out.iterations) out.iterations[i] = r.iterations;
            if (out.status) out.status[i] = static_cast<std::int8_t>(r.status);
            if (out.intersects) out.intersects[i] = r.intersects;
        }
    });
}

void all_edge_classes(const ConvexSetView& set, int threads, std::vector<std::int64_t>& offsets,
                      std::vector<double>& directions) {
    const std::int64_t h_count = set.shape_count;
    std::vector<EdgeClasses::List> lists(static_cast<size_t>(h_count));
    const bool pending = set.edge_pair_offsets != nullptr && set.edge_classes != nullptr;
    if (pending) {
        const int n_threads = resolve_threads(threads, h_count, defaults::min_shapes_per_thread);
        parallel_for(h_count, n_threads, [&](long long begin, long long end) {
            for (long long h = begin; h < end; ++h)
                if (set.edge_pair_offsets[h + 1] > set.edge_pair_offsets[h])
                    lists[static_cast<size_t>(h)] = set.edge_classes->get(set, h);
        });
    }
    offsets.assign(static_cast<size_t>(h_count) + 1, 0);
    for (std::int64_t h = 0; h < h_count; ++h)
        offsets[static_cast<size_t>(h) + 1] = offsets[static_cast<size_t>(h)] + lists[static_cast<size_t>(h)].count;
    directions.resize(3 * static_cast<size_t>(offsets.back()));
    for (std::int64_t h = 0; h < h_count; ++h) {
        const EdgeClasses::List& l = lists[static_cast<size_t>(h)];
        if (l.count > 0)
            std::copy_n(reinterpret_cast<const double*>(l.directions), 3 * static_cast<size_t>(l.count),
                        directions.data() + 3 * offsets[static_cast<size_t>(h)]);
    }
}

void world_aabbs(const ConvexSetView& set, const double* poses, double* lo, double* hi,
                 int threads) {
    const int n_threads =
        resolve_threads(threads, set.shape_count, defaults::min_shapes_per_thread);
    parallel_for(set.shape_count, n_threads, [&](long long begin, long long end) {
        for (long long h = begin; h < end; ++h) {
            const ShapeView s = set.shape(h);
            Pose p;
            bool good = is_valid(s);
            if (poses != nullptr) {
                if (!is_rigid_matrix4(poses + 16 * h, defaults::rigid_tolerance)) good = false;
                else p = Pose::from_matrix4(poses + 16 * h);
            }
            Vec3 a{kNaN, kNaN, kNaN}, b{kNaN, kNaN, kNaN};
            if (good) world_aabb(s, p, a, b);
            store_row(lo, h, a);
            store_row(hi, h, b);
        }
    });
}

void bounding_radii(const ConvexSetView& set, double* radii, int threads) {
    const int n_threads =
        resolve_threads(threads, set.shape_count, defaults::min_shapes_per_thread);
    parallel_for(set.shape_count, n_threads, [&](long long begin, long long end) {
        for (long long h = begin; h < end; ++h) {
            const ShapeView s = set.shape(h);
            radii[h] = is_valid(s) ? bounding_radius(s) : kNaN;
        }
    });
}

}  // namespace meshcol
