#pragma once
// Private to the core: the exact even-odd inside test of ray_parity.cpp over a chosen set of
// faces, shared by orientation.cpp (the nesting test of closed components).
#include <cstdint>
#include <vector>

#include "meshcol/orientation.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {
namespace parity_detail {

// The faces a point is classified against: their corners and bounding intervals.
class ParityFaces {
public:
    // `chosen`: indices into `faces` (each face's vertex indices valid for `vertices`); `tags`:
    // empty, or one number per chosen face (see classify).
    ParityFaces(const double* vertices, const std::int64_t* faces,
                const std::vector<std::int64_t>& chosen, const std::vector<std::int64_t>& tags = {});
    // Inside or outside by the even-odd rule along the perturbed ray (see ray_parity), or
    // undecided for a point on one of the faces (or not finite); the faces tagged `skip` left
    // out. Does not check that the faces close up: the caller does (closed_mod_two).
    Parity classify(const Vec3& p, std::int64_t skip = -1) const;

private:
    struct Face {
        Vec3 corner[3];
        Vec3 lower, upper;  // bounding box
        int projected;      // orientation sign of the (y, z) projection: 0 never crossed
        std::int64_t tag;
    };
    std::vector<Face> faces_;
};

}  // namespace parity_detail
}  // namespace meshcol
