// The report writer's JSON encoder: json.dumps(obj, sort_keys=True, indent=2) of a document
// of dicts, lists, strings, numbers, booleans and None, with NaN and infinities written as
// null, byte for byte (meshcol/io/report.py: dumps_json, which falls back to its Python
// encoder whenever this one declines a document). Only the limited C API is used.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <Python.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "meshcol/format.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

/// Deeper than this, the document is left to Python's encoder (which reports cycles).
constexpr int kMaxDepth = 400;

/// The document is not one this encoder writes exactly as json does: use Python's.
struct Decline {};

class Encoder {
public:
    explicit Encoder(PyObject* builtin) : builtin_(builtin) {}

    std::string text;

    void value(PyObject* o, int level) {
        if (level + conversions_ > kMaxDepth) throw Decline{};
        if (PyUnicode_Check(o)) return string(o);
        if (o == Py_None) return text.append("null"), void();
        if (o == Py_True) return text.append("true"), void();
        if (o == Py_False) return text.append("false"), void();
        if (PyLong_Check(o)) return integer(o);
        if (PyFloat_Check(o)) return real(PyFloat_AsDouble(o));
        if (PyList_Check(o) || PyTuple_Check(o)) return sequence(o, level);
        if (PyDict_Check(o)) {
            if (!PyDict_CheckExact(o)) throw Decline{};  // items() may be overridden
            return mapping(o, level);
        }
        // numpy arrays and scalars, other mappings: the Python side's _builtin
        // (each conversion counts as a level: one that never ends in plain values declines)
        PyObject* plain = PyObject_CallFunctionObjArgs(builtin_, o, nullptr);
        if (plain == nullptr) {
            // not serialisable (builtin's TypeError): declined, Python raises that error; any
            // other exception (KeyboardInterrupt, MemoryError) propagates as it is
            if (!PyErr_ExceptionMatches(PyExc_TypeError)) throw nb::python_error();
            throw Decline{};
        }
        ++conversions_;
        try {
            value(plain, level);
        } catch (...) {
            --conversions_;
            Py_DECREF(plain);
            throw;
        }
        --conversions_;
        Py_DECREF(plain);
    }

private:
    PyObject* builtin_;
    int conversions_ = 0;

    void newline(int level) {
        text.push_back('\n');
        text.append(static_cast<size_t>(2 * level), ' ');
    }

    void real(double x) {
        if (!std::isfinite(x)) return text.append("null"), void();
        char buf[meshcol::kDoubleReprSize];
        text.append(buf, meshcol::format_double_repr(x, buf));
    }

    void integer(PyObject* o) {
        int overflow = 0;
        const long long v = PyLong_AsLongLongAndOverflow(o, &overflow);
        if (overflow != 0 || (v == -1 && PyErr_Occurred())) throw Decline{};
        text.append(std::to_string(v));
    }

    void string(PyObject* o) {
        Py_ssize_t size = 0;
        const char* s = PyUnicode_AsUTF8AndSize(o, &size);
        if (s == nullptr) throw Decline{};  // lone surrogates: not UTF-8
        escape(std::string_view(s, static_cast<size_t>(size)));
    }

    // json's ensure_ascii escape (encode_basestring_ascii), from UTF-8.
    void escape(std::string_view s) {
        static const char hex[] = "0123456789abcdef";
        text.push_back('"');
        const auto* p = reinterpret_cast<const unsigned char*>(s.data());
        const auto* end = p + s.size();
        auto unit = [&](std::uint32_t u) {
            const char e[6] = {'\\', 'u', hex[(u >> 12) & 15], hex[(u >> 8) & 15],
                               hex[(u >> 4) & 15], hex[u & 15]};
            text.append(e, 6);
        };
        while (p < end) {
            std::uint32_t c = *p;
            if (c >= 0x20 && c <= 0x7e && c != '"' && c != '\\') {
                const auto* run = p;
                while (p < end && *p >= 0x20 && *p <= 0x7e && *p != '"' && *p != '\\') ++p;
                text.append(reinterpret_cast<const char*>(run), static_cast<size_t>(p - run));
                continue;
            }
            int extra = 0;
            if (c >= 0xf0) c &= 0x07, extra = 3;
            else if (c >= 0xe0) c &= 0x0f, extra = 2;
            else if (c >= 0xc0) c &= 0x1f, extra = 1;
            ++p;
            for (int i = 0; i < extra && p < end; ++i) c = (c << 6) | (*p++ & 0x3f);
            switch (c) {
                case '"': text.append("\\\""); break;
                case '\\': text.append("\\\\"); break;
                case '\n': text.append("\\n"); break;
                case '\r': text.append("\\r"); break;
                case '\t': text.append("\\t"); break;
                case '\b': text.append("\\b"); break;
                case '\f': text.append("\\f"); break;
                default:
                    if (c >= 0x10000) {
                        c -= 0x10000;
                        unit(0xd800 | (c >> 10));
                        unit(0xdc00 | (c & 0x3ff));
                    } else {
                        unit(c);
                    }
            }
        }
        text.push_back('"');
    }

