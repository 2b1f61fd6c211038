#include "meshcol/gjk.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include "climb.hpp"

namespace meshcol {

MinkowskiDifference::MinkowskiDifference(const ShapeView& shape_a, const Pose& pose_a,
                                         const ShapeView& shape_b, const Pose& pose_b,
                                         bool margins, double radius_a, double radius_b)
    : a(&shape_a), b(&shape_b), with_margins(margins) {
    // b in a's frame: x_a = Ra^T (Rb x_b + tb - ta).
    rotation_b = pose_a.rotation.transposed() * pose_b.rotation;
    translation_b = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
    if (radius_a < 0.0) radius_a = bounding_radius(shape_a);
    if (radius_b < 0.0) radius_b = bounding_radius(shape_b);
    climb_both = climbs(shape_a) && climbs(shape_b);
    climb_lists_both =
        climb_both && shape_a.climb_lists != nullptr && shape_b.climb_lists != nullptr;
    scan_both = scans(shape_a) && scans(shape_b);
    scale = radius_a + radius_b + norm(translation_b);
    if (!(scale > 0.0)) scale = 1.0;
}

namespace {

// The support point of a - b from the shapes' support points `sa` and `sb` in `d` (b's in its
// own frame), with the margins when asked; records them as the next climbs' hints.
MESHCOL_CLIMB_INLINE SimplexVertex finish_support(MinkowskiDifference& md, const Vec3& d,
                                                  const SupportPoint& sa, const SupportPoint& sb) {
    SimplexVertex v;
    md.hint_a = sa.index;
    md.hint_b = sb.index;
    v.a = sa.point;
    v.b = md.rotation_b * sb.point + md.translation_b;
    v.index_a = sa.index;
    v.index_b = sb.index;
    if (md.with_margins) {
        const double ma = margin(*md.a), mb = margin(*md.b);
        if (ma > 0.0 || mb > 0.0) {
            const double n = norm(d);
            if (n > 0.0) {
                v.a += d * (ma / n);
                v.b -= d * (mb / n);
            }
            if (ma > 0.0) v.index_a = -1;
            if (mb > 0.0) v.index_b = -1;
        }
    }
    v.w = v.a - v.b;
    return v;
}

}  // namespace

SimplexVertex MinkowskiDifference::support(const Vec3& d) {
    SupportPoint sa, sb;
    if (scan_both) {
        const Vec3 db = rotation_b.transpose_times(-d);
        // Scans start nowhere: no warm start to decide.
        int ia, ib;
        climb::scan_pair(a->vertices, a->vertex_count, d, b->vertices, b->vertex_count, db, ia,
                         ib);
        sa = {a->vertices[ia], ia};
        sb = {b->vertices[ib], ib};
        return finish_support(*this, d, sa, sb);
    }
    // The previous support points are good starts for the climbs when the direction turned
    // little (as in EPA and late GJK); after a larger turn (early GJK) a few strided samples
    // start them nearer the top. Compares squares: cos^2 > c^2 without a square root.
    constexpr double c2 = defaults::support_warm_start_min_cosine *
                          defaults::support_warm_start_min_cosine;
    const double dd = dot(d, last_direction);
    const bool near =
        dd > 0.0 && dd * dd > c2 * (squared_norm(d) * squared_norm(last_direction));
    last_direction = d;
    const int start_a = near ? hint_a : -1, start_b = near ? hint_b : -1;
    const Vec3 db = rotation_b.transpose_times(-d);
    // Only the lists' joint climb inline: the CSR arrays' joint climbs inlined beside it made
    // every support (the scanning pairs' too) pay for their registers, 2-4% of a 16-point
    // pair; a pair without lists on both sides climbs each shape in `support_core`.
    if (climb_lists_both) {
        climb::climb_pair(*a, d, start_a, *b, db, start_b, sa, sb);
    } else {
        sa = support_core(*a, d, start_a);
        sb = support_core(*b, db, start_b);
    }
    return finish_support(*this, d, sa, sb);
}

SimplexVertex MinkowskiDifference::support_from(const Vec3& d, int start_a, int start_b) {
    if (start_a >= 0) hint_a = start_a;
    if (start_b >= 0) hint_b = start_b;
    last_direction = d;
    return support(d);
}


namespace {

// The closest feature of a simplex to the origin: which of its points span it (in the order
// the subalgorithm visits them) and their barycentric weights. It works on the Minkowski
// points alone, so the simplex itself (three points per vertex) is rearranged once, at the
// end, and only when it shrinks.
struct Feature {
    int count = 0;
    int index[4] = {0, 1, 2, 3};
    double weight[4] = {1.0, 0.0, 0.0, 0.0};
};

void vertex_feature(Feature& f, int i) {
    f.count = 1;
    f.index[0] = i;
    f.weight[0] = 1.0;
}

// Closest point of segment w[i] w[j] to the origin (Ericson 2004, sec. 5.1.2).
Vec3 closest_segment(const Vec3* w, int i, int j, Feature& f) {
    const Vec3 p = w[i], q = w[j];
    const Vec3 pq = q - p;
    const double len2 = squared_norm(pq);
    const double t_num = -dot(p, pq);
    if (t_num <= 0.0 || len2 <= 0.0) {
        vertex_feature(f, i);
        return p;
    }
    if (t_num >= len2) {
        vertex_feature(f, j);
        return q;
    }
    const double t = t_num / len2;
    f.count = 2;
    f.index[0] = i;
    f.index[1] = j;
    f.weight[0] = 1.0 - t;
    f.weight[1] = t;
    return p + pq * t;
}

// Closest point of triangle w[i] w[j] w[k] to the origin by Voronoi regions (Ericson 2004,
// sec. 5.1.5). In the face region the point is the plane projection n (n.p)/(n.n), which is
// more accurate than a barycentric sum when the face is far from the origin (parallel faces).
Vec3 closest_triangle(const Vec3* w, int i, int j, int k, Feature& f) {
    const Vec3 a = w[i], b = w[j], c = w[k];
    const Vec3 ab = b - a, ac = c - a;
    const double d1 = -dot(ab, a), d2 = -dot(ac, a);
    if (d1 <= 0.0 && d2 <= 0.0) {
        vertex_feature(f, i);
        return a;
    }
    const double d3 = -dot(ab, b), d4 = -dot(ac, b);
    if (d3 >= 0.0 && d4 <= d3) {
        vertex_feature(f, j);
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return closest_segment(w, i, j, f);
    const double d5 = -dot(ab, c), d6 = -dot(ac, c);
    if (d6 >= 0.0 && d5 <= d6) {
        vertex_feature(f, k);
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return closest_segment(w, i, k, f);
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return closest_segment(w, j, k, f);
    const double sum = va + vb + vc;
    const Vec3 n = cross(ab, ac);
    const double nn = squared_norm(n);
    if (!(sum > 0.0) || !(nn > 0.0)) {
        // Flat (collinear) triangle: the best of its three edges.
        Feature f1, f2, f3;
        const Vec3 x1 = closest_segment(w, i, j, f1);
        const Vec3 x2 = closest_segment(w, i, k, f2);
        const Vec3 x3 = closest_segment(w, j, k, f3);
        const double n1 = squared_norm(x1), n2 = squared_norm(x2), n3 = squared_norm(x3);
        if (n1 <= n2 && n1 <= n3) {
            f = f1;
            return x1;
        }
        if (n2 <= n3) {
            f = f2;
            return x2;
        }
        f = f3;
        return x3;
    }
    f.count = 3;
    f.index[0] = i;
    f.index[1] = j;
    f.index[2] = k;
    f.weight[0] = va / sum;
    f.weight[1] = vb / sum;
    f.weight[2] = vc / sum;
    return n * (dot(n, a) / nn);
}

// Tetrahedron (Ericson 2004, sec. 5.1.6): test the origin against each face plane, oriented
// away from the opposite vertex; the closest of the faces it lies outside of. Returns false
// when the origin is inside: `f` then holds all four points with the origin's barycentric
// weights.
// Whether the tetrahedron w[0..3] is too flat to tell the origin's side of its faces.
bool flat_tetrahedron(const Vec3* w) {
    const Vec3 a = w[0], b = w[1], c = w[2], d = w[3];
    const double volume = dot(d - a, cross(b - a, c - a));
    // The largest coordinate of the three edges from a, by plain compares: std::fmax (a libm
    // call here, which also spills the caller's registers) gives the same number on finite
    // points, all these are >= +0, and a NaN makes `volume` NaN and `flat` false either way.
    const auto larger = [](double x, double y) { return x > y ? x : y; };
    const auto largest_abs = [&larger](const Vec3& v) {
        return larger(std::fabs(v.x), larger(std::fabs(v.y), std::fabs(v.z)));
    };
    const double size = larger(larger(largest_abs(b - a), largest_abs(c - a)), largest_abs(d - a));
    return std::fabs(volume) <= defaults::gjk_flat_tetrahedron_volume * size * size * size;
}

bool closest_tetrahedron(const Vec3* w, Feature& f, Vec3& closest) {
    const Vec3 a = w[0], b = w[1], c = w[2], d = w[3];
    const bool flat = flat_tetrahedron(w);
    double best = std::numeric_limits<double>::infinity();
    bool outside_any = false;
    Feature best_f;
    Vec3 best_x;
    // Face (i, j, k) against the opposite vertex o; the four calls below are the faces in a
    // fixed order (written out, so that the points' indices are constants).
    const auto face = [&](int i, int j, int k, int o) {
        const Vec3 x0 = w[i];
        const Vec3 n = cross(w[j] - x0, w[k] - x0);
        const double side_origin = -dot(n, x0);
        const double side_opposite = dot(n, w[o] - x0);
        const bool outside = flat || side_origin * side_opposite < 0.0;
        if (!outside) return;
        outside_any = true;
        Feature ff;
        const Vec3 x = closest_triangle(w, i, j, k, ff);
        const double dist = squared_norm(x);
        if (dist < best) {
            best = dist;
            best_f = ff;
            best_x = x;
        }
    };
    face(0, 1, 2, 3);
    face(0, 2, 3, 1);
    face(0, 3, 1, 2);
    face(1, 3, 2, 0);
    if (outside_any && !(flat && best == 0.0)) {
        f = best_f;
        closest = best_x;
        return true;
    }
    // Inside: the weights are the signed sub-volumes with the origin replacing each vertex.
    auto sub_volume = [](const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
        return dot(x3 - x0, cross(x1 - x0, x2 - x0));
    };
    const Vec3 o{0.0, 0.0, 0.0};
    const double w0 = sub_volume(o, b, c, d), w1 = sub_volume(a, o, c, d);
    const double w2 = sub_volume(a, b, o, d), w3 = sub_volume(a, b, c, o);
    const double total = w0 + w1 + w2 + w3;
    f.count = 4;
    for (int k = 0; k < 4; ++k) f.index[k] = k;
    if (total != 0.0 && std::isfinite(total)) {
        f.weight[0] = w0 / total;
        f.weight[1] = w1 / total;
        f.weight[2] = w2 / total;
        f.weight[3] = w3 / total;
    } else {
        f.weight[0] = f.weight[1] = f.weight[2] = f.weight[3] = 0.25;
    }
    closest = Vec3{0.0, 0.0, 0.0};
    return false;
}

// Closest feature of the `size` points `w`; false when the origin is inside a tetrahedron.
bool closest_feature(const Vec3* w, int size, Feature& f, Vec3& closest) {
    switch (size) {
        case 1:
            vertex_feature(f, 0);
            closest = w[0];
            return true;
        case 2:
            closest = closest_segment(w, 0, 1, f);
            return true;
        case 3:
            closest = closest_triangle(w, 0, 1, 2, f);
            return true;
        default:
            return closest_tetrahedron(w, f, closest);
    }
}

// Shrinks `s` to the feature and sets its weights. Vertices move only when they change.
void apply_feature(Simplex& s, const Feature& f) {
    bool same = f.count == s.size;
    for (int k = 0; k < f.count && same; ++k) same = f.index[k] == k;
    if (!same) {
        SimplexVertex kept[4];
        for (int k = 0; k < f.count; ++k) kept[k] = s.vertices[f.index[k]];
        for (int k = 0; k < f.count; ++k) s.vertices[k] = kept[k];
        s.size = f.count;
    }
    for (int k = 0; k < f.count; ++k) s.weights[k] = f.weight[k];
}

}  // namespace

bool closest_point_on_simplex(Simplex& s, Vec3& closest) {
    Vec3 w[4];
    for (int i = 0; i < s.size; ++i) w[i] = s.vertices[i].w;
    Feature f;
    const bool outside = closest_feature(w, s.size, f, closest);
    apply_feature(s, f);
    return outside;
}

namespace {

// A vertex's two feature indices in one word; two vertices with the same word (other than
// kNoFeature, a curved side's) came from the same features.
constexpr std::uint64_t kNoFeature = ~std::uint64_t{0};

std::uint64_t feature_key(const SimplexVertex& x) {
    if (x.index_a < 0 || x.index_b < 0) return kNoFeature;
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x.index_a)) << 32) |
           static_cast<std::uint32_t>(x.index_b);
}

// The end of a GJK run that stopped on a shrunk simplex (`size` points in the slots `order`,
// with `weights`) touching the origin, when the simplex before that shrink (`wide` points in
// the slots `wide_order`) is not flat: the result's points are the shrunk simplex's (the same
// sums as `weighted_points`), its simplex the wide one, which holds the origin on its
// boundary, so that EPA starts from it instead of blowing the shrunk one up again. False
// (nothing written) when the wide simplex is a flat tetrahedron.
bool hand_over_wide(SimplexVertex* slots, const int* order, const double* weights, int size,
                    const int* wide_order, int wide, GjkResult& res) {
    SimplexVertex kept[4];
    Vec3 points[4];
    double kept_weights[4] = {0.0, 0.0, 0.0, 0.0};
    for (int k = 0; k < wide; ++k) {
        kept[k] = slots[wide_order[k]];
        points[k] = kept[k].w;
        for (int j = 0; j < size; ++j)
            if (order[j] == wide_order[k]) kept_weights[k] = weights[j];
    }
    if (wide == 4 && flat_tetrahedron(points)) return false;
    Vec3 pa{}, pb{};
    for (int k = 0; k < size; ++k) {
        pa += slots[order[k]].a * weights[k];
        pb += slots[order[k]].b * weights[k];
    }
    res.point_a = pa;
    res.point_b = pb;
    Simplex& s = res.simplex;
    for (int k = 0; k < wide; ++k) {
        s.vertices[k] = kept[k];
        s.weights[k] = kept_weights[k];
    }
    s.size = wide;
    return true;
}

}  // namespace

