#pragma once
// The one copy of the ndarray helpers of the bindings: the shape-typed input arrays every
// binding takes, the numpy output arrays it makes, and the offset check of packed arrays.
// Shape-typed signatures give the generated _core.pyi stub real array types.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
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
using Pairs32 = In<std::int32_t, -1, 2>; ///< (P, 2) int32 local index pairs
using Faces = In<std::int64_t, -1, 3>;   ///< (F, 3) vertex indices

/// A writable C-contiguous CPU array of `T` with shape `Shape`, filled in place (the caller's).
template <class T, ssize_t... Shape>
using InOut = nb::ndarray<T, nb::shape<Shape...>, nb::c_contig, nb::device::cpu>;

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

/// The buffer (Python's buffer protocol, as numpy arrays export it) of an argument taken as a
/// plain object, for the calls whose whole cost is a few hundred nanoseconds: reading a numpy
/// array this way costs a fraction of the ndarray caster's DLPack import. `get` accepts only a
/// C-contiguous buffer of T in native byte order whose shape matches (-1: any size); anything
/// else (another dtype, strides, a list) reads as null, and the caller takes its general path.
class Buffer {
public:
    Buffer() = default;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    ~Buffer() {
        if (held_) PyBuffer_Release(&view_);
    }

    template <class T>
    T* get(PyObject* object, std::initializer_list<Py_ssize_t> shape, bool writable = false) {
        if (held_ || !PyObject_CheckBuffer(object)) return nullptr;
        const int flags = PyBUF_RECORDS_RO | (writable ? PyBUF_WRITABLE : 0);
        if (PyObject_GetBuffer(object, &view_, flags) != 0) {
            PyErr_Clear();
            return nullptr;
        }
        held_ = true;
        if (view_.itemsize != static_cast<Py_ssize_t>(sizeof(T)) || !format_is<T>(view_.format) ||
            view_.ndim != static_cast<int>(shape.size()) || !PyBuffer_IsContiguous(&view_, 'C'))
            return nullptr;
        int d = 0;
        for (Py_ssize_t s : shape) {
            if (s >= 0 && view_.shape[d] != s) return nullptr;
            ++d;
        }
        if (reinterpret_cast<std::uintptr_t>(view_.buf) % alignof(T) != 0) return aligned_copy<T>(writable);
        return static_cast<T*>(view_.buf);
    }

    /// Whether a buffer is exported (and released at destruction).
    bool held() const { return held_; }

    /// Size of dimension `d` of the buffer `get` accepted.
    Py_ssize_t shape(int d) const { return view_.shape[d]; }

private:
    // A buffer at an address T may not be read from (a view at an odd byte offset: loads
    // through a misaligned T* are undefined) is read through an aligned copy; one the caller
    // would write to reads as null (the caller converts it).
    template <class T>
    T* aligned_copy(bool writable) {
        if (writable) return nullptr;
        const size_t n = static_cast<size_t>(view_.len) / sizeof(T);
        if constexpr (std::is_same_v<T, double>) {
            doubles_.resize(n);
            std::memcpy(doubles_.data(), view_.buf, n * sizeof(T));
            return doubles_.data();
        } else if constexpr (std::is_same_v<T, std::int64_t>) {
            integers_.resize(n);
            std::memcpy(integers_.data(), view_.buf, n * sizeof(T));
            return integers_.data();
        } else {
            static_assert(alignof(T) == 1, "add an aligned copy for this type");
            return static_cast<T*>(view_.buf);
        }
    }

    // struct-module codes: '@', '=' or (on a little-endian machine) '<' may lead.
    template <class T>
    static bool format_is(const char* f) {
        if (f == nullptr) return false;
        if (*f == '@' || *f == '=' || (*f == '<' && is_little_endian())) ++f;
        if (f[0] == '\0' || f[1] != '\0') return false;
        if constexpr (std::is_same_v<T, double>) return f[0] == 'd';
        else if constexpr (std::is_same_v<T, bool>) return f[0] == '?';
        else if constexpr (std::is_same_v<T, std::int8_t>) return f[0] == 'b';
        else if constexpr (std::is_same_v<T, std::int64_t>) return f[0] == 'l' || f[0] == 'q';
        else static_assert(sizeof(T) == 0, "no buffer format for this type");
    }
    static bool is_little_endian() {
        const std::uint16_t one = 1;
        return *reinterpret_cast<const unsigned char*>(&one) == 1;
    }

