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
    char buf[kDoubleReprSize];
    const auto result = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific);
    const char* p = buf;
    const char* end = result.ptr;
    char* o = out;
    if (*p == '-') *o++ = *p++;
    char digits[24];
    int count = 0;
    for (; p < end && *p != 'e'; ++p)
        if (*p != '.') digits[count++] = *p;
    int exponent = 0;
    bool negative = false;
    if (p < end) {  // 'e', a sign, two or three digits
        ++p;
        if (*p == '-' || *p == '+') negative = *p++ == '-';
        for (; p < end; ++p) exponent = exponent * 10 + (*p - '0');
    }
    if (negative) exponent = -exponent;
    const int decpt = exponent + 1;
    if (decpt <= -4 || decpt > 16) {
        *o++ = digits[0];
        if (count > 1) {
            *o++ = '.';
            std::memcpy(o, digits + 1, static_cast<std::size_t>(count - 1));
            o += count - 1;
        }
        *o++ = 'e';
        *o++ = exponent < 0 ? '-' : '+';
        const int magnitude = exponent < 0 ? -exponent : exponent;
        if (magnitude >= 100) *o++ = static_cast<char>('0' + magnitude / 100);
        *o++ = static_cast<char>('0' + magnitude / 10 % 10);
        *o++ = static_cast<char>('0' + magnitude % 10);
    } else if (decpt <= 0) {
        *o++ = '0';
        *o++ = '.';
        for (int i = 0; i < -decpt; ++i) *o++ = '0';
        std::memcpy(o, digits, static_cast<std::size_t>(count));
        o += count;
    } else if (decpt < count) {
        std::memcpy(o, digits, static_cast<std::size_t>(decpt));
        o += decpt;
        *o++ = '.';
        std::memcpy(o, digits + decpt, static_cast<std::size_t>(count - decpt));
        o += count - decpt;
    } else {
        std::memcpy(o, digits, static_cast<std::size_t>(count));
        o += count;
        for (int i = count; i < decpt; ++i) *o++ = '0';
        *o++ = '.';
        *o++ = '0';
    }
    return static_cast<std::size_t>(o - out);
}

}  // namespace meshcol
