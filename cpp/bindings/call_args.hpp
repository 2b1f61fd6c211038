#pragma once
// The arguments and results of the calls that take plain Python objects and build their result
// natively (the batches' fast path: a batch of one pair costs about what its query costs):
// pairs read in place, interned field names, and result dataclasses made without a Python
// frame. Bindings only: no nanobind code outside cpp/bindings/.
#include <nanobind/nanobind.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <vector>

#include "ndarray.hpp"

namespace meshcol::bindings {

namespace nb = nanobind;

// The pairs of a call that takes them as a plain object: a C-contiguous (P, 2) int64 buffer
// (a numpy array, read in place) or a list or tuple of (i, j) lists or tuples of Python ints
// (copied); anything else reads as null and the caller converts it (as_pairs) and calls again.
// The size of an exact list or tuple (false for anything else), and its item k (borrowed).
inline bool sequence_size(PyObject* o, Py_ssize_t* size) {
    if (PyList_CheckExact(o)) *size = PyList_Size(o);
    else if (PyTuple_CheckExact(o)) *size = PyTuple_Size(o);
    else return false;
    return true;
}

inline PyObject* sequence_item(PyObject* o, Py_ssize_t k) {
    return PyList_CheckExact(o) ? PyList_GetItem(o, k) : PyTuple_GetItem(o, k);
}

struct PairsArg {
    Buffer buffer;
    std::vector<std::int64_t> copied;
    const std::int64_t* data = nullptr;
    long long count = 0;

    bool read(PyObject* pairs) {
        Py_ssize_t shape[2];
        if (const std::int64_t* p = numpy_int64_data(pairs, 2, shape); p != nullptr && shape[1] == 2) {
            data = p;
            count = static_cast<long long>(shape[0]);
            return true;
        }
        if (const std::int64_t* p = buffer.get<std::int64_t>(pairs, {-1, 2})) {
            data = p;
            count = static_cast<long long>(buffer.shape(0));
            return true;
        }
        // list and tuple access by functions, not the PySequence_Fast macros: the module is
        // built for the stable ABI on Python 3.12 and later
        Py_ssize_t n = 0;
        if (!sequence_size(pairs, &n) || n == 0) return false;  // as_pairs decides what [] means
        copied.resize(2 * static_cast<size_t>(n));
        for (Py_ssize_t k = 0; k < n; ++k) {
            PyObject* pair = sequence_item(pairs, k);
            Py_ssize_t two = 0;
            if (!sequence_size(pair, &two) || two != 2) return false;
            for (Py_ssize_t c = 0; c < 2; ++c) {
                PyObject* index = sequence_item(pair, c);
                if (!PyLong_CheckExact(index)) return false;  // bools, numpy scalars: as_pairs
                int overflow = 0;
                const long long value = PyLong_AsLongLongAndOverflow(index, &overflow);
                if (overflow != 0 || (value == -1 && PyErr_Occurred())) {
                    PyErr_Clear();
                    return false;
                }
                copied[2 * static_cast<size_t>(k) + static_cast<size_t>(c)] = value;
            }
        }
        data = copied.data();
        count = static_cast<long long>(n);
        return true;
    }

    // Before the GIL is released: pairs read from numpy's struct (no buffer held) are copied,
    // so that nothing another thread does to that array can reach the loop.
    void pin() {
        if (data == copied.data() || data == nullptr) return;
        if (buffer.held()) return;
        copied.assign(data, data + 2 * count);
        data = copied.data();
    }
};

// A float64 array of exactly `shape` read in place: from numpy's struct, else from a buffer that
// `buffer` holds until it is destroyed. Null when `object` is in another form (a list, another
// dtype or shape, strides): the caller declines, and Python converts it and calls again.
inline const double* float64_array(PyObject* object, std::initializer_list<Py_ssize_t> shape,
                                   Buffer& buffer) {
    constexpr size_t kMaxDims = 4;
    Py_ssize_t got[kMaxDims];
    if (shape.size() > kMaxDims) return nullptr;
    if (const double* p = numpy_data<double>(object, static_cast<int>(shape.size()), got))
        return std::equal(shape.begin(), shape.end(), got) ? p : nullptr;
    return buffer.get<double>(object, shape);
}

// An optional float64 array argument of a call that reads its arguments in place: None is
// absent (null data), anything float64_array reads is present, anything else is declined.
// Read from numpy's struct, it holds no reference to the data, so `pin` exports its buffer
// before the GIL is released: while a buffer is exported numpy refuses to resize or free it.
class Float64Arg {
public:
    bool read(nb::handle object, std::initializer_list<Py_ssize_t> shape) {
        object_ = object.ptr();
        if (object.is_none()) return true;
        ndim_ = shape.size();
        std::copy(shape.begin(), shape.end(), shape_.begin());
        data_ = float64_array(object_, shape, buffer_);
        return data_ != nullptr;
    }

