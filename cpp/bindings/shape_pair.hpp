#pragma once
// Two shapes (meshcol.types Sphere, Box, Capsule, Cylinder, Ellipsoid, or (n, 3) float64
// points whose hull is taken) as the two-shape set ConvexSet.from_shapes packs for a
// single-pair query, read from the Python objects and packed without a Python array: the
// single-pair calls (distance, time_of_impact, ...) then cost about their query (and the
// hulls they build).
// Bindings only: no nanobind code outside cpp/bindings/.
#include <nanobind/nanobind.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <optional>
#include <string>
#include <vector>

#include "meshcol/hull.hpp"
#include "meshcol/narrowphase.hpp"
#include "call_args.hpp"
#include "ndarray.hpp"

namespace meshcol::bindings {

/// Shapes 0 (a) and 1 (b) of a pair, packed as `ConvexSet.from_shapes` packs them: a
/// primitive as its kind and params, owning no rows; points as their hull by the core's
/// `pack_polytopes` (the packing `pack_hulls` makes), with its adjacency and SAT features;
/// and the view the core reads.
class ShapePair {
  public:
    /// Reads shape `k` (0, then 1) of ShapeKind `kind`: a primitive (1..5) as
    /// `meshcol.collision.shapes._primitive` reads it (a box's half sizes, a capsule's and a
    /// cylinder's half length), or (0) an (n, 3) float64 C-contiguous array of points
    /// (copied). False when a field or the array is in another form (the caller declines and
    /// the Python path packs it).
    bool read(int k, int kind, PyObject* shape) {
        double* p = params_.data() + 4 * k;
        std::fill(p, p + 4, 0.0);
        kinds_[static_cast<size_t>(k)] = static_cast<std::int8_t>(kind);
        static PyObject* const radius = interned("radius");
        static PyObject* const length = interned("length");
        static PyObject* const size = interned("size");
        static PyObject* const semi_axes = interned("semi_axes");
        switch (static_cast<ShapeKind>(kind)) {
            case ShapeKind::POLYTOPE: return read_points(shape);
            case ShapeKind::SPHERE: return float_attr(shape, radius, &p[0]);
            case ShapeKind::BOX: return float_triple(shape, size, 0.5, p);
            case ShapeKind::ELLIPSOID: return float_triple(shape, semi_axes, 1.0, p);
            case ShapeKind::CAPSULE:
            case ShapeKind::CYLINDER:
                if (!float_attr(shape, radius, &p[0]) || !float_attr(shape, length, &p[1])) return false;
                p[1] /= 2.0;
                return true;
            case ShapeKind::HALFSPACE: return true;  // no parameters
            default:
                throw std::invalid_argument("kind must be a shape kind (0..6), got " +
                                            std::to_string(kind));
        }
    }

    /// Packs the points read (their hulls, one call, as `ConvexSet._assemble` spreads them
    /// over the shapes: primitives own no rows) and returns the view. Releases no GIL: a
    /// pair's hulls are small next to a thread's start.
    const ConvexSetView& pack() {
        view_.shape_count = 2;
        view_.kinds = kinds_.data();
        view_.params = params_.data();
        if (polytopes_ == 0) {  // two primitives: no vertices, empty feature blocks
            view_.vertices = nullptr;
            view_.vertex_count = 0;
            view_.offsets = kZeros.data();
            view_.adjacency_offsets = kZeros.data();  // (V + 1,) for V = 0, as the packing's
            view_.adjacency = kNone.data();
            view_.face_offsets = kZeros.data();
            view_.face_normals = kNoNormals.data();
            view_.edge_pair_offsets = kZeros.data();
            view_.edge_pairs = kNone.data();
            return view_;  // no edges: the view's edge-class cache is never reached
        }
        packed_ = pack_polytopes(reinterpret_cast<const Vec3*>(points_.data()),
                                 point_offsets_.data(), polytopes_, 1);
        size_t j = 0;  // the polytope of shape h, in order
        for (size_t h = 0; h < 2; ++h) {
            const bool own = kinds_[h] == static_cast<std::int8_t>(ShapeKind::POLYTOPE);
            const auto rows = [&](const std::vector<std::int64_t>& o) {
                return own ? o[j + 1] - o[j] : std::int64_t{0};
            };
            offsets_[h + 1] = offsets_[h] + rows(packed_.offsets);
            face_offsets_[h + 1] = face_offsets_[h] + rows(packed_.face_offsets);
            edge_pair_offsets_[h + 1] = edge_pair_offsets_[h] + rows(packed_.edge_pair_offsets);
            if (own) ++j;
        }
        view_.vertices = packed_.vertices.empty() ? kNoNormals.data() : packed_.vertices.data();
        view_.vertex_count = static_cast<std::int64_t>(packed_.vertices.size() / 3);
        view_.offsets = offsets_.data();
        // never null, as a numpy array's data is not: a null adjacency would stop the climb
        view_.adjacency_offsets = packed_.adjacency_offsets.data();
        view_.adjacency = packed_.adjacency.empty() ? kNone.data() : packed_.adjacency.data();
        view_.face_offsets = face_offsets_.data();
        view_.face_normals = packed_.face_normals.empty() ? kNoNormals.data() : packed_.face_normals.data();
        view_.edge_pair_offsets = edge_pair_offsets_.data();
        view_.edge_pairs = packed_.edge_pairs.empty() ? kNone.data() : packed_.edge_pairs.data();
        view_.edge_classes = &edge_classes_.emplace(2);
        return view_;
    }

