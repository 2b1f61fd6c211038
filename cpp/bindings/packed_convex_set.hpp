#pragma once
// A packed convex set as the bindings see it: the arrays of a Python
// meshcol.collision.shapes.ConvexSet, checked once when the set is made, and the view the core reads. Shared by every binding
// that takes convex shapes (narrow phase, time of impact). Bindings only: no nanobind code
// outside cpp/bindings/.
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>

#include <atomic>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/narrowphase.hpp"
#include "ndarray.hpp"

namespace meshcol::bindings {

/// The bytes of a `ClimbList` (its count, then its slots): a row of a set's (M, 16) uint8
/// `climb_lists` array.
constexpr size_t kClimbRowBytes = sizeof(ClimbList);
static_assert(sizeof(ClimbIndex) == 1, "a row's elements are its bytes");
using ClimbRecords = In<ClimbIndex, -1, static_cast<ssize_t>(kClimbRowBytes)>;

/// What `pack_polytopes` made: references to its index arrays (the adjacency, its offsets and
/// the edge pairs, which stay alive and at their addresses while this lives) and copies of
/// its per-shape vertex and edge offsets. A PackedConvexSet handed these very arrays, with
/// its polytopes laid out as the packing laid them out, need not read every index again to
/// know they are in range: the packing wrote them in range (hull_packing.cpp). Any other
/// array, or layout, is checked as usual.
struct PackSeal {
    nb::object adjacency_offsets, adjacency, edge_pairs;  // the arrays, held
    const std::int64_t* adjacency_offsets_data = nullptr;
    const std::int32_t* adjacency_data = nullptr;
    const std::int32_t* edge_pairs_data = nullptr;
    std::int64_t vertex_count = 0, adjacency_count = 0, edge_count = 0;
    std::vector<std::int64_t> offsets, edge_pair_offsets;  // per packed shape, H + 1 each
    nb::object climb_lists;  // the climb lists, held, and their offsets' copy (H + 1)
    const ClimbIndex* climb_lists_data = nullptr;
    std::int64_t climb_list_count = 0;
    std::vector<std::int64_t> climb_list_offsets;

    /// Whether the set's climb lists are the sealed ones, its polytopes (kind 0, in order)
    /// owning exactly the packed shapes' lists and every other shape none (`clo` checked).
    bool vouches_for_climb_lists(std::int64_t h, const std::int8_t* kinds, const std::int64_t* clo,
                                 const ClimbRecords& lists) const {
        if (lists.data() != climb_lists_data ||
            static_cast<std::int64_t>(lists.shape(0)) != climb_list_count ||
            climb_list_offsets.size() != offsets.size())
            return false;
        const size_t packed = climb_list_offsets.size() - 1;
        size_t k = 0;
        for (std::int64_t s = 0; s < h; ++s) {
            if (kinds[s] == 0) {
                if (k == packed || clo[s] != climb_list_offsets[k] ||
                    clo[s + 1] != climb_list_offsets[k + 1])
                    return false;
                ++k;
            } else if (clo[s + 1] != clo[s]) {
                return false;
            }
        }
        return k == packed;
    }