    const double* data() const { return data_; }

    void pin() {
        if (data_ == nullptr || buffer_.held()) return;
        const double* exported = nullptr;
        switch (ndim_) {  // the same shape, which the numpy read has already matched
            case 2: exported = buffer_.get<double>(object_, {shape_[0], shape_[1]}); break;
            case 3: exported = buffer_.get<double>(object_, {shape_[0], shape_[1], shape_[2]}); break;
            default: break;
        }
        if (exported == nullptr) throw std::runtime_error("an array read in place refused its buffer");
        data_ = exported;
    }

private:
    Buffer buffer_;
    PyObject* object_ = nullptr;
    std::array<Py_ssize_t, 4> shape_{};
    size_t ndim_ = 0;
    const double* data_ = nullptr;
};

// A result dataclass instance made as its generated __init__ makes it (object.__setattr__ of
// each field, frozen or not), without the Python frame: `names` (interned once by the caller)
// and `values` in field order. The setters of a slotted class (its fields' member descriptors)
// are looked up once per type and called directly, which is what object.__setattr__ ends in;
// any other class takes object.__setattr__ itself.
template <size_t N>
class DataclassMaker {
public:
    nb::object make(nb::handle type, const std::array<PyObject*, N>& names,
                    const std::array<nb::handle, N>& values) {
        if (!PyType_Check(type.ptr())) throw nb::type_error("result_type must be a class");
        auto* tp = reinterpret_cast<PyTypeObject*>(type.ptr());
        if (type.ptr() != type_) learn(type, names);
        auto alloc = reinterpret_cast<allocfunc>(PyType_GetSlot(tp, Py_tp_alloc));
        nb::object self = nb::steal(alloc(tp, 0));
        if (!self.is_valid()) throw nb::python_error();
        for (size_t k = 0; k < N; ++k) {
            const int failed = setter_[k] != nullptr
                                   ? setter_[k](descriptor_[k], self.ptr(), values[k].ptr())
                                   : PyObject_GenericSetAttr(self.ptr(), names[k], values[k].ptr());
            if (failed != 0) throw nb::python_error();
        }
        return self;
    }

private:
    // The type and its descriptors are held while they are the ones kept (so that a new type
    // at the same address cannot inherit them), and let go when another type takes their place.
    void learn(nb::handle type, const std::array<PyObject*, N>& names) {
        // the attribute of a slotted class is its member descriptor (a built-in type)
        static PyObject* const member_type =
            nb::object(nb::module_::import_("types").attr("MemberDescriptorType")).release().ptr();
        std::array<PyObject*, N> descriptor{};
        std::array<descrsetfunc, N> setter{};
        for (size_t k = 0; k < N; ++k) {
            PyObject* d = PyObject_GetAttr(type.ptr(), names[k]);
            if (d == nullptr) {
                PyErr_Clear();
            } else if (reinterpret_cast<PyObject*>(Py_TYPE(d)) == member_type) {
                descriptor[k] = d;
                setter[k] = reinterpret_cast<descrsetfunc>(PyType_GetSlot(Py_TYPE(d), Py_tp_descr_set));
                continue;
            } else {
                Py_DECREF(d);
            }
        }
        Py_XDECREF(type_);
        for (PyObject* d : descriptor_) Py_XDECREF(d);
        type_ = nb::handle(type).inc_ref().ptr();
        descriptor_ = descriptor;
        setter_ = setter;
    }

    PyObject* type_ = nullptr;
    std::array<PyObject*, N> descriptor_{};
    std::array<descrsetfunc, N> setter_{};
};

inline PyObject* interned(const char* name) {
    PyObject* s = PyUnicode_InternFromString(name);
    if (s == nullptr) throw nb::python_error();
    return s;  // kept for the module's life
}

}  // namespace meshcol::bindings
