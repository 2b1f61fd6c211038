#pragma once
/// Small fixed-size linear algebra: 3-vectors, 3x3 matrices and rigid poses.
/// Everything is double precision and header-only so hot loops inline it.

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace meshcol {

/// A 3-vector (point or direction; the caller's frame).
struct Vec3 {
    double x = 0.0, y = 0.0, z = 0.0;

    constexpr Vec3() = default;
    constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
};

constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr double squared_norm(const Vec3& v) { return dot(v, v); }
inline double norm(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline bool is_finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline Vec3 component_min(const Vec3& a, const Vec3& b) {
    return {std::fmin(a.x, b.x), std::fmin(a.y, b.y), std::fmin(a.z, b.z)};
}
inline Vec3 component_max(const Vec3& a, const Vec3& b) {
    return {std::fmax(a.x, b.x), std::fmax(a.y, b.y), std::fmax(a.z, b.z)};
}
/// Largest absolute component (the infinity norm), used for relative tolerances.
inline double max_abs(const Vec3& v) {
    return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
}

/// `v`, whose largest absolute component is `m` (> 0, finite), made safe to square: itself
/// when m lies in [2^-500, 2^500], else divided by the power of two 2^e (exactly) that brings
/// m into [1, 2), with e written to `*exponent` (0 when unscaled). Products, sums, square roots
/// and quotients of the result round as those of v would (a power-of-two scale commutes with
/// rounding away from the denormals), so in range every caller gets v's own bits.
inline Vec3 safe_scaled(const Vec3& v, double m, int* exponent = nullptr) {
    if (m >= 0x1p-500 && m <= 0x1p500) {
        if (exponent != nullptr) *exponent = 0;
        return v;
    }
    const int e = std::ilogb(m);
    if (exponent != nullptr) *exponent = e;
    return {std::ldexp(v.x, -e), std::ldexp(v.y, -e), std::ldexp(v.z, -e)};
}

/// |v| without overflow or underflow in the squares (`safe_scaled`: plain `norm` when the
/// largest component is in [2^-500, 2^500], bit for bit).
inline double safe_norm(const Vec3& v) {
    const double m = max_abs(v);
    if (!(m > 0.0) || !std::isfinite(m)) return m;
    int e = 0;
    const Vec3 u = safe_scaled(v, m, &e);
    return e == 0 ? norm(u) : std::ldexp(norm(u), e);
}

/// Writes `v` as row `i` of a row-major (n, 3) array; does nothing when `out` is null (an
/// output the caller did not ask for).
inline void store_row(double* out, long long i, const Vec3& v) {
    if (out == nullptr) return;
    out[3 * i] = v.x;
    out[3 * i + 1] = v.y;
    out[3 * i + 2] = v.z;
}

/// A 3x3 matrix, row-major: m[r][c].
struct Mat3 {
    double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    static Mat3 identity() { return Mat3{}; }
    constexpr Vec3 row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
    constexpr Vec3 column(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
    /// M v
    constexpr Vec3 operator*(const Vec3& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    /// M^T v
    constexpr Vec3 transpose_times(const Vec3& v) const {
        return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
                m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
                m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
    }
    Mat3 operator*(const Mat3& o) const {
        Mat3 r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
        return r;
    }
    Mat3 transposed() const {
        Mat3 r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = m[j][i];
        return r;
    }
};

/// A rigid pose: world = rotation * local + translation.
struct Pose {
    Mat3 rotation;     ///< orthonormal, det +1 (checked by `is_rigid`)
    Vec3 translation;  ///< world frame

    Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
    Vec3 apply_inverse(const Vec3& p) const { return rotation.transpose_times(p - translation); }
    Vec3 rotate(const Vec3& d) const { return rotation * d; }
    Vec3 rotate_inverse(const Vec3& d) const { return rotation.transpose_times(d); }

    /// Reads a row-major homogeneous 4x4 matrix (16 doubles).
    static Pose from_matrix4(const double* m) {
        Pose p;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) p.rotation.m[r][c] = m[r * 4 + c];
        p.translation = {m[3], m[7], m[11]};
        return p;
    }
};

/// True when a row-major 4x4 matrix is finite, has last row (0, 0, 0, 1), and an orthonormal
/// rotation block with determinant +1, each within `tolerance` (finite, >= 0).
/// The rotation block is not tested for finiteness on its own: an infinite entry makes its
/// row's squared length infinite, and a NaN makes the determinant NaN, so either fails below.
/// R R^T is symmetric (its (i, j) and (j, i) entries are the same products), so its upper half
/// is tested.
inline bool is_rigid_matrix4(const double* m, double tolerance) {
    for (int i : {3, 7, 11, 12, 13, 14, 15})
        if (!std::isfinite(m[i])) return false;
    if (std::fabs(m[12]) > tolerance || std::fabs(m[13]) > tolerance ||
        std::fabs(m[14]) > tolerance || std::fabs(m[15] - 1.0) > tolerance)
        return false;
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
            double d = 0.0;
            for (int k = 0; k < 3; ++k) d += m[i * 4 + k] * m[j * 4 + k];
            if (std::fabs(d - (i == j ? 1.0 : 0.0)) > tolerance) return false;
        }
    const Vec3 r0{m[0], m[1], m[2]}, r1{m[4], m[5], m[6]}, r2{m[8], m[9], m[10]};
    return dot(cross(r0, r1), r2) > 0.0;
}

}  // namespace meshcol