    void sequence(PyObject* o, int level) {
        const bool list = PyList_Check(o);
        const Py_ssize_t n = list ? PyList_Size(o) : PyTuple_Size(o);
        if (n == 0) return text.append("[]"), void();
        text.push_back('[');
        for (Py_ssize_t i = 0; i < n; ++i) {
            if (i) text.push_back(',');
            newline(level + 1);
            // borrowed; a list cannot change under us: nothing here runs Python code but
            // _builtin, and only on items that are not lists
            PyObject* item = list ? PyList_GetItem(o, i) : PyTuple_GetItem(o, i);
            if (item == nullptr) throw Decline{};
            Py_INCREF(item);
            try {
                value(item, level + 1);
            } catch (...) {
                Py_DECREF(item);
                throw;
            }
            Py_DECREF(item);
        }
        newline(level);
        text.push_back(']');
    }

    void mapping(PyObject* o, int level) {
        if (PyDict_Size(o) == 0) return text.append("{}"), void();
        std::vector<std::pair<std::string_view, PyObject*>> items;
        items.reserve(static_cast<size_t>(PyDict_Size(o)));
        Py_ssize_t pos = 0;
        PyObject *key = nullptr, *val = nullptr;
        while (PyDict_Next(o, &pos, &key, &val)) {
            if (!PyUnicode_Check(key)) throw Decline{};  // json converts such keys itself
            Py_ssize_t size = 0;
            const char* s = PyUnicode_AsUTF8AndSize(key, &size);
            if (s == nullptr) throw Decline{};
            items.emplace_back(std::string_view(s, static_cast<size_t>(size)), val);
        }
        // UTF-8 byte order is code point order: Python's sorted() of str keys.
        std::sort(items.begin(), items.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        // keys and values held: a _builtin call cannot free what the walk still reads
        std::vector<PyObject*> held;
        held.reserve(2 * items.size());
        pos = 0;
        while (PyDict_Next(o, &pos, &key, &val)) {
            Py_INCREF(key), held.push_back(key);
            Py_INCREF(val), held.push_back(val);
        }
        try {
            text.push_back('{');
            bool first = true;
            for (const auto& [name, v] : items) {
                if (!first) text.push_back(',');
                first = false;
                newline(level + 1);
                escape(name);
                text.append(": ");
                value(v, level + 1);
            }
            newline(level);
            text.push_back('}');
        } catch (...) {
            for (PyObject* h : held) Py_DECREF(h);
            throw;
        }
        for (PyObject* h : held) Py_DECREF(h);
    }
};

std::optional<nb::str> dumps_indented(nb::handle document, nb::handle builtin) {
    Encoder encoder(builtin.ptr());
    try {
        encoder.value(document.ptr(), 0);
    } catch (const Decline&) {
        PyErr_Clear();
        return std::nullopt;
    }
    encoder.text.push_back('\n');
    PyObject* text = PyUnicode_DecodeASCII(
        encoder.text.data(), static_cast<Py_ssize_t>(encoder.text.size()), nullptr);
    if (text == nullptr) throw nb::python_error();
    return nb::steal<nb::str>(text);
}

}  // namespace

void bind_report(nb::module_& m) {
    m.def("dumps_indented", &dumps_indented, "document"_a.none(), "builtin"_a,
          "json.dumps(document, sort_keys=True, indent=2) + newline, NaN and infinities as "
          "null; builtin(o) turns any other object into one of those; None when the document "
          "is one to leave to Python's json (a key that is not a string, an int beyond 64 "
          "bits, a dict subclass, a string that is not UTF-8, nesting past 400, or builtin "
          "raising).");
    m.def(
        "float_reprs",
        [](const Values& values) {
            nb::typed<nb::list, nb::str> out;
            char buf[meshcol::kDoubleReprSize];
            const double* v = values.data();
            for (size_t i = 0; i < values.shape(0); ++i) {
                const std::size_t n = meshcol::format_double_repr(v[i], buf);
                out.append(nb::steal(PyUnicode_FromStringAndSize(buf, static_cast<Py_ssize_t>(n))));
            }
            return out;
        },
        "values"_a,
        "repr(float(x)) of each value, by the core's formatter (for tests).");
}