    /// Whether the set's arrays are the sealed ones and its polytopes (kind 0, in order) own
    /// exactly the packed shapes' vertices and edges, every other shape none; `offsets` and
    /// `eo` already checked (non-decreasing, from 0 to their totals).
    bool vouches(std::int64_t h, const std::int8_t* kinds, const std::int64_t* o,
                 std::int64_t v, const Index64& ao, const Index32& adj, const std::int64_t* eo,
                 const Pairs32& edges) const {
        if (ao.data() != adjacency_offsets_data ||
            static_cast<std::int64_t>(ao.shape(0)) != vertex_count + 1 ||
            adj.data() != adjacency_data ||
            static_cast<std::int64_t>(adj.shape(0)) != adjacency_count ||
            edges.data() != edge_pairs_data ||
            static_cast<std::int64_t>(edges.shape(0)) != edge_count || v != vertex_count)
            return false;
        const size_t packed = offsets.size() - 1;
        size_t k = 0;
        for (std::int64_t s = 0; s < h; ++s) {
            if (kinds[s] == 0) {
                if (k == packed || o[s] != offsets[k] || o[s + 1] != offsets[k + 1] ||
                    eo[s] != edge_pair_offsets[k] || eo[s + 1] != edge_pair_offsets[k + 1])
                    return false;
                ++k;
            } else if (o[s + 1] != o[s] || eo[s + 1] != eo[s]) {
                return false;
            }
        }
        return k == packed;
    }
};

/// Owns (references to) the arrays of a Python ConvexSet and the view over them.
class PackedConvexSet {
  public:
    PackedConvexSet(Points vertices, Index64 offsets, Kinds kinds, Params params,
                    std::optional<Index64> adjacency_offsets, std::optional<Index32> adjacency,
                    std::optional<Index64> face_offsets, std::optional<Points> face_normals,
                    std::optional<Index64> edge_pair_offsets, std::optional<Pairs32> edge_pairs,
                    const PackSeal* seal = nullptr,
                    std::optional<Index64> climb_list_offsets = std::nullopt,
                    std::optional<ClimbRecords> climb_lists = std::nullopt)
        : vertices_(vertices), offsets_(offsets), kinds_(kinds), params_(params),
          adjacency_offsets_(adjacency_offsets), adjacency_(adjacency),
          face_offsets_(face_offsets), face_normals_(face_normals),
          edge_pair_offsets_(edge_pair_offsets), edge_pairs_(edge_pairs),
          climb_list_offsets_(climb_list_offsets), climb_lists_(climb_lists),
          radii_(static_cast<std::int64_t>(kinds.shape(0))),
          edge_classes_(static_cast<std::int64_t>(kinds.shape(0))) {
        const std::int64_t v = static_cast<std::int64_t>(vertices.shape(0));
        const std::int64_t h = static_cast<std::int64_t>(kinds.shape(0));
        if (static_cast<std::int64_t>(offsets.shape(0)) != h + 1)
            throw std::invalid_argument("offsets must be (H + 1,) with H = len(kinds)");
        if (static_cast<std::int64_t>(params.shape(0)) != h)
            throw std::invalid_argument("params must be (H, 4) with H = len(kinds)");
        check_offsets(offsets.data(), offsets.shape(0), v, "offsets");
        for (std::int64_t i = 0; i < h; ++i)
            if (kinds.data()[i] < 0 || kinds.data()[i] > static_cast<std::int8_t>(ShapeKind::HALFSPACE))
                throw std::invalid_argument("kinds must be in 0..6, got " +
                                            std::to_string(int(kinds.data()[i])));
        view_.vertices = vertices.data();
        view_.vertex_count = v;
        view_.offsets = offsets.data();
        view_.shape_count = h;
        view_.kinds = kinds.data();
        view_.params = params.data();
        if (adjacency_offsets.has_value() != adjacency.has_value())
            throw std::invalid_argument("adjacency_offsets and adjacency go together");
        if (adjacency_offsets) {
            const std::int64_t k = static_cast<std::int64_t>(adjacency->shape(0));
            if (static_cast<std::int64_t>(adjacency_offsets->shape(0)) != v + 1)
                throw std::invalid_argument("adjacency_offsets must be (V + 1,)");
            // The packing's own arrays in its own layout (a ConvexSet built from points) are in
            // range by construction: reading their indices again cost a 40,000-hull set 28-34 ms
            // of CPU, about 3% of its build's.
            sealed_ = seal != nullptr && edge_pair_offsets && edge_pairs &&
                      static_cast<std::int64_t>(edge_pair_offsets->shape(0)) == h + 1 &&
                      seal->vouches(h, kinds.data(), offsets.data(), v, *adjacency_offsets,
                                    *adjacency, edge_pair_offsets->data(), *edge_pairs);
            if (!sealed_) {
                check_offsets(adjacency_offsets->data(), adjacency_offsets->shape(0), k,
                              "adjacency_offsets");
                // Every neighbour must be a vertex of the same shape.
                const std::int64_t* o = offsets.data();
                const std::int64_t* ao = adjacency_offsets->data();
                const bool in_range =
                    indices_in_shapes(h, o, adjacency->data(), [&](std::int64_t s) {
                        return std::pair{ao[o[s]], ao[o[s + 1]]};
                    });
                if (!in_range)
                    throw std::invalid_argument("adjacency holds an index out of range");
            }
            view_.adjacency_offsets = adjacency_offsets->data();
            view_.adjacency = adjacency->data();
        }
        const bool any_features = face_offsets || face_normals || edge_pair_offsets || edge_pairs;
        if (any_features) {
            if (!(face_offsets && face_normals && edge_pair_offsets && edge_pairs))
                throw std::invalid_argument(
                    "face_offsets, face_normals, edge_pair_offsets and edge_pairs go together");
            if (static_cast<std::int64_t>(face_offsets->shape(0)) != h + 1 ||
                static_cast<std::int64_t>(edge_pair_offsets->shape(0)) != h + 1)
                throw std::invalid_argument("face_offsets and edge_pair_offsets must be (H + 1,)");
            check_offsets(face_offsets->data(), face_offsets->shape(0),
                          static_cast<std::int64_t>(face_normals->shape(0)), "face_offsets");
            check_offsets(edge_pair_offsets->data(), edge_pair_offsets->shape(0),
                          static_cast<std::int64_t>(edge_pairs->shape(0)), "edge_pair_offsets");
            // Every edge must join two vertices of its own shape (the classes read them).
            const std::int64_t* eo = edge_pair_offsets->data();
            const bool in_range =
                sealed_ ||
                indices_in_shapes(h, offsets.data(), edge_pairs->data(), [&](std::int64_t s) {
                    return std::pair{2 * eo[s], 2 * eo[s + 1]};
                });
            if (!in_range) throw std::invalid_argument("edge_pairs holds an index out of range");
            view_.face_offsets = face_offsets->data();
            view_.face_normals = face_normals->data();
            view_.edge_pair_offsets = edge_pair_offsets->data();
            view_.edge_pairs = edge_pairs->data();
            view_.edge_classes = &edge_classes_;
        }
        attach_climb_lists(seal);
    }