    // Filled by PyObject_GetBuffer and read only once `held_`: not zeroed on construction (every
    // call of a few hundred nanoseconds makes one or two of these).
    Py_buffer view_;
    bool held_ = false;
    std::vector<double> doubles_;          // aligned_copy's
    std::vector<std::int64_t> integers_;   // aligned_copy's
};

/// numpy's array constructor from its C API table (the `_ARRAY_API` capsule every extension
/// compiled against numpy reads at import_array), found without numpy's headers, which do not
/// build under the stable ABI. Only entries fixed by numpy's ABI are used: 0
/// (PyArray_GetNDArrayCVersion, checked to be ABI 1.x or 2.x), 2 (PyArray_Type), 93
/// (PyArray_New) and 282 (PyArray_SetBaseObject). Null members: numpy.empty is called instead.
struct NumpyApi {
    using NewArray = PyObject* (*)(PyTypeObject*, int, const Py_ssize_t*, int, const Py_ssize_t*,
                                   void*, int, int, PyObject*);
    using SetBase = int (*)(PyObject*, PyObject*);
    PyTypeObject* array_type = nullptr;
    NewArray new_array = nullptr;
    SetBase set_base = nullptr;

    static const NumpyApi& get() {
        static const NumpyApi api = find();
        return api;
    }

private:
    static NumpyApi find() {
        NumpyApi api;
        for (const char* name : {"numpy._core._multiarray_umath", "numpy.core._multiarray_umath"}) {
            PyObject* module = PyImport_ImportModule(name);
            if (module == nullptr) {
                PyErr_Clear();
                continue;
            }
            PyObject* capsule = PyObject_GetAttrString(module, "_ARRAY_API");
            Py_DECREF(module);
            if (capsule == nullptr || !PyCapsule_CheckExact(capsule)) {
                Py_XDECREF(capsule);
                PyErr_Clear();
                continue;
            }
            auto** table = static_cast<void**>(PyCapsule_GetPointer(capsule, PyCapsule_GetName(capsule)));
            Py_DECREF(capsule);  // the module keeps the table alive
            if (table == nullptr) {
                PyErr_Clear();
                continue;
            }
            const unsigned int abi = reinterpret_cast<unsigned int (*)()>(table[0])();
            if (abi < 0x01000009u || abi >= 0x03000000u) break;
            api.array_type = static_cast<PyTypeObject*>(table[2]);
            api.new_array = reinterpret_cast<NewArray>(table[93]);
            api.set_base = reinterpret_cast<SetBase>(table[282]);
            break;
        }
        return api;
    }
};

/// numpy's type number of T (bool, std::int8_t, std::int32_t, std::int64_t or double): NPY_BOOL,
/// NPY_BYTE, NPY_INT (32 bits where int is), NPY_LONG or NPY_LONGLONG (whichever is 64 bits),
/// NPY_DOUBLE.
template <class T>
constexpr int numpy_type_number() {
    static_assert(std::is_same_v<T, bool> || std::is_same_v<T, std::int8_t> || std::is_same_v<T, std::int32_t> ||
                      std::is_same_v<T, std::int64_t> || std::is_same_v<T, double>,
                  "add the dtype");
    static_assert(sizeof(int) == 4, "NPY_INT is int32 only where int is 32 bits");
    return std::is_same_v<T, bool>           ? 0
           : std::is_same_v<T, std::int8_t>  ? 1
           : std::is_same_v<T, std::int32_t> ? 5
           : std::is_same_v<T, std::int64_t> ? (sizeof(long) == 8 ? 7 : 9)
                                             : 12;
}

