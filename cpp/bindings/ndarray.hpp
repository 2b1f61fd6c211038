#pragma once
// The one copy of the ndarray helpers of the bindings: the shape-typed input arrays every
// binding takes, the numpy output arrays it makes, and the offset check of packed arrays.
// Shape-typed signatures give the generated _core.pyi stub real array types.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace meshcol::bindings {

namespace nb = nanobind;

/// A read-only C-contiguous CPU input array of `T` with shape `Shape` (-1: any size).
template <class T, ssize_t... Shape>
using In = nb::ndarray<const T, nb::shape<Shape...>, nb::c_contig, nb::device::cpu>;

using Points = In<double, -1, 3>;        ///< (N, 3) points or vectors
using Point = In<double, 3>;             ///< (3,) one point or vector
using Params = In<double, -1, 4>;        ///< (H, 4) shape parameters
using Poses = In<double, -1, 4, 4>;      ///< (N, 4, 4) row-major world-from-local poses
using Triangles = In<double, -1, 3, 3>;  ///< (N, 3, 3) triangle corners
using Values = In<double, -1>;           ///< (N,) doubles
using Index64 = In<std::int64_t, -1>;    ///< (N,) int64 indices or offsets
using Index32 = In<std::int32_t, -1>;    ///< (N,) int32 indices
using Kinds = In<std::int8_t, -1>;       ///< (H,) ShapeKind codes
using Pairs = In<std::int64_t, -1, 2>;   ///< (P, 2) index pairs
using Faces = In<std::int64_t, -1, 3>;   ///< (F, 3) vertex indices

/// A writable numpy output array of `T` with shape `Shape`.
template <class T, ssize_t... Shape>
using Out = nb::ndarray<nb::numpy, T, nb::shape<Shape...>, nb::c_contig>;

/// The Python object of an exported `Out` array, keeping its type for the stub: result
/// classes hold these, so every read of a field returns the same numpy array.
template <class A>
using ArrayObject = decltype(std::declval<A&>().cast());

/// A new numpy array of type `A` (an `Out`) and `shape` that owns its uninitialised data.
template <class A>
A new_array(std::initializer_list<size_t> shape) {
    using T = typename A::Scalar;
    size_t n = 1;
    for (size_t s : shape) n *= s;
    T* data = new T[n == 0 ? 1 : n];
    nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
    return A(data, shape, owner);
}

/// Hands `values` (rows x cols entries; cols 0: a 1-D array of rows) to numpy without a copy.
template <class A>
A vector_array(std::vector<typename A::Scalar>&& values, size_t rows, size_t cols) {
    using T = typename A::Scalar;
    auto* heap = new std::vector<T>(std::move(values));
    if (heap->empty()) heap->reserve(1);  // a non-null data pointer even for 0 rows
    nb::capsule owner(heap, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    const size_t shape[2] = {rows, cols};
    return A(heap->data(), cols == 0 ? 1 : 2, shape, owner);
}

/// Throws unless `offsets` (n entries) starts at 0, ends at `total` and never decreases.
inline void check_offsets(const std::int64_t* offsets, size_t n, std::int64_t total,
                          const char* name) {
    if (n == 0 || offsets[0] != 0 || offsets[n - 1] != total)
        throw std::invalid_argument(std::string(name) + " must start at 0 and end at " +
                                    std::to_string(total));
    for (size_t i = 1; i < n; ++i)
        if (offsets[i] < offsets[i - 1])
            throw std::invalid_argument(std::string(name) + " must be non-decreasing");
}

}  // namespace meshcol::bindings