  private:
    bool read_points(PyObject* shape) {
        Py_ssize_t got[2] = {0, 0};
        const double* p = numpy_data<double>(shape, 2, got);
        Buffer buffer;
        if (p == nullptr) {
            p = buffer.get<double>(shape, {-1, 3});
            if (p == nullptr) return false;
            got[0] = buffer.shape(0);
            got[1] = 3;
        }
        if (got[1] != 3) return false;
        points_.insert(points_.end(), p, p + 3 * got[0]);
        point_offsets_[polytopes_ + 1] = point_offsets_[polytopes_] + got[0];
        ++polytopes_;
        return true;
    }

    static bool float_attr(PyObject* shape, PyObject* name, double* value) {
        nb::object v = nb::steal(PyObject_GetAttr(shape, name));
        if (!v.is_valid()) throw nb::python_error();
        if (!PyFloat_CheckExact(v.ptr())) return false;
        *value = PyFloat_AsDouble(v.ptr());
        return true;
    }

    /// Reads a tuple of three floats (a box's sides, an ellipsoid's semi-axes) into
    /// `value[0..2]`, each times `factor` (a power of two: exact). False when the field is in
    /// another form.
    static bool float_triple(PyObject* shape, PyObject* name, double factor, double* value) {
        nb::object items = nb::steal(PyObject_GetAttr(shape, name));
        if (!items.is_valid()) throw nb::python_error();
        if (!PyTuple_CheckExact(items.ptr()) || PyTuple_Size(items.ptr()) != 3) return false;
        for (Py_ssize_t c = 0; c < 3; ++c) {
            PyObject* item = PyTuple_GetItem(items.ptr(), c);
            if (!PyFloat_CheckExact(item)) return false;
            value[c] = PyFloat_AsDouble(item) * factor;
        }
        return true;
    }

    static constexpr std::array<std::int64_t, 3> kZeros = {0, 0, 0};
    static constexpr std::array<std::int32_t, 2> kNone = {0, 0};
    static constexpr std::array<double, 3> kNoNormals = {0.0, 0.0, 0.0};
    std::array<std::int8_t, 2> kinds_{};
    std::array<double, 8> params_{};
    std::vector<double> points_;                       // the polytopes' points, a then b
    std::array<std::int64_t, 3> point_offsets_{};      // (P + 1,) for the P polytopes read
    long long polytopes_ = 0;
    PackedPolytopes packed_;
    std::array<std::int64_t, 3> offsets_{}, face_offsets_{}, edge_pair_offsets_{};
    std::optional<EdgeClasses> edge_classes_;  // made when there are polytopes
    ConvexSetView view_;
};

/// The (2, 4, 4) row-major poses of a pair, copied from two (4, 4) float64 arrays read in
/// place (None: the identity, as `as_pose` gives it). `read` is false when a pose is in
/// another form (a list, another dtype or shape, strides): the caller declines and Python
/// converts it (as_pose: its message).
class PairPoses {
  public:
    bool read(nb::handle pose_a, nb::handle pose_b) {
        return read_one(pose_a, matrices_.data()) && read_one(pose_b, matrices_.data() + 16);
    }

    const double* data() const { return matrices_.data(); }

  private:
    static bool read_one(nb::handle pose, double* m) {
        if (pose.is_none()) {
            for (int k = 0; k < 16; ++k) m[k] = k % 5 == 0 ? 1.0 : 0.0;
            return true;
        }
        Buffer buffer;
        const double* p = float64_array(pose.ptr(), {4, 4}, buffer);
        if (p == nullptr) return false;
        std::copy_n(p, 16, m);
        return true;
    }

    std::array<double, 32> matrices_{};
};

/// Member `value` of a status enum given as the tuple of its members in value order (the
/// enum's own call costs more than a query).
inline nb::handle status_member(nb::handle statuses, int value) {
    if (!PyTuple_CheckExact(statuses.ptr()) || value < 0 || value >= PyTuple_Size(statuses.ptr()))
        throw std::invalid_argument("statuses must be the tuple of the status enum's members, "
                                    "holding value " + std::to_string(value));
    return PyTuple_GetItem(statuses.ptr(), value);
}

}  // namespace meshcol::bindings
