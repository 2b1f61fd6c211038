// meshcol._core: the private native module. Each area binds itself in bind_<area>.cpp.
#include <nanobind/nanobind.h>

namespace nb = nanobind;

void bind_defaults(nb::module_& m);
void bind_narrowphase(nb::module_& m);
void bind_broadphase(nb::module_& m);
void bind_toi(nb::module_& m);
void bind_mesh_query(nb::module_& m);
void bind_io(nb::module_& m);
void bind_inspect(nb::module_& m);
void bind_hull(nb::module_& m);
void bind_hull_budget(nb::module_& m);
void bind_fit(nb::module_& m);
void bind_report(nb::module_& m);
void bind_orientation(nb::module_& m);
void bind_triangulate(nb::module_& m);
void bind_manifest(nb::module_& m);
void bind_raster(nb::module_& m);

NB_MODULE(_core, m) {
    m.doc() = "meshcol native core (private: use the meshcol package API)";
    bind_defaults(m);
    bind_narrowphase(m);
    bind_broadphase(m);
    bind_toi(m);
    bind_mesh_query(m);
    bind_io(m);
    bind_inspect(m);
    bind_hull(m);
    bind_hull_budget(m);
    bind_fit(m);
    bind_report(m);
    bind_orientation(m);
    bind_triangulate(m);
    bind_manifest(m);
    bind_raster(m);
}
