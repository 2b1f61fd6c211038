#pragma once
// Quickhull as the core built it before quickhull_flat (conflict lists of point copies, one
// vector a face), kept out of the core as the tests' reference: quickhull_flat must replay its
// steps and give its triangulation to the bit (test_hull.cpp).

#include <cstddef>
#include <vector>

#include "hull_detail.hpp"

namespace meshcol::hull_reference {

// A point waiting outside a face, with its coordinates.
struct Conflict {
    Vec3 p;
    int index;
};

struct Face {
    int v[3];  // point indices, counter-clockwise seen from outside
    int n[3];  // neighbour across edge v[i] -> v[(i + 1) % 3]
    int s[3];  // the edge of n[i] that leads back here (its twin)
    hull_detail::Plane plane;
    std::vector<Conflict> conflicts;  // the points outside this face (farther than eps)
    int furthest = -1;
    double furthest_distance = 0.0;
    unsigned visit = 0;
    bool visible = false;
    bool alive = false;
};

/// The core's workspace (points, eps, the horizon walk's arrays) and the reference's faces.
struct Workspace : hull_detail::Workspace {
    std::vector<Face> faces;  // a pool: faces[0 .. face_count) are this hull's
    size_t face_count = 0;
    size_t free_top = 0;  // the free slots: free_faces[0 .. free_top)
    std::vector<Conflict> orphans;
    std::vector<double> new_planes;  // the new faces' planes (nx, ny, nz, offset), packed
};

/// Quickhull of the points `subset` of w.p, without the interior filter.
hull_detail::Build quickhull(Workspace& w, const std::vector<int>& subset,
                             hull_detail::Triangulation& out);

}  // namespace meshcol::hull_reference