    std::int64_t size() const { return view_.shape_count; }
    /// Whether a PackSeal vouched for the index arrays (their ranges were not read again).
    bool sealed() const { return sealed_; }
    const ConvexSetView& view() const { return view_; }
    /// The shapes' checked radii, kept from the first batch that uses each shape for the
    /// batches after it (the Python ConvexSet makes or copies its arrays and holds them
    /// read-only, so the shapes never change).
    ShapeRadii& radii() const { return radii_; }

    /// The pose data, after checking there is one (4, 4) pose per shape (null: identity).
    const double* check_poses(const std::optional<Poses>& poses) const {
        if (!poses) return nullptr;
        if (static_cast<std::int64_t>(poses->shape(0)) != view_.shape_count)
            throw std::invalid_argument("poses must be (" +
                                        std::to_string(view_.shape_count) + ", 4, 4), got (" +
                                        std::to_string(poses->shape(0)) + ", 4, 4)");
        return poses->data();
    }

    /// Throws unless every index of the `count` (i, j) pairs names a shape of the set.
    void check_pairs(const std::int64_t* idx, long long count) const {
        for (long long i = 0; i < 2 * count; ++i)
            if (idx[i] < 0 || idx[i] >= view_.shape_count)
                throw std::invalid_argument("pairs: index " + std::to_string(idx[i]) +
                                            " out of range for " +
                                            std::to_string(view_.shape_count) + " shapes");
    }