/// A new, uninitialised, C-contiguous numpy array of T (bool, std::int8_t, std::int32_t,
/// std::int64_t or double), of `n` entries or, with `columns` > 0, of shape (n, columns), and its data in
/// `*data`, for results of a few entries: numpy's own constructor
/// (NumpyApi) costs a small fraction of exporting an `Out` (numpy.asarray of a DLPack view),
/// numpy.empty about a third. The data pointer is read where every extension compiled against
/// numpy reads it (the first field after the object header of numpy's array struct, what
/// PyArray_DATA expands to), not through a buffer export (which costs as much as the array);
/// checked once against the buffer protocol, which is used from then on should the two ever
/// disagree. Holds the GIL.
template <class T>
nb::object numpy_empty(size_t n, T** data, size_t columns = 0) {
    constexpr int type_number = numpy_type_number<T>();
    constexpr const char* type_name = std::is_same_v<T, bool>           ? "bool"
                                      : std::is_same_v<T, std::int8_t>  ? "int8"
                                      : std::is_same_v<T, std::int32_t> ? "int32"
                                      : std::is_same_v<T, std::int64_t> ? "int64"
                                                                        : "float64";
    static int layout_checked = 0;  // 0: not yet, 1: the struct read agrees, -1: use the buffer
    const NumpyApi& api = NumpyApi::get();
    nb::object array;
    const int ndim = columns > 0 ? 2 : 1;
    if (api.new_array != nullptr) {
        const Py_ssize_t shape[2] = {static_cast<Py_ssize_t>(n), static_cast<Py_ssize_t>(columns)};
        array = nb::steal(api.new_array(api.array_type, ndim, shape, type_number, nullptr, nullptr, 0, 0, nullptr));
    } else {
        // never released: they live as long as the interpreter's numpy
        static PyObject* const empty = nb::object(nb::module_::import_("numpy").attr("empty")).release().ptr();
        static PyObject* const dtype =
            nb::object(nb::module_::import_("numpy").attr("dtype")(type_name)).release().ptr();
        const auto rows = static_cast<Py_ssize_t>(n), width = static_cast<Py_ssize_t>(columns);
        nb::object size = nb::steal(ndim == 1 ? PyLong_FromSsize_t(rows) : Py_BuildValue("(nn)", rows, width));
        if (!size.is_valid()) throw nb::python_error();
        PyObject* args[] = {size.ptr(), dtype};
        array = nb::steal(PyObject_Vectorcall(empty, args, 2, nullptr));
    }
    if (!array.is_valid()) throw nb::python_error();
    struct ArrayHead {
        PyObject head;
        char* data;
    };
    if (layout_checked <= 0) {
        Py_buffer view;
        if (PyObject_GetBuffer(array.ptr(), &view, PyBUF_SIMPLE | PyBUF_WRITABLE) != 0) throw nb::python_error();
        void* buffer_data = view.buf;
        PyBuffer_Release(&view);
        if (layout_checked == 0)
            layout_checked = reinterpret_cast<ArrayHead*>(array.ptr())->data == buffer_data ? 1 : -1;
        if (layout_checked < 0) {
            *data = static_cast<T*>(buffer_data);
            return array;
        }
    }
    *data = reinterpret_cast<T*>(reinterpret_cast<ArrayHead*>(array.ptr())->data);
    return array;
}

/// The arrays of one small result, made together: their data are slices of one block (a
/// small native object, each array's `base`), so a batch of a few pairs pays one allocation
/// for all its columns and no numpy memory handler (about a third of what an array costs to
/// make and free). `add` records a column (n entries of T, or (n, columns)) and where its data
/// pointer goes; `make` makes them all, after which `operator[]` is column k's array. Columns
/// whose total passes kBlockBytes are made one by one by `numpy_empty` instead (each array
/// owns its data): a block lives as long as any of its arrays, and a caller that keeps one
/// column of a large batch must not keep the others' memory. The arrays are writable and
/// C-contiguous either way. Holds the GIL.
class NumpyColumns {
public:
    static constexpr size_t kMaxColumns = 10;
    static constexpr size_t kBlockBytes = 4096;  ///< the most a block holds

    NumpyColumns() = default;
    NumpyColumns(const NumpyColumns&) = delete;
    NumpyColumns& operator=(const NumpyColumns&) = delete;
    ~NumpyColumns() {
        for (size_t k = 0; k < made_; ++k) Py_DECREF(arrays_[k]);
    }

