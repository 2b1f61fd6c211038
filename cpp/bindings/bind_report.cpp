// The report writer's JSON encoder: json.dumps(obj, sort_keys=True, indent=2) of a document
// of dicts, lists, strings, numbers, booleans and None, with NaN and infinities written as
// null, byte for byte (meshcol/io/report.py: dumps_json, which falls back to its Python
// encoder whenever this one declines a document). Only the limited C API is used.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include <Python.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/format.hpp"
#include "meshcol/report_rows.hpp"
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

private:
    PyObject* builtin_;
    int conversions_ = 0;

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

// --- rows of one shape from columns (meshcol/report_rows.hpp) ---------------------------

meshcol::RowColumn::Kind column_kind(const std::string& name) {
    using C = meshcol::RowColumn;
    static const std::pair<const char*, C::Kind> kinds[] = {
        {"number", C::kNumber},   {"vector", C::kVector}, {"box", C::kBox},
        {"numbers3", C::kNumbers3}, {"matrix4", C::kMatrix4},
        {"integer", C::kInteger}, {"index", C::kIndex},   {"boolean", C::kBoolean},
        {"string", C::kString},   {"raw", C::kRaw},
    };
    for (const auto& [word, kind] : kinds)
        if (name == word) return kind;
    throw nb::value_error(("unknown column kind " + name).c_str());
}

/// The array of `object` as T with `width` values a row (n rows), or a ValueError.
template <class T>
const T* column_array(Buffer& buffer, nb::handle object, size_t n, Py_ssize_t width) {
    const T* data = width == 1 ? buffer.get<T>(object.ptr(), {static_cast<Py_ssize_t>(n)})
                               : buffer.get<T>(object.ptr(), {static_cast<Py_ssize_t>(n), width});
    if (data == nullptr) throw nb::value_error("a column's array has the wrong type or shape");
    return data;
}

/// A string column's table: its entries JSON-escaped (`raw`: as given, JSON text already).
std::shared_ptr<const std::vector<std::string>> table_of(nb::handle list, bool raw, Encoder& out) {
    auto entries = nb::cast<nb::list>(list);
    auto table = std::make_shared<std::vector<std::string>>();
    table->reserve(nb::len(entries));
    for (nb::handle item : entries) {
        Py_ssize_t size = 0;
        const char* s = PyUnicode_AsUTF8AndSize(item.ptr(), &size);
        if (s == nullptr) throw nb::python_error();
        if (raw) {
            table->emplace_back(s, static_cast<size_t>(size));
        } else {
            out.text.clear();
            out.escape(std::string_view(s, static_cast<size_t>(size)));
            table->push_back(out.text);
        }
    }
    return table;
}

/// The columns of one `dumps_rows` or `write_rows` call, parsed and checked once (keys and
/// string tables escaped, codes in their tables), the arrays' buffers held until it ends.
struct Rows {
    std::vector<Buffer> buffers;
    std::optional<meshcol::RowWriter> writer;

    Rows(nb::list columns, size_t count, size_t start, size_t stop, int level)
        : buffers(nb::len(columns)) {
        using C = meshcol::RowColumn;
        if (start > stop || stop > count) throw nb::value_error("rows out of range");
        if (level < 0 || level > 64) throw nb::value_error("level out of range");
        std::vector<C> parsed(buffers.size());
        Encoder out(nullptr);
        // tables by the list they came from (held by `columns` for the call)
        std::vector<std::pair<PyObject*, std::shared_ptr<const std::vector<std::string>>>>
            string_tables, raw_tables;
        for (size_t k = 0; k < parsed.size(); ++k) {
            auto spec = nb::cast<nb::tuple>(columns[k]);
            C& c = parsed[k];
            out.text.clear();
            out.escape(nb::cast<std::string>(spec[0]));
            c.key = out.text;
            c.kind = column_kind(nb::cast<std::string>(spec[1]));
            Buffer& b = buffers[k];
            switch (c.kind) {
                case C::kNumber: c.reals = column_array<double>(b, spec[2], count, 1); break;
                case C::kVector: c.reals = column_array<double>(b, spec[2], count, 3); break;
                case C::kBox: c.reals = column_array<double>(b, spec[2], count, 6); break;
                case C::kNumbers3: c.reals = column_array<double>(b, spec[2], count, 3); break;
                case C::kMatrix4: c.reals = column_array<double>(b, spec[2], count, 16); break;
                case C::kBoolean: c.flags = column_array<bool>(b, spec[2], count, 1); break;
                default: c.integers = column_array<std::int64_t>(b, spec[2], count, 1);
            }
            if (c.kind == C::kString || c.kind == C::kRaw) {
                nb::handle list = spec[3];
                auto& known = c.kind == C::kRaw ? raw_tables : string_tables;
                auto found = std::find_if(known.begin(), known.end(),
                                          [&](const auto& t) { return t.first == list.ptr(); });
                if (found != known.end()) {
                    c.table = found->second;  // one list for several columns: escaped once
                } else {
                    c.table = table_of(list, c.kind == C::kRaw, out);
                    known.emplace_back(list.ptr(), c.table);
                }
                const auto size = static_cast<std::int64_t>(c.table->size());
                for (size_t i = start; i < stop; ++i)
                    if (c.integers[i] >= size)
                        throw nb::index_error("a column's code is past its table");
            }
        }
        writer.emplace(std::move(parsed), level);
    }
};