  private:
    /// The climbs' fixed-stride lists (shapes.hpp: `ClimbList`) into the view: the arrays
    /// handed over (`climb_list_offsets`, `climb_lists`: what the packing wrote with the
    /// adjacency, or a `take` or concatenation of such), their ranges checked unless the seal
    /// vouches for them. Without them (a set made from a caller's arrays) the shapes climb on
    /// the CSR arrays: making the lists here cost more than the copy and checks of the set
    /// (40,000 hulls of 64 points: 144-150 ms of CPU against 65-69 ms), and the sets the
    /// pipeline makes from its own arrays (triangle parts) have no shape that climbs.
    void attach_climb_lists(const PackSeal* seal) {
        if (climb_list_offsets_.has_value() != climb_lists_.has_value())
            throw std::invalid_argument("climb_list_offsets and climb_lists go together");
        if (!climb_lists_) return;
        if (view_.adjacency == nullptr)
            throw std::invalid_argument("climb lists need the adjacency");
        const std::int64_t h = view_.shape_count;
        const std::int64_t m = static_cast<std::int64_t>(climb_lists_->shape(0));
        if (static_cast<std::int64_t>(climb_list_offsets_->shape(0)) != h + 1)
            throw std::invalid_argument("climb_list_offsets must be (H + 1,)");
        check_offsets(climb_list_offsets_->data(), climb_list_offsets_->shape(0), m,
                      "climb_list_offsets");
        if (m == 0) return;  // no shape has lists: every one climbs on the CSR arrays
        if (reinterpret_cast<std::uintptr_t>(climb_lists_->data()) % alignof(ClimbList) != 0)
            throw std::invalid_argument("climb_lists must be 16-byte aligned");
        const std::int64_t* o = view_.offsets;
        const std::int64_t* clo = climb_list_offsets_->data();
        const auto* lists = reinterpret_cast<const ClimbList*>(climb_lists_->data());
        const bool sealed = sealed_ && seal->vouches_for_climb_lists(h, view_.kinds, clo,
                                                                    *climb_lists_);
        if (!sealed) {
            // A shape has a list a vertex or none, of its width (`climb_rows` rows: 8-bit
            // entries up to kNarrowClimbVertices vertices, 16-bit above); every list's count
            // fits its slots and names vertices of its shape.
            constexpr long long kShapesPerThread = 4096;
            std::atomic<bool> all{true};
            parallel_for(h, resolve_threads(0, h, kShapesPerThread), [&](long long b, long long e) {
                bool ok = true;
                for (long long s = b; s < e && ok; ++s) {
                    const std::int64_t count = clo[s + 1] - clo[s], n = o[s + 1] - o[s];
                    if (count == 0) continue;
                    ok = n <= 0x10000 && count == n * climb_rows(n);
                    const ClimbList* first = lists + clo[s];
                    if (ok && climb_rows(n) == 1)
                        ok = lists_in_range(first, n);
                    else if (ok)
                        ok = lists_in_range(reinterpret_cast<const WideClimbList*>(first), n);
                }
                if (!ok) all = false;
            });
            if (!all) throw std::invalid_argument("climb_lists hold a list out of range");
        }
        view_.climb_list_offsets = clo;
        view_.climb_lists = lists;
    }

    /// Whether the `n` records at `list` each hold at most kClimbListSlots entries, every one
    /// below `n`.
    template <class Record>
    static bool lists_in_range(const Record* list, std::int64_t n) {
        std::uint32_t bad = 0;
        for (std::int64_t i = 0; i < n; ++i) {
            bad |= list[i].count > kClimbListSlots;
            for (int k = 0; k < kClimbListSlots; ++k)
                bad |= (k < list[i].count) & (list[i].neighbours[k] >= n);
        }
        return bad == 0;
    }

    /// Whether every shape s < h indexes only its own vertices: index[j] in [0, its vertex
    /// count) (offsets o) for j in [first, last) = range(s). On all cores for a large set: the
    /// checks of the adjacency and the edges read every index once (about 21 ms of CPU for
    /// 40,000 hulls of 64 points: sets made from arrays; a set made from points has its
    /// packing's PackSeal instead).
    template <class Range>
    static bool indices_in_shapes(std::int64_t h, const std::int64_t* o,
                                  const std::int32_t* index, const Range& range) {
        constexpr long long kShapesPerThread = 4096;
        std::atomic<bool> all{true};
        parallel_for(h, resolve_threads(0, h, kShapesPerThread), [&](long long b, long long e) {
            bool ok = true;
            for (long long s = b; s < e; ++s) {
                // One unsigned compare an index (a negative one wraps above any count): the
                // loop then runs in vector lanes, a third faster than two signed compares.
                const std::int64_t n = o[s + 1] - o[s];
                const std::uint32_t limit =
                    n > INT32_MAX ? std::uint32_t{0xffffffffu} : static_cast<std::uint32_t>(n);
                const auto [first, last] = range(s);
                std::uint32_t bad = 0;
                for (std::int64_t j = first; j < last; ++j)
                    bad |= static_cast<std::uint32_t>(index[j]) >= limit;
                ok &= bad == 0;
            }
            if (!ok) all = false;
        });
        return all;
    }

    Points vertices_;
    Index64 offsets_;
    Kinds kinds_;
    Params params_;
    std::optional<Index64> adjacency_offsets_;
    std::optional<Index32> adjacency_;
    std::optional<Index64> face_offsets_;
    std::optional<Points> face_normals_;
    std::optional<Index64> edge_pair_offsets_;
    std::optional<Pairs32> edge_pairs_;
    std::optional<Index64> climb_list_offsets_;
    std::optional<ClimbRecords> climb_lists_;
    bool sealed_ = false;
    mutable ShapeRadii radii_;
    mutable EdgeClasses edge_classes_;  // the view's cache: its pointer, set once
    ConvexSetView view_;
};

}  // namespace meshcol::bindings
