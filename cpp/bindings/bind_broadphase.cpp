// Binds broadphase.hpp: sort_and_sweep, SortAndSweep, AabbTree. Arrays in, arrays out; the
// Python wrappers in meshcol/collision/broadphase.py check shapes first with friendly messages.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "meshcol/broadphase.hpp"
#include "meshcol/defaults.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using Boxes = Points;
using Ids = Index64;
using PairsOut = Out<std::int64_t, -1, 2>;

PairsOut pairs_array(std::vector<std::int64_t>&& flat) {
    const size_t k = flat.size() / 2;
    return vector_array<PairsOut>(std::move(flat), k, 2);
}

/// A read-only (k, 2) view of pairs the sweep keeps sharing; the capsule holds a reference.
nb::ndarray<nb::numpy, const std::int64_t, nb::shape<-1, 2>, nb::c_contig> shared_pairs_array(
    std::shared_ptr<const std::vector<std::int64_t>> pairs) {
    static const std::int64_t empty = 0;
    auto* holder = new std::shared_ptr<const std::vector<std::int64_t>>(std::move(pairs));
    nb::capsule owner(holder, [](void* p) noexcept {
        delete static_cast<std::shared_ptr<const std::vector<std::int64_t>>*>(p);
    });
    const std::vector<std::int64_t>& flat = **holder;
    const size_t shape[2] = {flat.size() / 2, 2};
    return nb::ndarray<nb::numpy, const std::int64_t, nb::shape<-1, 2>, nb::c_contig>(flat.empty() ? &empty : flat.data(), 2, shape, owner);
}

PairsOut keys_array(const std::vector<std::uint64_t>& keys) {
    std::vector<std::int64_t> flat(2 * keys.size());
    for (size_t k = 0; k < keys.size(); ++k) {
        flat[2 * k] = static_cast<std::int64_t>(keys[k] >> 32);
        flat[2 * k + 1] = static_cast<std::int64_t>(keys[k] & 0xFFFFFFFFu);
    }
    return pairs_array(std::move(flat));
}

std::int64_t box_count(const Boxes& lo, const Boxes& hi) {
    if (lo.shape(0) != hi.shape(0))
        throw std::invalid_argument("aabb_max must be (" + std::to_string(lo.shape(0)) +
                                    ", 3) like aabb_min, got (" + std::to_string(hi.shape(0)) + ", 3)");
    return static_cast<std::int64_t>(lo.shape(0));
}

meshcol::Aabb box_at(const Boxes& lo, const Boxes& hi, std::int64_t i) {
    const double* a = lo.data() + 3 * i;
    const double* b = hi.data() + 3 * i;
    return {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}};
}

/// Checks that every id is live in `tree` and appears once.
void check_ids(const meshcol::AabbTree& tree, const Ids& ids) {
    std::vector<std::int64_t> seen(ids.data(), ids.data() + ids.shape(0));
    for (const std::int64_t id : seen)
        if (!tree.contains(id)) throw std::invalid_argument("ids: " + std::to_string(id) + " is not in the tree");
    std::sort(seen.begin(), seen.end());
    const auto dup = std::adjacent_find(seen.begin(), seen.end());
    if (dup != seen.end()) throw std::invalid_argument("ids: " + std::to_string(*dup) + " appears twice");
}

}  // namespace

