#pragma once
// Two primitives (meshcol.types Sphere, Box, Capsule, Cylinder) as the two-shape set
// ConvexSet.from_shapes packs for a single-pair query, read from the Python objects without
// an array: the single-pair calls (distance, time_of_impact, ...) then cost about their
// query. Bindings only: no nanobind code outside cpp/bindings/.
#include <nanobind/nanobind.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "meshcol/narrowphase.hpp"
#include "call_args.hpp"
#include "ndarray.hpp"

namespace meshcol::bindings {

/// Shapes 0 (a) and 1 (b) of a pair of primitives, packed as `ConvexSet.from_shapes` packs
/// them (kinds, params, no vertices, empty feature blocks), and the view the core reads.
class PrimitivePair {
  public:
    PrimitivePair() {
        view_.vertices = nullptr;
        view_.vertex_count = 0;
        view_.offsets = kZeros.data();
        view_.shape_count = 2;
        view_.kinds = kinds_.data();
        view_.params = params_.data();
        view_.adjacency_offsets = kZeros.data();  // (V + 1,) for V = 0, as the packing's
        view_.adjacency = kNoAdjacency.data();
        view_.face_offsets = kZeros.data();
        view_.face_normals = kNoNormals.data();
        view_.edge_pair_offsets = kZeros.data();
        view_.edge_pairs = kNoAdjacency.data();
        // no edges: the view's edge-class cache is never reached (ConvexSetView::shape)
    }

    /// Reads shape `k` (0 or 1) of ShapeKind `kind` (1..4) from the primitive `shape` as
    /// `meshcol.collision.shapes._primitive` does (a box's half sizes, a capsule's and a
    /// cylinder's half length); false when a field is not a Python float (the caller
    /// declines and the Python path packs it).
    bool read(int k, int kind, PyObject* shape) {
        double* p = params_.data() + 4 * k;
        std::fill(p, p + 4, 0.0);
        kinds_[static_cast<size_t>(k)] = static_cast<std::int8_t>(kind);
        static PyObject* const radius = interned("radius");
        static PyObject* const length = interned("length");
        static PyObject* const size = interned("size");
        switch (static_cast<ShapeKind>(kind)) {
            case ShapeKind::SPHERE: return float_attr(shape, radius, &p[0]);
            case ShapeKind::BOX: {
                nb::object sides = nb::steal(PyObject_GetAttr(shape, size));
                if (!sides.is_valid()) throw nb::python_error();
                if (!PyTuple_CheckExact(sides.ptr()) || PyTuple_Size(sides.ptr()) != 3) return false;
                for (Py_ssize_t c = 0; c < 3; ++c) {
                    PyObject* side = PyTuple_GetItem(sides.ptr(), c);
                    if (!PyFloat_CheckExact(side)) return false;
                    p[c] = PyFloat_AsDouble(side) / 2.0;
                }
                return true;
            }
            case ShapeKind::CAPSULE:
            case ShapeKind::CYLINDER:
                if (!float_attr(shape, radius, &p[0]) || !float_attr(shape, length, &p[1])) return false;
                p[1] /= 2.0;
                return true;
            default:
                throw std::invalid_argument("kind must be a primitive shape kind (1..4), got " +
                                            std::to_string(kind));
        }
    }

    const ConvexSetView& view() const { return view_; }

  private:
    static bool float_attr(PyObject* shape, PyObject* name, double* value) {
        nb::object v = nb::steal(PyObject_GetAttr(shape, name));
        if (!v.is_valid()) throw nb::python_error();
        if (!PyFloat_CheckExact(v.ptr())) return false;
        *value = PyFloat_AsDouble(v.ptr());
        return true;
    }

    static constexpr std::array<std::int64_t, 3> kZeros = {0, 0, 0};
    static constexpr std::array<std::int32_t, 2> kNoAdjacency = {0, 0};
    static constexpr std::array<double, 3> kNoNormals = {0.0, 0.0, 0.0};
    std::array<std::int8_t, 2> kinds_{};
    std::array<double, 8> params_{};
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
