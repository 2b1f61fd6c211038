// Python's repr(float) from std::to_chars' shortest round-trip digits.
//
// Python (Objects/floatobject.c, Python/pystrtod.c: format_float_short, mode 0 of David
// Gay's dtoa) takes the shortest digit string that reads back to the double, nearest to it
// when several are as short; std::to_chars without a precision gives the same digits (the
// C++17 [charconv.to.chars] contract: shortest, then nearest). Layout, with the digits
// d1..dn and the decimal point `decpt` places after d1's position:
//   decpt <= -4 or decpt > 16: d1[.d2..dn]e(+|-)XX  (exponent decpt - 1, two digits at least)
//   decpt <= 0:                0.(-decpt zeros)d1..dn
//   0 < decpt < n:             d1..d(decpt).d(decpt+1)..dn
//   decpt >= n:                d1..dn(decpt - n zeros).0
#include "meshcol/format.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <system_error>

namespace meshcol {

std::size_t format_double_repr(double value, char* out) {
    if (!std::isfinite(value)) {
        const char* word = std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf";
        const std::size_t n = std::strlen(word);
        std::memcpy(out, word, n);
        return n;
    }
    // to_chars' scientific form: [-]d[.ddd]e(+|-)XX[X], the exponent two digits at least,
    // as Python writes it: outside the fixed range, the text is Python's as it is.
    char buf[kDoubleReprSize];
    const char* end = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific).ptr;
    const bool wide = end[-5] == 'e';  // a three-digit exponent
    const char* e = wide ? end - 5 : end - 4;
    int exponent = (end[-2] - '0') * 10 + (end[-1] - '0');
    if (wide) exponent += (end[-3] - '0') * 100;
    if (e[1] == '-') exponent = -exponent;
    const int decpt = exponent + 1;
    if (decpt <= -4 || decpt > 16) {
        std::memcpy(out, buf, static_cast<std::size_t>(end - buf));
        return static_cast<std::size_t>(end - buf);
    }
    const char* p = buf;
    char* o = out;
    if (*p == '-') *o++ = *p++;
    const char first = *p++;
    const char* rest = *p == '.' ? p + 1 : p;  // the digits after the first
    const int more = static_cast<int>(e - rest);
    const int count = 1 + more;
    if (decpt <= 0) {
        *o++ = '0';
        *o++ = '.';
        for (int i = 0; i < -decpt; ++i) *o++ = '0';
        *o++ = first;
        std::memcpy(o, rest, static_cast<std::size_t>(more));
        o += more;
    } else if (decpt < count) {
        *o++ = first;
        std::memcpy(o, rest, static_cast<std::size_t>(decpt - 1));
        o += decpt - 1;
        *o++ = '.';
        std::memcpy(o, rest + decpt - 1, static_cast<std::size_t>(count - decpt));
        o += count - decpt;
    } else {
        *o++ = first;
        std::memcpy(o, rest, static_cast<std::size_t>(more));
        o += more;
        for (int i = count; i < decpt; ++i) *o++ = '0';
        *o++ = '.';
        *o++ = '0';
    }
    return static_cast<std::size_t>(o - out);
}

double round_significant(double value, int digits) {
    if (!std::isfinite(value)) return value;
    // scientific with digits - 1 after the point: `digits` significant digits, as %.*g keeps
    // them (the layout differs, the digits and so the value read back do not)
    char buf[64];
    const auto written =
        std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific, digits - 1);
    double rounded = value;
    const auto read = std::from_chars(buf, written.ptr, rounded, std::chars_format::scientific);
    if (read.ec == std::errc::result_out_of_range)  // past the largest double (few digits)
        rounded = std::abs(value) > 1.0 ? std::copysign(HUGE_VAL, value) : 0.0;
    return rounded + 0.0;  // -0.0 + 0.0 is 0.0, as in Python
}

}  // namespace meshcol
