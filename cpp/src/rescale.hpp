#pragma once
// Exact power-of-two rescaling of pair queries whose lengths leave the range where GJK, EPA and
// SAT are safe in double precision. Those algorithms form squared norms and products of up to
// eight lengths (triangle regions, tetrahedron volumes, EPA face normals): beyond about 1e38
// they overflow to inf, and below about 1e-38 they fall into denormals; a sphere 1e155 from a
// box then came out at distance 0, "intersecting", with status CONVERGED. The remedy keeps the
// arithmetic itself: the pair is moved so that a's origin is the world origin (distances,
// depths and normals do not change) and scaled by a power of two 2^k so that its extent (the
// centre distance and the bounding radii) is in [1, 2). Multiplying by 2^k is exact (short of
// denormals), so the scaled query computes the same answer in a range where every product is
// finite; its lengths are divided by 2^k afterwards, again exactly. An answer beyond DBL_MAX
// (two shapes near +-1e308) is reported as such (Status::OUT_OF_RANGE), never as a number. Queries whose extent is
// already in [2^-100, 2^100] run unchanged, bit for bit.
#include <cmath>
#include <vector>

#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol::rescale {

/// Lengths whose products of eight stay finite and normal: [2^-100, 2^100].
constexpr double kSafeLow = 0x1p-100;
constexpr double kSafeHigh = 0x1p100;

/// The frame of a rescaled query: world x maps to (x - origin) 2^exponent.
struct Frame {
    bool active = false;  ///< false: the query runs in the world frame unchanged
    bool finite = true;   ///< false: the extent itself overflows (a radius beyond DBL_MAX)
    int exponent = 0;     ///< the power of two (ldexp, so that 2^exponent need not be a double)
    Vec3 origin;          ///< world point that becomes 0

    /// A length or displacement in the scaled frame.
    double length(double d) const { return std::ldexp(d, exponent); }
    Vec3 vector(const Vec3& v) const {
        return {std::ldexp(v.x, exponent), std::ldexp(v.y, exponent), std::ldexp(v.z, exponent)};
    }
    /// A world point in the scaled frame. Halves first so that the difference cannot
    /// overflow (|x - origin| may exceed DBL_MAX when both are near it, of opposite signs).
    Vec3 point(const Vec3& x) const {
        const Vec3 half = x * 0.5 - origin * 0.5;
        return {std::ldexp(half.x, exponent + 1), std::ldexp(half.y, exponent + 1),
                std::ldexp(half.z, exponent + 1)};
    }
    /// Back to the world: may overflow to inf when the answer is beyond DBL_MAX.
    double world_length(double d) const { return std::ldexp(d, -exponent); }
    Vec3 world_point(const Vec3& x) const {
        return Vec3{std::ldexp(x.x, -exponent), std::ldexp(x.y, -exponent),
                    std::ldexp(x.z, -exponent)} +
               origin;
    }
};

/// Grows the half-extent `half` (half the largest length seen) by the world point `x`
/// relative to `origin`, computed without overflow.
inline void reach(double& half, const Vec3& origin, const Vec3& x) {
    half = std::fmax(half, max_abs(x * 0.5 - origin * 0.5));
}

/// The frame for a pair of half-extent `half` about `origin`: inactive when the extent,
/// 2 half, is already in [kSafeLow, kSafeHigh], or is 0; not `finite` when `half` is not.
inline Frame choose(const Vec3& origin, double half) {
    Frame f;
    f.origin = origin;
    if (!std::isfinite(half)) {
        f.finite = false;
        return f;
    }
    if (!(half > 0.0) || (2.0 * half >= kSafeLow && 2.0 * half <= kSafeHigh)) return f;
    f.active = true;
    f.exponent = -std::ilogb(half) - 1;  // half 2^exponent in [0.5, 1): the extent in [1, 2)
    return f;
}

/// `shape` in the frame `f` (vertices copied into `storage` for a polytope; the parameters of
/// every primitive are lengths, see ShapeKind). Normals and edge directions do not change.
inline ShapeView scaled(const ShapeView& shape, const Frame& f, std::vector<Vec3>& storage) {
    ShapeView s = shape;
    for (double& p : s.params) p = f.length(p);
    if (s.kind == ShapeKind::POLYTOPE && s.vertices != nullptr) {
        storage.resize(static_cast<size_t>(s.vertex_count));
        for (int i = 0; i < s.vertex_count; ++i) storage[i] = f.vector(s.vertices[i]);
        s.vertices = storage.data();
    }
    return s;
}

}  // namespace meshcol::rescale