    template <class T>
    size_t add(size_t n, T** data, size_t columns = 0) {
        if (count_ == kMaxColumns) throw std::logic_error("NumpyColumns: too many columns");
        const size_t k = count_++;
        Column& c = columns_[k];
        c.rows = n;
        c.columns = columns;
        c.data = reinterpret_cast<void**>(data);
        c.item = sizeof(T);
        c.make_one = [](size_t rows, void** out, size_t cols) {
            return numpy_empty(rows, reinterpret_cast<T**>(out), cols);
        };
        c.type_number = numpy_type_number<T>();
        return k;
    }

    void make() {
        size_t total = 0;
        for (size_t k = 0; k < count_; ++k) total = round_up(total) + bytes(columns_[k]);
        const NumpyApi& api = NumpyApi::get();
        if (total > kBlockBytes || api.new_array == nullptr || api.set_base == nullptr) {
            for (size_t k = 0; k < count_; ++k) {
                Column& c = columns_[k];
                arrays_[k] = c.make_one(c.rows, c.data, c.columns).release().ptr();
                made_ = k + 1;
            }
            return;
        }
        nb::object block = nb::steal(new_block(total));
        auto* base = reinterpret_cast<unsigned char*>(block.ptr()) + kHeader;
        size_t offset = 0;
        for (size_t k = 0; k < count_; ++k) {
            Column& c = columns_[k];
            offset = round_up(offset);
            void* data = base + offset;
            offset += bytes(c);
            const int ndim = c.columns > 0 ? 2 : 1;
            const Py_ssize_t shape[2] = {static_cast<Py_ssize_t>(c.rows), static_cast<Py_ssize_t>(c.columns)};
            constexpr int carray = 0x0001 | 0x0100 | 0x0400;  // NPY_ARRAY_CARRAY: C order, aligned, writable
            PyObject* array =
                api.new_array(api.array_type, ndim, shape, c.type_number, nullptr, data, 0, carray, nullptr);
            if (array == nullptr) throw nb::python_error();
            arrays_[k] = array;
            made_ = k + 1;
            if (api.set_base(array, block.inc_ref().ptr()) != 0) throw nb::python_error();  // steals
            *c.data = data;
        }
    }

    /// Column k's array once `make` has run (a null handle before).
    nb::handle operator[](size_t k) const { return k < made_ ? arrays_[k] : nullptr; }

private:
    // trivial, so that the unused entries of `columns_` cost nothing: a one-pair batch is
    // a few hundred nanoseconds
    struct Column {
        size_t rows, columns, item;
        void** data;
        int type_number;
        nb::object (*make_one)(size_t, void**, size_t);
    };

    // the block's data start 16-aligned after its object header, and so does each column
    static constexpr size_t kAlign = 16;
    static constexpr size_t kHeader = (sizeof(PyObject) + kAlign - 1) / kAlign * kAlign;
    static size_t round_up(size_t b) { return (b + kAlign - 1) / kAlign * kAlign; }
    static size_t bytes(const Column& c) { return c.rows * (c.columns > 0 ? c.columns : 1) * c.item; }

    // A block of `bytes` bytes after a plain object header: its type holds no references and
    // frees the memory with the object (PyObject_Malloc; no zeroing).
    static PyObject* new_block(size_t bytes) {
        static PyTypeObject* const type = block_type();
        void* memory = PyObject_Malloc(kHeader + (bytes == 0 ? 1 : bytes));
        if (memory == nullptr) throw std::bad_alloc();
        return PyObject_Init(static_cast<PyObject*>(memory), type);  // a reference to the type
    }

    static PyTypeObject* block_type() {
        static PyType_Slot slots[] = {{Py_tp_dealloc, reinterpret_cast<void*>(&free_block)},
                                      {Py_tp_doc, const_cast<char*>("The memory of a small batch's result arrays.")},
                                      {0, nullptr}};
        static PyType_Spec spec = {"meshcol._core.ResultBlock", static_cast<int>(kHeader), 0, Py_TPFLAGS_DEFAULT,
                                   slots};
        PyObject* type = PyType_FromSpec(&spec);
        if (type == nullptr) throw nb::python_error();
        return reinterpret_cast<PyTypeObject*>(type);  // kept for the module's life
    }

    static void free_block(PyObject* self) {
        PyTypeObject* type = Py_TYPE(self);
        PyObject_Free(self);
        Py_DECREF(type);  // instances of a heap type hold a reference to it
    }