void bind_broadphase(nb::module_& m) {
    m.def(
        "sort_and_sweep",
        [](const Boxes& lo, const Boxes& hi, int axis, int threads, std::optional<Ids> groups,
           std::int64_t max_pairs) -> std::optional<PairsOut> {
            const std::int64_t n = box_count(lo, hi);
            if (groups && static_cast<std::int64_t>(groups->shape(0)) != n)
                throw std::invalid_argument("groups must be (" + std::to_string(n) + ",), got (" +
                                            std::to_string(groups->shape(0)) + ",)");
            const std::int64_t* group_ids = groups ? groups->data() : nullptr;
            std::vector<std::int64_t> flat;
            bool exceeded = false;
            {
                nb::gil_scoped_release release;
                flat = meshcol::sort_and_sweep(lo.data(), hi.data(), n, axis, threads, group_ids,
                                               max_pairs, &exceeded);
            }
            if (exceeded) return std::nullopt;
            return pairs_array(std::move(flat));
        },
        "aabb_min"_a, "aabb_max"_a, "axis"_a = -1, "threads"_a = 0, "groups"_a = nb::none(),
        "max_pairs"_a = -1,
        "Overlapping pairs (K, 2) int64, i < j, sorted; axis -1 chooses by variance; boxes of "
        "one group (groups: (N,) int64) never pair; None when there are more than max_pairs "
        "(>= 0) pairs, found without holding them all.");
    m.def("choose_sweep_axis", [](const Boxes& lo, const Boxes& hi) {
        const std::int64_t n = box_count(lo, hi);
        meshcol::validate_boxes(lo.data(), hi.data(), n);
        return meshcol::choose_sweep_axis(lo.data(), hi.data(), n);
    }, "aabb_min"_a, "aabb_max"_a, "The axis of largest variance of the box centres.");

    nb::class_<meshcol::SortAndSweep>(m, "SortAndSweep", "Incremental sort and sweep.")
        .def("__init__",
             [](meshcol::SortAndSweep* self, const Boxes& lo, const Boxes& hi, int axis, int threads) {
                 const std::int64_t n = box_count(lo, hi);
                 nb::gil_scoped_release release;
                 new (self) meshcol::SortAndSweep(lo.data(), hi.data(), n, axis, threads);
             },
             "aabb_min"_a, "aabb_max"_a, "axis"_a = -1, "threads"_a = 0)
        .def("pairs", [](const meshcol::SortAndSweep& s) { return shared_pairs_array(s.shared_pairs()); })
        .def("update",
             [](meshcol::SortAndSweep& s, const Boxes& lo, const Boxes& hi) {
                 const std::int64_t n = box_count(lo, hi);
                 {
                     nb::gil_scoped_release release;
                     s.update(lo.data(), hi.data(), n);
                 }
                 return shared_pairs_array(s.shared_pairs());
             },
             "aabb_min"_a, "aabb_max"_a)
        .def_prop_ro("axis", &meshcol::SortAndSweep::axis)
        .def_prop_ro("last_shifts", &meshcol::SortAndSweep::last_shifts)
        .def("__len__", &meshcol::SortAndSweep::size);

    using Tree = meshcol::AabbTree;
    nb::class_<Tree>(m, "AabbTree", "Dynamic AABB tree (Box2D v3 style).")
        .def(nb::init<double>(), "margin"_a = 0.0)
        .def("insert",
             [](Tree& t, const Boxes& lo, const Boxes& hi) {
                 const std::int64_t n = box_count(lo, hi);
                 std::vector<std::int64_t> ids(static_cast<size_t>(n));
                 {
                     nb::gil_scoped_release release;
                     meshcol::validate_boxes(lo.data(), hi.data(), n);
                     if (t.size() + n > meshcol::defaults::tree_max_objects)
                         throw std::invalid_argument("AabbTree holds at most " +
                                                     std::to_string(meshcol::defaults::tree_max_objects) + " boxes");
                     for (std::int64_t i = 0; i < n; ++i) ids[i] = t.insert(box_at(lo, hi, i));
                 }
                 return vector_array<Out<std::int64_t, -1>>(std::move(ids), static_cast<size_t>(n), 0);
             },
             "aabb_min"_a, "aabb_max"_a)
        .def("remove",
             [](Tree& t, const Ids& ids) {
                 check_ids(t, ids);
                 nb::gil_scoped_release release;
                 for (size_t i = 0; i < ids.shape(0); ++i) t.remove(static_cast<std::int32_t>(ids.data()[i]));
             },
             "ids"_a)
        .def("move",
             [](Tree& t, const Ids& ids, const Boxes& lo, const Boxes& hi) {
                 const std::int64_t n = box_count(lo, hi);
                 if (static_cast<std::int64_t>(ids.shape(0)) != n)
                     throw std::invalid_argument("aabb_min must be (" + std::to_string(ids.shape(0)) +
                                                 ", 3) like ids, got (" + std::to_string(n) + ", 3)");
                 check_ids(t, ids);
                 auto* moved = new std::vector<std::uint8_t>(static_cast<size_t>(std::max<std::int64_t>(n, 1)));
                 nb::capsule owner(moved, [](void* p) noexcept { delete static_cast<std::vector<std::uint8_t>*>(p); });
                 {
                     nb::gil_scoped_release release;
                     meshcol::validate_boxes(lo.data(), hi.data(), n);
                     for (std::int64_t i = 0; i < n; ++i)
                         (*moved)[i] = t.move(static_cast<std::int32_t>(ids.data()[i]), box_at(lo, hi, i));
                 }
                 const size_t shape[1] = {static_cast<size_t>(n)};
                 return Out<bool, -1>(reinterpret_cast<bool*>(moved->data()), 1, shape, owner);
             },
             "ids"_a, "aabb_min"_a, "aabb_max"_a)
        .def("clear", &Tree::clear)
        .def("build",
             [](Tree& t, const Boxes& lo, const Boxes& hi, int threads) {
                 const std::int64_t n = box_count(lo, hi);
                 nb::gil_scoped_release release;
                 meshcol::validate_boxes(lo.data(), hi.data(), n);
                 t.build(lo.data(), hi.data(), n, threads);
             },
             "aabb_min"_a, "aabb_max"_a, "threads"_a = 0)
        .def("rebuild",
             [](Tree& t, int threads) {
                 nb::gil_scoped_release release;
                 t.rebuild(threads);
             },
             "threads"_a = 0)
        .def("query",
             [](const Tree& t, const Point& lo, const Point& hi) {
                 const meshcol::Aabb box{{lo(0), lo(1), lo(2)}, {hi(0), hi(1), hi(2)}};
                 meshcol::validate_boxes(lo.data(), hi.data(), 1);
                 std::vector<std::int64_t> ids = t.query(box);
                 const size_t k = ids.size();
                 return vector_array<Out<std::int64_t, -1>>(std::move(ids), k, 0);
             },
             "aabb_min"_a, "aabb_max"_a)
        .def("query_pairs",
             [](const Tree& t, int threads) {
                 std::vector<std::uint64_t> keys;
                 {
                     nb::gil_scoped_release release;
                     keys = t.query_pairs(threads);
                 }
                 return keys_array(keys);
             },
             "threads"_a = 0)
        .def("query_pairs_with",
             [](const Tree& t, const Tree& other, int threads) {
                 std::vector<std::uint64_t> keys;
                 {
                     nb::gil_scoped_release release;
                     keys = t.query_pairs(other, threads);
                 }
                 return keys_array(keys);
             },
             "other"_a, "threads"_a = 0)
        .def("ray_cast",
             [](const Tree& t, const Point& origin, const Point& direction, double max_fraction) {
                 const meshcol::Vec3 o{origin(0), origin(1), origin(2)}, d{direction(0), direction(1), direction(2)};
                 if (!meshcol::is_finite(o)) throw std::invalid_argument("origin is not finite");
                 if (!meshcol::is_finite(d)) throw std::invalid_argument("direction is not finite");
                 if (!std::isfinite(max_fraction) || max_fraction < 0.0)
                     throw std::invalid_argument("max_fraction must be finite and >= 0, got " + std::to_string(max_fraction));
                 std::vector<std::int64_t> ids;
                 std::vector<double> fractions;
                 t.ray_cast(o, d, max_fraction, ids, fractions);
                 const size_t k = ids.size();
                 return std::make_pair(vector_array<Out<std::int64_t, -1>>(std::move(ids), k, 0),
                                       vector_array<Out<double, -1>>(std::move(fractions), k, 0));
             },
             "origin"_a, "direction"_a, "max_fraction"_a = 1.0)
        .def("validate", &Tree::validate)
        .def_prop_ro("height", &Tree::height)
        .def_prop_ro("margin", &Tree::margin)
        .def_prop_ro("area_ratio", &Tree::area_ratio)
        .def("__len__", &Tree::size);
}
