// Static mesh hierarchy: top-down binned SAH build (Wald 2007, "On fast construction of
// SAH-based bounding volume hierarchies"), explicit work stack so deep trees cannot overflow the
// call stack, float boxes rounded outwards so they stay conservative.
#include "meshcol/mesh_bvh.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "meshcol/defaults.hpp"

namespace meshcol {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Largest float <= x (never above it), so a float lower bound stays below the double.
float round_down(double x) {
    if (x > static_cast<double>(FLT_MAX)) return FLT_MAX;
    if (x < -static_cast<double>(FLT_MAX)) return -std::numeric_limits<float>::infinity();
    float f = static_cast<float>(x);
    if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}

// Smallest float >= x.
float round_up(double x) {
    if (x > static_cast<double>(FLT_MAX)) return std::numeric_limits<float>::infinity();
    if (x < -static_cast<double>(FLT_MAX)) return -FLT_MAX;
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

struct Box {
    Vec3 lower{kInf, kInf, kInf};
    Vec3 upper{-kInf, -kInf, -kInf};

    void grow(const Vec3& p) {
        lower = component_min(lower, p);
        upper = component_max(upper, p);
    }
    void grow(const Box& b) {
        lower = component_min(lower, b.lower);
        upper = component_max(upper, b.upper);
    }
    bool empty() const { return lower.x > upper.x; }
    // Half the surface area (the SAH only compares areas).
    double half_area() const {
        if (empty()) return 0.0;
        const Vec3 d = upper - lower;
        return d.x * d.y + d.y * d.z + d.z * d.x;
    }
};

// SAH bin of a centroid coordinate `c` in [lo, lo + extent] (extent > 0), always in
// [0, mesh_bvh_bins). Divides before scaling: kBins / extent overflows to inf for a denormal
// extent (vertices near 1e-310), and 0 * inf is NaN, whose conversion to int is undefined; an
// infinite extent (coordinates near the double range) puts everything in bin 0.
inline int bin_of(double c, double lo, double extent) {
    constexpr int kBins = defaults::mesh_bvh_bins;
    const double x = (c - lo) / extent * kBins;
    if (!(x > 0.0)) return 0;  // also NaN
    return x >= kBins - 1 ? kBins - 1 : static_cast<int>(x);
}

struct BuildTask {
    std::int32_t begin, end;
    std::int32_t patch;  // node whose right-child index is this task's node, or -1
};

}  // namespace

MeshBvh::MeshBvh(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                 std::int64_t face_count) {
    if (vertex_count < 0 || face_count < 0) throw std::invalid_argument("negative mesh size");
    if (face_count > std::numeric_limits<std::int32_t>::max() / 2)
        throw std::invalid_argument("mesh has too many faces (" + std::to_string(face_count) + ")");
    for (std::int64_t f = 0; f < 3 * face_count; ++f)
        if (faces[f] < 0 || faces[f] >= vertex_count)
            throw std::invalid_argument("face " + std::to_string(f / 3) + " has vertex index " +
                                        std::to_string(faces[f]) + " out of range [0, " +
                                        std::to_string(vertex_count) + ")");
    for (std::int64_t i = 0; i < 3 * vertex_count; ++i)
        if (!std::isfinite(vertices[i])) return;  // not valid(): queries report INVALID_INPUT
    if (face_count == 0) return;

    const auto n = static_cast<std::int32_t>(face_count);
    auto vertex = [&](std::int64_t i) {
        return Vec3{vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
    };
    std::vector<Box> boxes(static_cast<size_t>(n));
    std::vector<Vec3> centroids(static_cast<size_t>(n));
    for (std::int32_t f = 0; f < n; ++f) {
        Box b;
        for (int k = 0; k < 3; ++k) b.grow(vertex(faces[3 * f + k]));
        boxes[static_cast<size_t>(f)] = b;
        centroids[static_cast<size_t>(f)] = (b.lower + b.upper) * 0.5;
    }
    std::vector<std::int32_t> order(static_cast<size_t>(n));
    for (std::int32_t f = 0; f < n; ++f) order[static_cast<size_t>(f)] = f;

    constexpr int kBins = defaults::mesh_bvh_bins;
    constexpr int kLeaf = defaults::mesh_bvh_leaf_size;
    nodes_.reserve(static_cast<size_t>(2 * (n / kLeaf + 1)));
    std::vector<BuildTask> stack{{0, n, -1}};
    Box bin_box[kBins];
    std::int32_t bin_count[kBins];
    double right_area[kBins];
    std::int32_t right_count[kBins];

    while (!stack.empty()) {
        const BuildTask task = stack.back();
        stack.pop_back();
        const auto id = static_cast<std::int32_t>(nodes_.size());
        if (task.patch >= 0) nodes_[static_cast<size_t>(task.patch)].index = id;
        Box bounds, centroid_bounds;
        for (std::int32_t i = task.begin; i < task.end; ++i) {
            const std::int32_t f = order[static_cast<size_t>(i)];
            bounds.grow(boxes[static_cast<size_t>(f)]);
            centroid_bounds.grow(centroids[static_cast<size_t>(f)]);
        }
        BvhNode node{};
        for (int k = 0; k < 3; ++k) {
            node.lower[k] = round_down(bounds.lower[k]);
            node.upper[k] = round_up(bounds.upper[k]);
        }
        const std::int32_t count = task.end - task.begin;
        if (count <= kLeaf) {
            node.index = task.begin;
            node.count = count;
            nodes_.push_back(node);
            continue;
        }
        // Best binned SAH split over the three axes.
        double best_cost = kInf;
        int best_axis = -1, best_bin = -1;
        for (int axis = 0; axis < 3; ++axis) {
            const double lo = centroid_bounds.lower[axis];
            const double extent = centroid_bounds.upper[axis] - lo;
            if (!(extent > 0.0)) continue;
            for (int b = 0; b < kBins; ++b) {
                bin_box[b] = Box{};
                bin_count[b] = 0;
            }
            for (std::int32_t i = task.begin; i < task.end; ++i) {
                const std::int32_t f = order[static_cast<size_t>(i)];
                const int b = bin_of(centroids[static_cast<size_t>(f)][axis], lo, extent);
                bin_box[b].grow(boxes[static_cast<size_t>(f)]);
                ++bin_count[b];
            }
            Box right;
            std::int32_t right_n = 0;
            for (int b = kBins - 1; b > 0; --b) {
                right.grow(bin_box[b]);
                right_n += bin_count[b];
                right_area[b] = right.half_area();
                right_count[b] = right_n;
            }
            Box left;
            std::int32_t left_n = 0;
            for (int b = 0; b < kBins - 1; ++b) {
                left.grow(bin_box[b]);
                left_n += bin_count[b];
                if (left_n == 0 || right_count[b + 1] == 0) continue;
                const double cost = left_n * left.half_area() + right_count[b + 1] * right_area[b + 1];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bin = b;
                }
            }
        }
        std::int32_t mid = task.begin + count / 2;
        if (best_axis >= 0) {
            const double lo = centroid_bounds.lower[best_axis];
            const double extent = centroid_bounds.upper[best_axis] - lo;
            auto first = order.begin() + task.begin, last = order.begin() + task.end;
            auto split = std::partition(first, last, [&](std::int32_t f) {
                return bin_of(centroids[static_cast<size_t>(f)][best_axis], lo, extent) <= best_bin;
            });
            const auto m = static_cast<std::int32_t>(split - order.begin());
            if (m > task.begin && m < task.end) mid = m;
        }
        // Otherwise all centroids coincide: any split is as good, halve by count.
        node.index = -1;
        node.count = 0;
        nodes_.push_back(node);
        stack.push_back({mid, task.end, id});
        stack.push_back({task.begin, mid, -1});
    }

    corners_.resize(3 * static_cast<size_t>(n));
    face_index_.resize(static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const std::int32_t f = order[static_cast<size_t>(i)];
        face_index_[static_cast<size_t>(i)] = f;
        for (int k = 0; k < 3; ++k) corners_[3 * static_cast<size_t>(i) + k] = vertex(faces[3 * f + k]);
    }
    // Closed and consistently wound: sorted directed edges pair up as (u, v) and (v, u).
    std::vector<std::pair<std::int64_t, std::int64_t>> edges;
    edges.reserve(3 * static_cast<size_t>(face_count));
    for (std::int64_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const std::int64_t u = faces[3 * f + k], v = faces[3 * f + (k + 1) % 3];
            if (u != v) edges.push_back({u, v});
        }
    std::sort(edges.begin(), edges.end());
    closed_ = !edges.empty();
    for (size_t e = 0; e < edges.size() && closed_; ++e) {
        const auto [u, v] = edges[e];
        const bool repeated = e + 1 < edges.size() && edges[e + 1] == edges[e];
        closed_ = !repeated && std::binary_search(edges.begin(), edges.end(), std::make_pair(v, u));
    }
    std::vector<char> used(static_cast<size_t>(vertex_count), 0);
    for (std::int64_t k = 0; k < 3 * face_count; ++k) used[static_cast<size_t>(faces[k])] = 1;
    for (std::int64_t v = 0; v < vertex_count; ++v)
        if (used[static_cast<size_t>(v)]) vertices_.push_back(vertex(v));
}

bool MeshBvh::validate() const {
    if (nodes_.empty()) return corners_.empty() && face_index_.empty();
    const std::int32_t n = triangle_count();
    if (corners_.size() != 3 * static_cast<size_t>(n)) return false;
    std::vector<char> seen(static_cast<size_t>(n), 0);
    for (std::int32_t i = 0; i < n; ++i) {
        const std::int64_t f = face_index_[static_cast<size_t>(i)];
        if (f < 0 || f >= n || seen[static_cast<size_t>(f)]) return false;
        seen[static_cast<size_t>(f)] = 1;
    }
    auto contains = [](const BvhNode& box, const float lo[3], const float hi[3]) {
        for (int k = 0; k < 3; ++k)
            if (lo[k] < box.lower[k] || hi[k] > box.upper[k]) return false;
        return true;
    };
    // Walk depth-first: leaves must cover [0, n) in order, children must follow the layout.
    std::int32_t next_triangle = 0;
    std::vector<std::int32_t> stack{0};
    std::int32_t visited = 0;
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        if (id < 0 || id >= static_cast<std::int32_t>(nodes_.size())) return false;
        ++visited;
        const BvhNode& node = nodes_[static_cast<size_t>(id)];
        for (int k = 0; k < 3; ++k)
            if (!(node.lower[k] <= node.upper[k])) return false;
        if (node.is_leaf()) {
            if (node.count > defaults::mesh_bvh_leaf_size || node.index != next_triangle) return false;
            for (std::int32_t t = node.index; t < node.index + node.count; ++t)
                for (int c = 0; c < 3; ++c) {
                    const Vec3& p = corners_[3 * static_cast<size_t>(t) + c];
                    for (int k = 0; k < 3; ++k)
                        if (p[k] < node.lower[k] || p[k] > node.upper[k]) return false;
                }
            next_triangle += node.count;
            continue;
        }
        if (node.count != 0 || node.index <= id + 1) return false;
        const std::int32_t left = id + 1, right = node.index;
        if (right >= static_cast<std::int32_t>(nodes_.size())) return false;
        const BvhNode& l = nodes_[static_cast<size_t>(left)];
        const BvhNode& r = nodes_[static_cast<size_t>(right)];
        if (!contains(node, l.lower, l.upper) || !contains(node, r.lower, r.upper)) return false;
        stack.push_back(right);
        stack.push_back(left);
    }
    return next_triangle == n && visited == static_cast<std::int32_t>(nodes_.size());
}

}  // namespace meshcol
