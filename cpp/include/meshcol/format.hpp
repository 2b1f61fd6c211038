#pragma once
/// Number text as Python writes it, for the report writers: the shortest digits that read
/// back to the same double (std::to_chars), laid out exactly as Python's repr(float) lays
/// them out, so a report written here is byte-identical to one written by Python's json.

#include <cstddef>

namespace meshcol {

/// Room `format_double_repr` needs: sign, 17 digits, point, "e-324", and a spare.
inline constexpr std::size_t kDoubleReprSize = 32;

/// Writes repr(value) to `out` (at least kDoubleReprSize chars, not terminated) and returns
/// the number of chars written: fixed notation with at least one digit after the point
/// ("0.0001", "1000000000000000.0") when the decimal exponent is in [-4, 16), else
/// "d[.ddd]e+XX" with a signed exponent of at least two digits ("1e-05", "1e+16",
/// "5e-324"); "-0.0" for negative zero; "nan", "inf", "-inf" as Python writes them (JSON
/// writers turn those into null themselves).
std::size_t format_double_repr(double value, char* out);

/// Python's float(f"{value:.{digits}g}") + 0.0: `value` correctly rounded to `digits`
/// significant decimal digits (1..17) and read back correctly rounded (std::to_chars,
/// std::from_chars), negative zero made 0.0; a non-finite value as it is. The reports'
/// rounding of numbers that compare across machines (a sweep's 12 digits).
double round_significant(double value, int digits);

}  // namespace meshcol