    std::array<Column, kMaxColumns> columns_;  // the first count_ are set
    std::array<PyObject*, kMaxColumns> arrays_;  // the first made_ are made (references owned)
    size_t count_ = 0, made_ = 0;
};

/// The data of `object` when it is exactly a numpy array (not a subclass), C-contiguous and
/// aligned, of T (int64 or float64) in native byte order, with `ndim` dimensions whose sizes go to `shape`;
/// null otherwise (the caller then asks the buffer protocol, which says the same for such an
/// array, only slower: a buffer export costs about as much as a one-pair query). Read from
/// numpy's array and dtype structs where every extension compiled against numpy reads them
/// (PyArray_DATA, _NDIM, _DIMS, _FLAGS, _DESCR and the dtype's kind, type and byteorder
/// characters, whose offsets numpy 1.x and 2.x share), checked once against the buffer
/// protocol (data, shape) and not used again should the two ever disagree. No reference to the
/// data is held: read it under the GIL, or export a buffer before releasing it. Holds the GIL.
template <class T>
const T* numpy_data(PyObject* object, int ndim, Py_ssize_t* shape) {
    static_assert(std::is_same_v<T, std::int64_t> || std::is_same_v<T, double>, "add the dtype");
    struct ArrayHead {
        PyObject head;
        char* data;
        int nd;
        Py_ssize_t* dimensions;
        Py_ssize_t* strides;
        PyObject* base;
        PyObject* descr;
        int flags;
    };
    struct DescrHead {
        PyObject head;
        PyTypeObject* typeobj;
        char kind;
        char type;
        char byteorder;
    };
    constexpr int c_contiguous = 0x0001, aligned = 0x0100;  // NPY_ARRAY_C_CONTIGUOUS, _ALIGNED
    static int layout_checked = 0;  // 0: not yet, 1: the struct read agrees, -1: never use it
    const NumpyApi& api = NumpyApi::get();
    if (layout_checked < 0 || api.array_type == nullptr || Py_TYPE(object) != api.array_type) return nullptr;
    const auto* a = reinterpret_cast<const ArrayHead*>(object);
    const auto* d = reinterpret_cast<const DescrHead*>(a->descr);
    const std::uint16_t one = 1;
    const bool little = *reinterpret_cast<const unsigned char*>(&one) == 1;
    const bool native = d->byteorder == '=' || d->byteorder == '|' || (d->byteorder == '<' && little) ||
                        (d->byteorder == '>' && !little);
    const bool typed = std::is_same_v<T, double>
                           ? d->kind == 'f' && d->type == 'd'
                           : d->kind == 'i' && (d->type == 'q' || (d->type == 'l' && sizeof(long) == 8));
    if (a->nd != ndim || !native || !typed || (a->flags & (c_contiguous | aligned)) != (c_contiguous | aligned))
        return nullptr;
    if (layout_checked == 0) {
        Py_buffer view;
        if (PyObject_GetBuffer(object, &view, PyBUF_RECORDS_RO) != 0) {
            PyErr_Clear();
            return nullptr;
        }
        bool agree = view.buf == a->data && view.ndim == ndim && view.itemsize == 8;
        for (int k = 0; agree && k < ndim; ++k) agree = view.shape[k] == a->dimensions[k];
        PyBuffer_Release(&view);
        layout_checked = agree ? 1 : -1;
        if (!agree) return nullptr;
    }
    for (int k = 0; k < ndim; ++k) shape[k] = a->dimensions[k];
    return reinterpret_cast<const T*>(a->data);
}

inline const std::int64_t* numpy_int64_data(PyObject* object, int ndim, Py_ssize_t* shape) {
    return numpy_data<std::int64_t>(object, ndim, shape);
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

/// The count H of the groups that `offsets` (H + 1 entries) delimits over `total` rows,
/// checked as check_offsets checks them: how every binding that takes groups opens.
inline long long group_count(const std::int64_t* offsets, size_t n, std::int64_t total,
                             const char* name) {
    if (n == 0) throw std::invalid_argument(std::string(name) + " must be (H + 1,), got (0,)");
    check_offsets(offsets, n, total, name);
    return static_cast<long long>(n) - 1;
}

}  // namespace meshcol::bindings
