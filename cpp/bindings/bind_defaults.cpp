// Exposes defaults.hpp, the status enums (status.hpp, shapes.hpp) and the thread helpers.
#include <nanobind/nanobind.h>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"

namespace nb = nanobind;

namespace {
// The namespace meshcol._core.defaults: a class holding the constants as class attributes,
// not a submodule, so that the stub of meshcol._core (nanobind's stubgen, one file) types
// each of them.
struct Defaults {};
}  // namespace

void bind_defaults(nb::module_& m) {
    namespace d = meshcol::defaults;
    nb::class_<Defaults> s(m, "defaults",
                           "Defaults and caps of the core (cpp/include/meshcol/defaults.inc).");
    // Every entry of the one list (defaults.inc), by name.
#define MESHCOL_DEFAULT(type, name, value) s.attr(#name) = d::name;
#include "meshcol/defaults.inc"
#undef MESHCOL_DEFAULT
    m.def("hardware_threads", &meshcol::hardware_threads,
          "Number of hardware threads (at least 1).");

    // The enums the Python ones in meshcol/types.py and meshcol/collision/shapes.py mirror
    // (tests/test_native.py checks they match).
    nb::enum_<meshcol::Status>(m, "Status", "Outcome of a pair query (status.hpp).")
        .value("CONVERGED", meshcol::Status::CONVERGED)
        .value("MAX_ITERATIONS", meshcol::Status::MAX_ITERATIONS)
        .value("DEGENERATE", meshcol::Status::DEGENERATE)
        .value("INVALID_INPUT", meshcol::Status::INVALID_INPUT)
        .value("NOT_RUN", meshcol::Status::NOT_RUN)
        .value("OUT_OF_RANGE", meshcol::Status::OUT_OF_RANGE);
    using T = meshcol::TimeOfImpactStatus;
    nb::enum_<T>(m, "TimeOfImpactStatus", "Outcome of a time-of-impact query (status.hpp).")
        .value("HIT", T::HIT)
        .value("SEPARATED", T::SEPARATED)
        .value("OVERLAPPED_AT_START", T::OVERLAPPED_AT_START)
        .value("FAILED", T::FAILED)
        .value("INVALID_INPUT", T::INVALID_INPUT);
    using K = meshcol::ShapeKind;
    nb::enum_<K>(m, "ShapeKind", "Kind of a packed convex shape (shapes.hpp).")
        .value("POLYTOPE", K::POLYTOPE)
        .value("SPHERE", K::SPHERE)
        .value("BOX", K::BOX)
        .value("CAPSULE", K::CAPSULE)
        .value("CYLINDER", K::CYLINDER)
        .value("ELLIPSOID", K::ELLIPSOID)
        .value("HALFSPACE", K::HALFSPACE);
}
