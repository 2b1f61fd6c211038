// The plain manifest of mesh and primitive bodies read into columns (see manifest_read.hpp).
//
// A recursive-descent reader of the one document shape it passes, on the raw bytes: every
// departure from that shape throws NotPlain and the whole document is left to Python. So
// it needs no error messages and no general JSON values: only the strings, numbers, arrays
// of numbers and the four kinds of object a plain manifest has, never nested deeper than
// four levels.
#include "meshcol/manifest_read.hpp"

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace meshcol {
namespace {

/// The document is not a plain manifest (thrown once, caught at the top).
struct NotPlain {};

[[noreturn]] void not_plain() { throw NotPlain{}; }

bool is_digit(char c) { return static_cast<unsigned>(c - '0') < 10; }

/// Strict UTF-8 (as Python's codec): no overlong forms, no surrogates, at most U+10FFFF.
bool valid_utf8(std::string_view s) {
    const auto* p = reinterpret_cast<const unsigned char*>(s.data());
    const auto* end = p + s.size();
    while (p < end) {
        const unsigned c = *p;
        if (c < 0x80) {
            ++p;
            continue;
        }
        int extra = 0;
        unsigned low = 0x80, high = 0xBF;  // the second byte's range
        if (c >= 0xC2 && c <= 0xDF) {
            extra = 1;
        } else if (c >= 0xE0 && c <= 0xEF) {
            extra = 2;
            if (c == 0xE0) low = 0xA0;
            if (c == 0xED) high = 0x9F;  // no surrogates
        } else if (c >= 0xF0 && c <= 0xF4) {
            extra = 3;
            if (c == 0xF0) low = 0x90;
            if (c == 0xF4) high = 0x8F;
        } else {
            return false;
        }
        if (end - p <= extra) return false;
        if (p[1] < low || p[1] > high) return false;
        for (int k = 2; k <= extra; ++k)
            if (p[k] < 0x80 || p[k] > 0xBF) return false;
        p += extra + 1;
    }
    return true;
}

/// The index of `word` in `words`, or -1.
int index_of(std::string_view word, const std::vector<std::string>& words) {
    for (size_t k = 0; k < words.size(); ++k)
        if (word == words[k]) return static_cast<int>(k);
    return -1;
}

class Reader {
  public:
    Reader(std::string_view text, const ManifestWords& words)
        : p_(text.data()), end_(text.data() + text.size()), words_(words) {}

    void document(ManifestColumns& out) {
        static constexpr std::string_view kBom = "\xEF\xBB\xBF";
        if (std::string_view(p_, static_cast<size_t>(end_ - p_)).substr(0, 3) == kBom) p_ += 3;
        space();
        expect('{');
        bool units = false, duration = false, bodies = false;
        members([&](std::string_view key) {
            if (key == "units") {
                once(units);
                out.units = utf8_string();
                out.has_units = true;
            } else if (key == "duration") {
                once(duration);
                const char* start = p_;
                if (!(number() > 0)) not_plain();
                out.duration = std::string_view(start, static_cast<size_t>(p_ - start));
                out.has_duration = true;
            } else if (key == "bodies") {
                once(bodies);
                body_array(out);
            } else {
                not_plain();
            }
        });
        space();
        if (!bodies || p_ != end_) not_plain();
        out.plain = true;
    }

  private:
    void space() {
        while (p_ < end_ && (*p_ == ' ' || *p_ == '\n' || *p_ == '\r' || *p_ == '\t')) ++p_;
    }
    void expect(char c) {
        if (p_ >= end_ || *p_ != c) not_plain();
        ++p_;
    }
    /// After a value: true at the next member or item (a comma eaten), false at `close`.
    bool more(char close) {
        space();
        if (p_ < end_ && *p_ == ',') {
            ++p_;
            space();
            return true;
        }
        expect(close);
        return false;
    }
    static void once(bool& seen) {
        if (seen) not_plain();  // a key twice: Python keeps the last, this reader passes
        seen = true;
    }

    /// Each member of an object whose '{' was read: `value(key)` reads the value.
    template <class Value>
    void members(Value&& value) {
        space();
        if (p_ < end_ && *p_ == '}') {
            ++p_;
            return;
        }
        do {
            const std::string_view key = string();
            space();
            expect(':');
            space();
            value(key);
        } while (more('}'));
    }

    /// A string without escapes or control characters: its bytes.
    std::string_view string() {
        expect('"');
        const char* start = p_;
        while (p_ < end_ && *p_ != '"') {
            const auto c = static_cast<unsigned char>(*p_);
            if (c == '\\' || c < 0x20) not_plain();
            ++p_;
        }
        if (p_ >= end_) not_plain();
        const std::string_view s(start, static_cast<size_t>(p_ - start));
        ++p_;
        return s;
    }

    /// A JSON number (finite, within a double's range).
    double number() {
        const char* start = p_;
        if (p_ < end_ && *p_ == '-') ++p_;
        if (p_ < end_ && *p_ == '0') {
            ++p_;
        } else {
            if (p_ >= end_ || !is_digit(*p_)) not_plain();
            while (p_ < end_ && is_digit(*p_)) ++p_;
        }
        if (p_ < end_ && *p_ == '.') {
            ++p_;
            if (p_ >= end_ || !is_digit(*p_)) not_plain();
            while (p_ < end_ && is_digit(*p_)) ++p_;
        }
        if (p_ < end_ && (*p_ == 'e' || *p_ == 'E')) {
            ++p_;
            if (p_ < end_ && (*p_ == '+' || *p_ == '-')) ++p_;
            if (p_ >= end_ || !is_digit(*p_)) not_plain();
            while (p_ < end_ && is_digit(*p_)) ++p_;
        }
        double value = 0.0;
        if (!json_number(std::string_view(start, static_cast<size_t>(p_ - start)), value))
            not_plain();
        return value;
    }

    /// An array of exactly `count` numbers, appended to `out`.
    void numbers(size_t count, std::vector<double>& out) {
        expect('[');
        for (size_t k = 0; k < count; ++k) {
            space();
            out.push_back(number());
            space();
            expect(k + 1 < count ? ',' : ']');
        }
    }

    void body_array(ManifestColumns& out) {
        expect('[');
        space();
        if (p_ < end_ && *p_ == ']') not_plain();  // no bodies: Python says so
        do {
            body(out);
        } while (more(']'));
    }

    void body(ManifestColumns& out) {
        expect('{');
        bool name = false, mesh = false, primitive = false, position = false, rotation = false,
             shape = false;
        out.positions.insert(out.positions.end(), 3, 0.0);
        out.rotation.push_back(0);
        out.shapes.push_back(-1);
        out.meshes.emplace_back();
        members([&](std::string_view key) {
            if (key == "name") {
                once(name);
                out.names.push_back(utf8_string());
            } else if (key == "mesh") {
                // the name as written: Python's reader confines and reads it (no escapes here,
                // so the text is the decoded string)
                once(mesh);
                out.meshes.back() = utf8_string();
            } else if (key == "primitive") {
                once(primitive);
                primitive_of(out);
            } else if (key == "position") {
                once(position);
                double* row = out.positions.data() + out.positions.size() - 3;
                std::vector<double>& xyz = scratch_;
                xyz.clear();
                numbers(3, xyz);
                row[0] = xyz[0], row[1] = xyz[1], row[2] = xyz[2];
                ++out.position_count;
            } else if (key == "rotation") {
                once(rotation);
                rotation_of(out);
            } else if (key == "shape") {
                once(shape);
                const int code = index_of(string(), words_.shapes);
                if (code < 0) not_plain();
                out.shapes.back() = static_cast<std::int8_t>(code);
            } else {
                not_plain();  // a moving or scaled body, an unknown field
            }
        });
        if (!name || mesh == primitive) not_plain();  // exactly one of mesh and primitive
        if (mesh) {
            ++out.mesh_count;
            out.kinds.push_back(-1);
            out.lengths.insert(out.lengths.end(), 3, 0.0);
        }
    }

    /// A non-empty string of valid UTF-8 without escapes.
    std::string_view utf8_string() {
        const std::string_view s = string();
        if (s.empty() || !valid_utf8(s)) not_plain();
        return s;
    }

    void primitive_of(ManifestColumns& out) {
        expect('{');
        int kind = -1, given = 0;
        bool type = false;
        double radius = 0.0, length = 0.0;
        std::vector<double>& size = scratch_;
        size.clear();
        members([&](std::string_view key) {
            int bit = 0;
            if (key == "type") {
                once(type);
                kind = index_of(string(), words_.types);
                if (kind < 0) not_plain();
                return;
            }
            if (key == "radius") {
                bit = kRadius;
                radius = positive();
            } else if (key == "length") {
                bit = kLength;
                length = positive();
            } else if (key == "size" || key == "semi_axes") {
                // a box's full sizes or an ellipsoid's semi-axes: the body's three lengths
                bit = key == "size" ? kSize : kSemiAxes;
                if (given & (kSize | kSemiAxes)) not_plain();
                numbers(3, size);
                for (double v : size)
                    if (!(v > 0)) not_plain();
            } else {
                not_plain();
            }
            if (given & bit) not_plain();
            given |= bit;
        });
        if (!type || given != words_.type_fields[static_cast<size_t>(kind)]) not_plain();
        out.kinds.push_back(static_cast<std::int8_t>(kind));
        if (given & (kSize | kSemiAxes)) {
            out.lengths.insert(out.lengths.end(), size.begin(), size.end());
        } else {
            out.lengths.push_back(radius);
            out.lengths.push_back(given & kLength ? length : 0.0);
            out.lengths.push_back(0.0);
        }
    }

    double positive() {
        const double value = number();
        if (!(value > 0)) not_plain();
        return value;
    }

    void rotation_of(ManifestColumns& out) {
        expect('{');
        bool quaternion = false, angles = false, order = false;
        int code = -1;
        std::vector<double>& values = scratch_;
        values.clear();
        members([&](std::string_view key) {
            if (key == "quaternion") {
                once(quaternion);
                numbers(4, values);
            } else if (key == "euler_deg") {
                once(angles);
                numbers(3, values);
            } else if (key == "order") {
                once(order);
                code = index_of(string(), words_.orders);
                if (code < 0) not_plain();
            } else {
                not_plain();
            }
        });
        if (quaternion && !angles && !order) {
            out.rotation.back() = 1;
            out.quaternions.insert(out.quaternions.end(), values.begin(), values.end());
        } else if (angles && order && !quaternion) {
            out.rotation.back() = 2;
            out.euler.insert(out.euler.end(), values.begin(), values.end());
            out.orders.push_back(static_cast<std::int8_t>(code));
        } else {
            not_plain();
        }
    }

    const char* p_;
    const char* end_;
    const ManifestWords& words_;
    std::vector<double> scratch_;  // one object's arrays at a time
};

}  // namespace

bool json_number(std::string_view token, double& value) {
    if (token.empty() || token.size() > 64) return false;
    const char* p = token.data();
    const char* end = p + token.size();
    const bool negative = *p == '-';
    const char* digits_start = negative ? p + 1 : p;
    // A plain decimal of at most 15 digits without an exponent: its digits as an integer
    // and a power of ten, both exact in a double, so the one rounding of the division is the
    // correctly rounded value (Clinger 1990), the bits std::from_chars gives.
    static constexpr double kPow10[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
    std::uint64_t digits = 0;
    int count = 0, fraction = -1;
    bool integer = true, simple = true;
    for (const char* q = digits_start; q < end; ++q) {
        if (is_digit(*q)) {
            digits = digits * 10 + static_cast<unsigned>(*q - '0');
            ++count;
            if (fraction >= 0) ++fraction;
        } else if (*q == '.' && fraction < 0) {
            fraction = 0;
            integer = false;
        } else {
            simple = false;  // an exponent (the grammar was checked by the caller)
            integer = false;
            break;
        }
        if (count > 15) {
            simple = false;
            break;
        }
    }
    if (simple && count > 0) {
        value = static_cast<double>(digits) / kPow10[fraction < 0 ? 0 : fraction];
    } else {
        const auto result = std::from_chars(p, end, value);
        if (result.ec != std::errc() || result.ptr != end) return false;
        for (const char* q = digits_start; q < end && integer; ++q)
            integer = is_digit(*q);
    }
    if (!std::isfinite(value)) return false;
    if (negative && simple) value = -value;
    if (integer && value == 0.0) value = 0.0;  // "-0" is Python's integer 0
    return true;
}

ManifestColumns read_plain_manifest(std::string_view text, const ManifestWords& words) {
    ManifestColumns out;
    if (words.type_fields.size() != words.types.size()) return out;
    try {
        Reader(text, words).document(out);
    } catch (const NotPlain&) {
        return ManifestColumns{};
    }
    return out;
}

}  // namespace meshcol
