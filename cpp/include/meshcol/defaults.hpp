#pragma once
/// Every default and cap of the core, in one place (as coal's narrowphase_defaults.h): the
/// list is defaults.inc, each entry a `constexpr` here. Exposed to Python as
/// `meshcol._core.defaults` (every entry, by bind_defaults.cpp).

#include <cstdint>

namespace meshcol::defaults {

#define MESHCOL_DEFAULT(type, name, value) constexpr type name = value;
#include "meshcol/defaults.inc"
#undef MESHCOL_DEFAULT

}  // namespace meshcol::defaults