// GJK after van den Bergen 2003 (sec. 4.3): v is the closest point of the current simplex to
// the origin, w the support point of a - b in -v. v.v - v.w bounds the squared error; on
// polytopes the loop ends exactly when a support point repeats (a finite number of features).
//
// The simplex's vertices stay in the slots of the result's simplex they were stored in,
// listed in the simplex's order by `order`, and its Minkowski points are kept in that order
// beside them: a shrinking simplex moves four indices and points, not its vertices (80 bytes
// each), which are put in order once, at the end. The arithmetic sees the same points in the
// same order as with the vertices moved.
GjkResult gjk_run(MinkowskiDifference& md, const GjkOptions& opt, const SimplexVertex* first) {
    GjkResult res;
    const double touch = opt.contact_tolerance * md.scale;
    const double touch2 = touch * touch;
    // On the cores of swept shapes, separation needs a gap wider than the two radii.
    const double separation_gap =
        touch + (opt.with_margins && !md.with_margins ? margin(*md.a) + margin(*md.b) : 0.0);
    SimplexVertex* slots = res.simplex.vertices;
    int order[4] = {0, 1, 2, 3};
    Vec3 points[4];
    double weights[4] = {1.0, 0.0, 0.0, 0.0};
    // Each vertex's two feature indices in one word (kNoFeature when either is curved), in
    // the simplex's order: a repeated support point is one equal word.
    std::uint64_t features[4] = {kNoFeature, kNoFeature, kNoFeature, kNoFeature};
    int size = 1;
    // Start from the support in the direction of b's centre as seen from a: a good first guess.
    Vec3 dir = md.translation_b;
    if (!(squared_norm(dir) > 0.0)) dir = Vec3{1.0, 0.0, 0.0};
    slots[0] = first != nullptr ? *first : md.support(dir);
    points[0] = slots[0].w;
    features[0] = feature_key(slots[0]);
    Vec3 v = points[0];
    double vv = squared_norm(v);
    res.status = Status::MAX_ITERATIONS;
    int it = 0;
    bool inside = false;
    // The simplex of the last step before its shrink (`wide` points in the slots
    // `wide_order`), for EPA when the shrunk one touches the origin: it holds the origin on
    // its boundary, and EPA then skips the blow-up of a point, segment or triangle (up to 16
    // supports).
    int wide = 0;
    int wide_order[4] = {0, 1, 2, 3};
    // The direction of the last support (minus v before the step) and its dot with that
    // support, for `contact_direction`: checked once, at the end.
    Vec3 last_v = -dir;
    double last_vw = -dot(dir, points[0]);
    while (it < opt.max_iterations) {
        ++it;
        if (vv <= touch2) {
            res.status = Status::CONVERGED;
            inside = true;
            break;
        }
        // The slot no vertex of the simplex holds (size < 4 here): the lowest clear bit of the
        // slots in use, by masks and a table (the size and the slots change at random from
        // one step to the next, and branches on them mispredict).
        static constexpr int kFirstFree[8] = {0, 1, 0, 2, 0, 1, 0, 3};
        const unsigned used = (1u << order[0]) | (static_cast<unsigned>(size > 1) << order[1]) |
                              (static_cast<unsigned>(size > 2) << order[2]);
        const int slot = kFirstFree[used & 7u];
        SimplexVertex& w = slots[slot];
        w = md.support(-v);
        const std::uint64_t key = feature_key(w);
        bool repeated = false;
        if (key != kNoFeature)
            // Four trips with the size as a mask: no loop exit to mispredict.
            for (int i = 0; i < 4; ++i) repeated |= (features[i] == key) & (i < size);
        const double vw = dot(v, w.w);
        if (opt.stop_when_separated && vw > separation_gap * std::sqrt(vv)) {
            // A separating plane with a positive gap: no contact (lower bound > tolerance).
            res.status = Status::CONVERGED;
            break;
        }
        if (repeated || vv - vw <= opt.relative_tolerance * vv) {
            res.status = Status::CONVERGED;
            break;
        }
        order[size] = slot;
        points[size] = w.w;
        features[size] = key;
        ++size;
        Feature feature;
        Vec3 nv;
        if (!closest_feature(points, size, feature, nv)) {
            // Inside: the feature is the whole tetrahedron, in its order.
            for (int k = 0; k < 4; ++k) weights[k] = feature.weight[k];
            last_v = v;
            last_vw = vw;
            inside = true;
            res.status = Status::CONVERGED;
            v = Vec3{};
            vv = 0.0;
            break;
        }
        const double nvv = squared_norm(nv);
        if (!(nvv < vv)) {
            // No progress in floating point: v is as close as rounding allows.
            --size;
            res.status = Status::CONVERGED;
            break;
        }
        wide = size;
        for (int k = 0; k < 4; ++k) wide_order[k] = order[k];
        // All four entries (a feature's unused indices are valid ones): fixed trips, no calls.
        int kept_order[4];
        Vec3 kept_points[4];
        std::uint64_t kept_features[4];
        for (int k = 0; k < 4; ++k) {
            kept_order[k] = order[feature.index[k]];
            kept_points[k] = points[feature.index[k]];
            kept_features[k] = features[feature.index[k]];
        }
        for (int k = 0; k < 4; ++k) {
            order[k] = kept_order[k];
            points[k] = kept_points[k];
            features[k] = kept_features[k];
            weights[k] = feature.weight[k];
        }
        size = feature.count;
        last_v = v;
        last_vw = vw;
        v = nv;
        vv = nvv;
    }
    Simplex& s = res.simplex;
    res.iterations = it;
    res.overlap = inside || vv <= touch2;
    // The last support within the contact distance of the origin along its direction d = -v:
    // |h| <= touch for h = d.w / |d| (the overlap along d), by squares. Then d is a contact
    // normal of an overlapping pair (a vertex of a - b at the origin, as a rule).
    if (res.overlap && last_vw * last_vw <= touch2 * squared_norm(last_v)) {
        res.contact_direction = -last_v;
        res.contact_support = -last_vw;
    }
    if (inside && wide > size && hand_over_wide(slots, order, weights, size, wide_order, wide, res)) {
        // Done: the points are the shrunk simplex's, the simplex the wide one.
    } else {
        bool in_order = true;
        for (int k = 0; k < size; ++k) in_order = in_order && order[k] == k;
        if (!in_order) {
            SimplexVertex kept[4];
            for (int k = 0; k < size; ++k) kept[k] = slots[order[k]];
            for (int k = 0; k < size; ++k) slots[k] = kept[k];
        }
        s.size = size;
        for (int k = 0; k < size; ++k) s.weights[k] = weights[k];
        weighted_points(s, res.point_a, res.point_b);
    }
    if (!res.overlap) {
        // v is the accurate answer; the barycentric weights behind the witness points are not
        // when the simplex is nearly degenerate (parallel edges, a curved side against an
        // edge), and the points could then stand farther apart than the distance. b's point
        // is taken at a's point minus v, so that the two are exactly the distance apart.
        res.point_b = res.point_a - v;
    }
    if (res.overlap) {
        res.distance = 0.0;
        res.normal = Vec3{};
    } else {
        const double d = std::sqrt(vv);
        res.distance = d;
        res.normal = v * (-1.0 / d);
    }
    return res;
}

GjkResult gjk_distance(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, const GjkOptions& opt) {
    MinkowskiDifference md(a, pose_a, b, pose_b, false);
    GjkOptions core_opt = opt;
    GjkResult res = gjk_run(md, core_opt);
    const double ma = opt.with_margins ? margin(a) : 0.0;
    const double mb = opt.with_margins ? margin(b) : 0.0;
    if (!res.overlap && (ma > 0.0 || mb > 0.0)) {
        // Swept-sphere shapes: subtract the radii from the exact core distance.
        const double d = res.distance - ma - mb;
        const double touch = opt.contact_tolerance * md.scale;
        res.point_a += res.normal * ma;
        res.point_b -= res.normal * mb;
        if (d > touch) {
            res.distance = d;
        } else {
            res.distance = 0.0;
            res.overlap = true;
        }
    } else if (res.overlap && (ma > 0.0 || mb > 0.0)) {
        res.normal = Vec3{};
    }
    res.point_a = pose_a.apply(res.point_a);
    res.point_b = pose_a.apply(res.point_b);
    res.normal = pose_a.rotate(res.normal);
    if (res.overlap) res.normal = Vec3{};
    return res;
}

}  // namespace meshcol
