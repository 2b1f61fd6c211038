// The exact even-odd inside test (orientation.hpp: ray_parity): a ray along +x from the point
// moved by (0, e, e^2), e infinitesimal (Simulation of Simplicity), crossing counted with exact
// orientation signs.
#include "ray_parity.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

#include "meshcol/orientation.hpp"
#include "meshcol/triangle.hpp"
#include "predicates.hpp"

namespace meshcol {
namespace parity_detail {
namespace {

inline Vec3 vertex(const double* vertices, std::int64_t i) {
    const double* v = vertices + 3 * i;
    return {v[0], v[1], v[2]};
}

// Sign of orient2d((u.y, u.z), (v.y, v.z), (p.y + e, p.z + e^2)), never 0 unless the edge's
// projection is a point. The determinant is O + (v.y - u.y) e^2 - (v.z - u.z) e, with O its
// value at p: the sign of the first nonzero of O, u.z - v.z, v.y - u.y (e >> e^2 > 0). Swapping
// u and v negates every term, so two faces sharing an edge see the point on opposite sides of
// it, whichever way each winds it.
inline int perturbed_side(const Vec3& u, const Vec3& v, const Vec3& p) {
    const int exact = predicates::orient2d_sign(u.y, u.z, v.y, v.z, p.y, p.z);
    if (exact != 0) return exact;
    if (u.z != v.z) return u.z > v.z ? 1 : -1;
    if (u.y != v.y) return v.y > u.y ? 1 : -1;
    return 0;
}

}  // namespace

ParityFaces::ParityFaces(const double* vertices, const std::int64_t* faces,
                         const std::vector<std::int64_t>& chosen,
                         const std::vector<std::int64_t>& tags) {
    faces_.reserve(chosen.size());
    for (size_t i = 0; i < chosen.size(); ++i) {
        const std::int64_t f = chosen[i];
        Face face;
        face.tag = tags.empty() ? -1 : tags[i];
        for (int k = 0; k < 3; ++k) face.corner[k] = vertex(vertices, faces[3 * f + k]);
        const Vec3 &a = face.corner[0], &b = face.corner[1], &c = face.corner[2];
        face.lower = component_min(component_min(a, b), c);
        face.upper = component_max(component_max(a, b), c);
        face.projected = predicates::orient2d_sign(a.y, a.z, b.y, b.z, c.y, c.z);
        faces_.push_back(face);
    }
}

Parity ParityFaces::classify(const Vec3& p, std::int64_t skip) const {
    if (!is_finite(p)) return Parity::undecided;
    const Vec3 point[3] = {p, p, p};
    bool odd = false;
    for (const Face& face : faces_) {
        if (skip >= 0 && face.tag == skip) continue;
        const bool in_box = p.x >= face.lower.x && p.x <= face.upper.x && p.y >= face.lower.y &&
                            p.y <= face.upper.y && p.z >= face.lower.z && p.z <= face.upper.z;
        // On the face (closed triangle, exact): inside is not defined there.
        if (in_box && triangles_intersect(face.corner, point, nullptr)) return Parity::undecided;
        // The perturbed ray keeps x >= p.x, y = p.y + e and z = p.z + e^2: it can meet only a
        // face reaching x >= p.x whose y range holds p.y + e and z range p.z + e^2.
        if (face.projected == 0 || face.upper.x < p.x) continue;
        if (p.y < face.lower.y || p.y >= face.upper.y || p.z < face.lower.z || p.z >= face.upper.z)
            continue;
        const Vec3 &a = face.corner[0], &b = face.corner[1], &c = face.corner[2];
        const int s = face.projected;
        if (perturbed_side(a, b, p) != s || perturbed_side(b, c, p) != s ||
            perturbed_side(c, a, p) != s)
            continue;
        // The line meets the face's plane at p + t x with t > 0 exactly when orient3d(a, b, c,
        // p) (= -n . (p - a), n = (b - a) x (c - a), n.x = the projected orientation) has the
        // projection's sign. Zero would put p on the face, handled above.
        const int side = predicates::orient3d_sign(a, b, c, p);
        if (side == 0) return Parity::undecided;
        if (side == s) odd = !odd;
    }
    return odd ? Parity::inside : Parity::outside;
}

}  // namespace parity_detail

bool closed_mod_two(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                    std::int64_t face_count) {
    for (std::int64_t k = 0; k < 3 * face_count; ++k)
        if (!std::isfinite(vertices[3 * faces[k]]) || !std::isfinite(vertices[3 * faces[k] + 1]) ||
            !std::isfinite(vertices[3 * faces[k] + 2]))
            return false;  // a face with no place bounds nothing
    // Vertices at the same place are one: rank the used ones (all finite) by their coordinates.
    std::vector<std::int64_t> order(faces, faces + 3 * face_count);
    std::sort(order.begin(), order.end());
    order.erase(std::unique(order.begin(), order.end()), order.end());
    auto coordinates = [vertices](std::int64_t i) {
        return std::array<double, 3>{vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
    };
    std::sort(order.begin(), order.end(),
              [&](std::int64_t i, std::int64_t j) { return coordinates(i) < coordinates(j); });
    std::vector<std::int64_t> place(static_cast<size_t>(vertex_count), -1);
    std::int64_t rank = -1;
    for (size_t k = 0; k < order.size(); ++k) {
        if (k == 0 || coordinates(order[k - 1]) < coordinates(order[k])) ++rank;
        place[static_cast<size_t>(order[k])] = rank;
    }
    std::vector<std::pair<std::int64_t, std::int64_t>> edges;
    edges.reserve(static_cast<size_t>(3 * face_count));
    for (std::int64_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const std::int64_t a = place[static_cast<size_t>(faces[3 * f + k])];
            const std::int64_t b = place[static_cast<size_t>(faces[3 * f + (k + 1) % 3])];
            if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    if (edges.empty()) return false;
    std::sort(edges.begin(), edges.end());
    for (size_t k = 0; k < edges.size();) {
        size_t end = k;
        while (end < edges.size() && edges[end] == edges[k]) ++end;
        if ((end - k) % 2 != 0) return false;
        k = end;
    }
    return true;
}

void ray_parity(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                std::int64_t face_count, const double* points, std::int64_t point_count,
                Parity* out) {
    if (!closed_mod_two(vertices, vertex_count, faces, face_count)) {
        std::fill(out, out + point_count, Parity::undecided);
        return;
    }
    std::vector<std::int64_t> all(static_cast<size_t>(face_count));
    std::iota(all.begin(), all.end(), std::int64_t{0});
    const parity_detail::ParityFaces chosen(vertices, faces, all);
    for (std::int64_t i = 0; i < point_count; ++i)
        out[i] = chosen.classify({points[3 * i], points[3 * i + 1], points[3 * i + 2]});
}

}  // namespace meshcol