/// Rows from which on `dumps_rows` writes blocks of rows on several threads.
constexpr long long kRowsPerBlock = 4096;

nb::str dumps_rows(nb::list columns, size_t count, size_t start, size_t stop, int level) {
    const Rows rows(columns, count, start, stop, level);
    const meshcol::RowWriter& writer = *rows.writer;
    // Rows are written independently (the text of a row depends on its index and columns
    // only), so blocks of rows are written on the core's threads, without the GIL, and joined
    // in order: the same text as one pass.
    const size_t n = stop - start;
    const int threads = meshcol::resolve_threads(0, static_cast<long long>(n), kRowsPerBlock);
    const size_t blocks = threads <= 1 ? 1 : static_cast<size_t>(threads) * 4;
    std::vector<std::string> pieces(blocks);
    {
        nb::gil_scoped_release unlocked;
        meshcol::parallel_for(static_cast<long long>(blocks), threads, [&](long long b, long long e) {
            for (long long k = b; k < e; ++k) {
                const size_t from = start + n * static_cast<size_t>(k) / blocks;
                const size_t to = start + n * static_cast<size_t>(k + 1) / blocks;
                std::string& piece = pieces[static_cast<size_t>(k)];
                piece.resize((to - from) * writer.row_bound());
                char* end = writer.write(from, to, piece.data());
                piece.resize(static_cast<size_t>(end - piece.data()));
            }
        });
    }
    std::string joined;
    if (blocks > 1) {
        size_t total = 0;
        for (const auto& piece : pieces) total += piece.size();
        joined.reserve(total);
        for (auto& piece : pieces) {
            joined += piece;
            std::string().swap(piece);
        }
    }
    const std::string& text = blocks > 1 ? joined : pieces[0];
    PyObject* result =
        PyUnicode_DecodeASCII(text.data(), static_cast<Py_ssize_t>(text.size()), nullptr);
    if (result == nullptr) throw nb::python_error();
    return nb::steal<nb::str>(result);
}

void write_rows_fd(int fd, nb::list columns, size_t count, int level) {
    const Rows rows(columns, count, 0, count, level);
    int failed = 0;
    {
        nb::gil_scoped_release unlocked;
        failed = rows.writer->write_to(fd, count, 0);
    }
    if (failed != 0) {
        errno = failed;
        PyErr_SetFromErrno(PyExc_OSError);
        throw nb::python_error();
    }
}

}  // namespace

void bind_report(nb::module_& m) {
    m.def("dumps_indented", &dumps_indented, "document"_a.none(), "builtin"_a,
          "json.dumps(document, sort_keys=True, indent=2) + newline, NaN and infinities as "
          "null; builtin(o) turns any other object into one of those; None when the document "
          "is one to leave to Python's json (a key that is not a string, an int beyond 64 "
          "bits, a dict subclass, a string that is not UTF-8, nesting past 400, or builtin "
          "raising).");
    m.def("dumps_rows", &dumps_rows, "columns"_a, "count"_a, "start"_a, "stop"_a, "level"_a,
          "The rows start..stop of a list of `count` dicts of one set of keys, as dumps_indented "
          "writes them inside a list at nesting `level`: each row ',' (but the first of the "
          "list), a newline, the dict. columns: (key, kind, array[, table]) in key order; kind "
          "number (n,) float64, vector (n, 3) and box (n, 6) float64 (a non-finite row null), "
          "numbers3 (n, 3) float64 (a list of 3) and matrix4 (n, 16) float64 (a 4x4 list of "
          "lists, row-major), each non-finite entry null, "
          "integer (n,) int64, index (n,) int64 (negative null), boolean (n,) bool, string and "
          "raw (n,) int64 codes into a list of str (negative null; raw: JSON text as given).");
    m.def("write_rows", &write_rows_fd, "fd"_a, "columns"_a, "count"_a, "level"_a,
          "dumps_rows's text of all `count` rows as a list ('[', the rows, a newline and "
          "']'; '[]' when empty) written to the open file descriptor `fd` at its offset, "
          "formatted on the core's threads and written in blocks of a few megabytes, never "
          "whole in memory. OSError (errno set) when a write fails: the file then holds "
          "part of the text.");
    m.def(
        "round_significant",
        [](const Values& values, int digits) {
            if (digits < 1 || digits > 17) throw nb::value_error("digits must be in 1..17");
            const size_t n = values.shape(0);
            auto out = new_array<Out<double, -1>>({n});
            const double* v = values.data();
            double* r = out.data();
            {
                nb::gil_scoped_release unlocked;
                for (size_t i = 0; i < n; ++i) r[i] = meshcol::round_significant(v[i], digits);
            }
            return out;
        },
        "values"_a, "digits"_a,
        "float(f'{x:.{digits}g}') + 0.0 of each value (digits 1..17): correctly rounded to "
        "`digits` significant digits, negative zero made 0.0, non-finite values as they are.");
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
