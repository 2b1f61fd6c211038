// The float formatter of the report writer (format.hpp): repr(float) as Python writes it.
#include <cmath>
#include <limits>
#include <string>

#include "check.hpp"
#include "meshcol/format.hpp"

using namespace meshcol;

namespace {

std::string repr(double value) {
    char text[kDoubleReprSize];
    return std::string(text, format_double_repr(value, text));
}

}  // namespace

TEST_CASE("format: fixed notation inside [1e-4, 1e16)") {
    CHECK_EQ(repr(0.0), std::string("0.0"));
    CHECK_EQ(repr(-0.0), std::string("-0.0"));
    CHECK_EQ(repr(1.0), std::string("1.0"));
    CHECK_EQ(repr(0.1), std::string("0.1"));
    CHECK_EQ(repr(0.1 + 0.2), std::string("0.30000000000000004"));
    CHECK_EQ(repr(-2.5), std::string("-2.5"));
    CHECK_EQ(repr(0.0001), std::string("0.0001"));
    CHECK_EQ(repr(123456.789), std::string("123456.789"));
    CHECK_EQ(repr(1e15), std::string("1000000000000000.0"));
    CHECK_EQ(repr(9999999999999998.0), std::string("9999999999999998.0"));
}

TEST_CASE("format: scientific notation outside, two exponent digits at least") {
    CHECK_EQ(repr(1e16), std::string("1e+16"));
    CHECK_EQ(repr(1e-5), std::string("1e-05"));
    CHECK_EQ(repr(1.5e-7), std::string("1.5e-07"));
    CHECK_EQ(repr(-1.2345e100), std::string("-1.2345e+100"));
    CHECK_EQ(repr(5e-324), std::string("5e-324"));
    CHECK_EQ(repr(std::numeric_limits<double>::max()), std::string("1.7976931348623157e+308"));
    CHECK_EQ(repr(2.2250738585072014e-308), std::string("2.2250738585072014e-308"));
}

TEST_CASE("format: non-finite values as Python writes them") {
    CHECK_EQ(repr(std::numeric_limits<double>::quiet_NaN()), std::string("nan"));
    CHECK_EQ(repr(std::numeric_limits<double>::infinity()), std::string("inf"));
    CHECK_EQ(repr(-std::numeric_limits<double>::infinity()), std::string("-inf"));
}

TEST_CASE("format: every text reads back to the same double") {
    // a walk over magnitudes and mantissas; the shortest digits are exact round trips
    double x = 1.2345678901234567e-300;
    for (int i = 0; i < 2000; ++i) {
        const std::string text = repr(x);
        CHECK_EQ(std::stod(text), x);
        x *= 1.4142135623730951;
    }
}

TEST_CASE("format: round_significant is Python's float(f'{x:.12g}') + 0.0") {
    // expected values from CPython 3.11: float(f"{x:.12g}") + 0.0
    CHECK_EQ(round_significant(0.1 + 0.2, 12), 0.3);
    CHECK_EQ(round_significant(1.0000000000005, 12), 1.0);  // the double is below the half
    CHECK_EQ(round_significant(2.5, 1), 2.0);               // an exact half: to even
    CHECK_EQ(round_significant(3.5, 1), 4.0);
    CHECK_EQ(round_significant(123456789012.5, 12), 123456789012.0);
    CHECK_EQ(round_significant(1e308, 12), 1e308);
    CHECK_EQ(round_significant(5e-324, 12), 5e-324);
    CHECK_EQ(round_significant(2.225073858507201e-308, 12), 2.22507385851e-308);
    CHECK_EQ(round_significant(1.7976931348623157e308, 12), 1.79769313486e308);
    CHECK(!std::signbit(round_significant(-0.0, 12)));
    CHECK(std::isnan(round_significant(std::numeric_limits<double>::quiet_NaN(), 12)));
    CHECK_EQ(round_significant(-std::numeric_limits<double>::infinity(), 12),
             -std::numeric_limits<double>::infinity());
}

TEST_CASE("format: round_significant past the largest double is infinite, as in Python") {
    CHECK_EQ(round_significant(1.7976931348623157e308, 1), std::numeric_limits<double>::infinity());
    CHECK_EQ(round_significant(-1.7976931348623157e308, 2), -std::numeric_limits<double>::infinity());
}
