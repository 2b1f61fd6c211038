// The budgeted hull's cut loop (hull_budget.hpp): the polytope of supporting planes kept as
// vertices and the planes through each, so a cut is a clip of the vertices (O(vertices): the
// cut vertices, their edges to kept ones by shared planes, the crossings) instead of a new
// half-space intersection of every plane (the qhull call per trial of
// meshcol/collision/hull.py). The loop's choices are those of hull.py's `_simplify`.
#include "meshcol/hull_budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <numeric>
#include <vector>

#include "meshcol/hull.hpp"

namespace meshcol {

namespace {

// The corner on three planes n . x = d (Cramer's rule by triple products).
Vec3 corner(const Vec3& na, double da, const Vec3& nb, double db, const Vec3& nc, double dc) {
    const Vec3 bc = cross(nb, nc), ca = cross(nc, na), ab = cross(na, nb);
    const double det = dot(na, bc);
    return (da * bc + db * ca + dc * ab) / det;
}

void push_vertex(PlanePolytope& p, const Vec3& v, const int* planes_begin, const int* planes_end) {
    p.vertices.push_back(v);
    p.plane_ids.insert(p.plane_ids.end(), planes_begin, planes_end);
    p.plane_offsets.push_back(static_cast<int>(p.plane_ids.size()));
}

// Whether planes `ids` meet in a line: two of them not parallel (a sine above 1e-9). Two
// vertices on one plane and on a repeat of it (or on two nearly parallel planes) share two
// planes but no edge.
bool spans_line(const std::vector<int>& ids, const std::vector<Vec3>& normals) {
    for (std::size_t i = 0; i < ids.size(); ++i)
        for (std::size_t j = i + 1; j < ids.size(); ++j)
            if (squared_norm(cross(normals[ids[i]], normals[ids[j]])) > 1e-18) return true;
    return false;
}

// Union-find root with path halving.
int root(std::vector<int>& parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

// Merges the vertices of `p` from `first_new` on that lie within `merge_distance` of another
// (one per cluster, the farthest from the centroid of all, the first of equals, with the union
// of the cluster's planes), as meshcol.collision.hull._merge_close does to qhull's output.
void merge_new_vertices(PlanePolytope& p, std::vector<int>& source, std::size_t first_new,
                        double merge_distance) {
    const std::size_t n = p.size();
    const double limit = merge_distance * merge_distance;
    std::vector<int> parent;
    for (std::size_t j = first_new; j < n; ++j) {
        for (std::size_t i = 0; i < j; ++i) {
            if (squared_norm(p.vertices[j] - p.vertices[i]) > limit) continue;
            if (parent.empty()) {
                parent.resize(n);
                std::iota(parent.begin(), parent.end(), 0);
            }
            const int a = root(parent, static_cast<int>(i)), b = root(parent, static_cast<int>(j));
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    }
    if (parent.empty()) return;
    Vec3 centroid;
    for (const Vec3& v : p.vertices) centroid += v;
    centroid = centroid / static_cast<double>(n);
    std::vector<int> best(n, -1);
    std::vector<double> reach(n);
    for (std::size_t i = 0; i < n; ++i) {
        reach[i] = norm(p.vertices[i] - centroid);
        const int r = root(parent, static_cast<int>(i));
        if (best[r] < 0 || reach[i] > reach[best[r]]) best[r] = static_cast<int>(i);
    }
    PlanePolytope merged;
    merged.clear();
    std::vector<int> merged_source, planes;
    for (std::size_t i = 0; i < n; ++i) {
        if (root(parent, static_cast<int>(i)) != static_cast<int>(i)) continue;  // not first
        planes.clear();
        for (std::size_t j = i; j < n; ++j) {
            if (root(parent, static_cast<int>(j)) != static_cast<int>(i)) continue;
            planes.insert(planes.end(), p.plane_ids.begin() + p.plane_offsets[j],
                          p.plane_ids.begin() + p.plane_offsets[j + 1]);
        }
        std::sort(planes.begin(), planes.end());
        planes.erase(std::unique(planes.begin(), planes.end()), planes.end());
        const int keep = best[i];
        push_vertex(merged, p.vertices[keep], planes.data(), planes.data() + planes.size());
        merged_source.push_back(source[keep]);
    }
    p = std::move(merged);
    source = std::move(merged_source);
}

// Exact distances from points to the exact hull over the facets each lies in front of, with
// hull.py's `distances_to_facets` rule (a rounding allowance of 1e-12 of the coordinates'
// magnitude; a point behind every facet is inside: 0).
class FacetSearch {
  public:
    explicit FacetSearch(const BudgetInput& in) : in_(in), row_(in.facet_count) {
        for (long long f = 0; f < 3 * in.facet_count; ++f)
            facet_scale_ = std::max(facet_scale_, max_abs(in.facets[f]));
    }

    void distance(const Vec3& p, double& distance, Vec3& closest) {
        const double scale = std::max(facet_scale_, max_abs(p));
        const double allowance = -1e-12 * std::max(scale, 1e-300);
        bool outside = false;
        for (long long f = 0; f < in_.facet_count; ++f) {
            const double* e = in_.equations + 4 * f;
            const double signed_distance = (p.x * e[0] + p.y * e[1]) + p.z * e[2] + e[3];
            outside = outside || signed_distance > 0.0;
            row_[f] = signed_distance > allowance ? 1 : 0;
        }
        if (!outside) {
            distance = 0.0;
            closest = p;
            return;
        }
        distances_to_facets(&p, 1, in_.facets, in_.facet_count, row_.data(), &distance, &closest);
    }

  private:
    const BudgetInput& in_;
    std::vector<std::uint8_t> row_;
    double facet_scale_ = 0.0;
};

// The `count` farthest vertices, farthest first, the lower index first among equals (numpy's
// stable argsort of the negated distances).
std::vector<int> farthest(const std::vector<double>& distances, int count) {
    std::vector<int> order(distances.size());
    std::iota(order.begin(), order.end(), 0);
    const auto further = [&](int a, int b) {
        return distances[a] > distances[b] || (distances[a] == distances[b] && a < b);
    };
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(count), order.size());
    std::partial_sort(order.begin(), order.begin() + k, order.end(), further);
    order.resize(k);
    return order;
}

}  // namespace

bool tetrahedron_polytope(const Vec3 normals[4], const double offsets[4], PlanePolytope& out) {
    out.clear();
    for (int k = 0; k < 4; ++k) {
        int ids[3], m = 0;
        for (int j = 0; j < 4; ++j)
            if (j != k) ids[m++] = j;
        const Vec3 v = corner(normals[ids[0]], offsets[ids[0]], normals[ids[1]], offsets[ids[1]],
                              normals[ids[2]], offsets[ids[2]]);
        // the corner must be finite and strictly inside the plane it is not on
        if (!is_finite(v) || !(dot(normals[k], v) < offsets[k])) return false;
        push_vertex(out, v, ids, ids + 3);
    }
    return true;
}

// Appends to `out` the crossing of `plane` (signed distances `s`, sides `side`) with each
// edge of `in` from a kept vertex to a cut one (source -1).
static void add_crossings(const PlanePolytope& in, const std::vector<Vec3>& normals, int plane,
                   const std::vector<double>& s, const std::vector<signed char>& side,
                   PlanePolytope& out, std::vector<int>& source) {
    const std::size_t n = in.size();
    const auto planes_of = [&](std::size_t i) {
        return std::make_pair(in.plane_ids.data() + in.plane_offsets[i],
                              in.plane_ids.data() + in.plane_offsets[i + 1]);
    };
    std::vector<int> ids;
    // The kept vertices on each plane of a cut vertex: a cut vertex's edges end there.
    std::vector<int> slot(static_cast<std::size_t>(plane), -1);
    std::vector<std::vector<int>> on_plane;
    for (std::size_t i = 0; i < n; ++i) {
        if (side[i] <= 0) continue;
        const auto [b, e] = planes_of(i);
        for (const int* q = b; q != e; ++q) {
            if (slot[*q] >= 0) continue;
            slot[*q] = static_cast<int>(on_plane.size());
            on_plane.emplace_back();
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (side[i] >= 0) continue;
        const auto [b, e] = planes_of(i);
        for (const int* q = b; q != e; ++q)
            if (slot[*q] >= 0) on_plane[slot[*q]].push_back(static_cast<int>(i));
    }
    std::vector<int> seen(n, -1);
    for (std::size_t r = 0; r < n; ++r) {
        if (side[r] <= 0) continue;
        const auto [rb, re] = planes_of(r);
        for (const int* q = rb; q != re; ++q) {
            for (const int u : on_plane[slot[*q]]) {
                if (seen[u] == static_cast<int>(r)) continue;
                seen[u] = static_cast<int>(r);
                // an edge: the two vertices share two planes at least (the edge's line)
                const auto [ub, ue] = planes_of(static_cast<std::size_t>(u));
                ids.clear();
                std::set_intersection(rb, re, ub, ue, std::back_inserter(ids));
                if (!spans_line(ids, normals)) continue;
                ids.push_back(plane);
                const double t = s[u] / (s[u] - s[r]);
                const Vec3 v = in.vertices[u] + t * (in.vertices[r] - in.vertices[u]);
                push_vertex(out, v, ids.data(), ids.data() + ids.size());
                source.push_back(-1);
            }
        }
    }
}

bool clip_polytope(const PlanePolytope& in, const std::vector<Vec3>& normals, double offset,
                   int plane, double merge_distance, PlanePolytope& out,
                   std::vector<int>& source) {
    const Vec3& normal = normals[static_cast<std::size_t>(plane)];
    const std::size_t n = in.size();
    std::vector<double> s(n);
    // -1 kept, 0 on the plane, 1 cut off. "On" is a rounding error only (kOnPlane of the
    // coordinates' magnitude), not the merge distance: a vertex a little more beyond the plane
    // is cut and its crossings, within the merge distance of it, merge back into one vertex,
    // as qhull's nearly coincident intersections are merged; a vertex a little more inside
    // merges with the crossings next to it and so gains the plane. A band as wide as the merge
    // distance would keep vertices whose crossings lie far along an edge nearly parallel to
    // the plane (qhull has them); none at all would cut an edge lying in the plane at a
    // rounding error, a vertex in its middle (qhull has none).
    constexpr double kOnPlane = 128 * 2.220446049250313e-16;
    double magnitude = std::abs(offset);
    for (const Vec3& v : in.vertices) magnitude = std::max(magnitude, max_abs(v));
    const double band = kOnPlane * magnitude;
    std::vector<signed char> side(n);
    bool any_left = false, any_cut = false;
    for (std::size_t i = 0; i < n; ++i) {
        s[i] = dot(normal, in.vertices[i]) - offset;
        side[i] = s[i] > band ? 1 : (s[i] < -band ? -1 : 0);
        any_left = any_left || side[i] <= 0;
        any_cut = any_cut || side[i] > 0;
    }
    out.clear();
    source.clear();
    if (!any_left) return false;
    const auto planes_of = [&](std::size_t i) {
        return std::make_pair(in.plane_ids.data() + in.plane_offsets[i],
                              in.plane_ids.data() + in.plane_offsets[i + 1]);
    };
    std::vector<int> ids;
    for (std::size_t i = 0; i < n; ++i) {
        if (side[i] > 0) continue;
        const auto [b, e] = planes_of(i);
        ids.assign(b, e);
        if (side[i] == 0) ids.push_back(plane);  // above every id: still ascending
        push_vertex(out, in.vertices[i], ids.data(), ids.data() + ids.size());
        source.push_back(static_cast<int>(i));
    }
    if (!any_cut) return true;
    const std::size_t first_new = out.size();
    add_crossings(in, normals, plane, s, side, out, source);
    merge_new_vertices(out, source, first_new, merge_distance);
    return true;
}

BudgetStatus budget_planes(const BudgetInput& in, std::vector<double>& planes,
                           std::vector<Vec3>& vertices) {
    Vec3 normals[4];
    double offsets[4];
    for (int k = 0; k < 4; ++k) {
        normals[k] = {in.start[4 * k], in.start[4 * k + 1], in.start[4 * k + 2]};
        offsets[k] = in.start[4 * k + 3];
    }
    PlanePolytope polytope, trial;
    if (!tetrahedron_polytope(normals, offsets, polytope)) return BudgetStatus::FAILED;
    std::vector<Vec3> plane_normals(normals, normals + 4);
    planes.insert(planes.end(), in.start, in.start + 16);
    int plane_count = 4;
    FacetSearch search(in);
    std::vector<double> distances(polytope.size()), trial_distances;
    std::vector<Vec3> closest(polytope.size()), trial_closest;
    for (std::size_t i = 0; i < polytope.size(); ++i)
        search.distance(polytope.vertices[i], distances[i], closest[i]);
    std::vector<int> source;
    const long long iterations = 4LL * in.budget + 16;
    for (long long step = 0; step < iterations; ++step) {
        if (in.max_planes >= 0 && plane_count >= in.max_planes) break;
        bool accepted = false;
        for (const int index : farthest(distances, in.candidates)) {
            if (distances[index] <= in.converged_distance) break;
            const Vec3 normal = (polytope.vertices[index] - closest[index]) / distances[index];
            double offset = -INFINITY;
            for (long long k = 0; k < in.hull_vertex_count; ++k)
                offset = std::max(offset, dot(in.hull_vertices[k], normal));
            plane_normals.resize(static_cast<std::size_t>(plane_count));
            plane_normals.push_back(normal);
            if (!clip_polytope(polytope, plane_normals, offset, plane_count, in.merge_distance,
                               trial, source))
                continue;
            if (trial.size() > static_cast<std::size_t>(in.budget)) continue;
            trial_distances.resize(trial.size());
            trial_closest.resize(trial.size());
            for (std::size_t j = 0; j < trial.size(); ++j) {
                if (source[j] >= 0) {
                    trial_distances[j] = distances[source[j]];
                    trial_closest[j] = closest[source[j]];
                } else {
                    search.distance(trial.vertices[j], trial_distances[j], trial_closest[j]);
                }
            }
            std::swap(polytope, trial);
            std::swap(distances, trial_distances);
            std::swap(closest, trial_closest);
            planes.insert(planes.end(), {normal.x, normal.y, normal.z, offset});
            ++plane_count;
            accepted = true;
            break;
        }
        if (!accepted) break;
    }
    vertices.insert(vertices.end(), polytope.vertices.begin(), polytope.vertices.end());
    return BudgetStatus::OK;
}

}  // namespace meshcol
