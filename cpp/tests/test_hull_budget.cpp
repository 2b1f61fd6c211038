// The budgeted hull's clip and cut loop (hull_budget.hpp) against known polytopes.
#include <algorithm>
#include <cmath>
#include <vector>

#include "check.hpp"
#include "meshcol/hull_budget.hpp"

using meshcol::PlanePolytope;
using meshcol::Vec3;

namespace {

// The regular tetrahedron of inscribed radius `r` about the origin: normals (1,1,1)/sqrt(3)...
void big_tetrahedron(double r, PlanePolytope& out) {
    const double k = 1.0 / std::sqrt(3.0);
    const Vec3 normals[4] = {{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}};
    const double offsets[4] = {r, r, r, r};
    REQUIRE(meshcol::tetrahedron_polytope(normals, offsets, out));
}

// `p` clipped by the planes n . x <= d of `planes` (n, d), ids from 4 on.
bool clip_all(PlanePolytope& p, const std::vector<std::pair<Vec3, double>>& planes,
              double merge = 1e-11) {
    PlanePolytope next;
    std::vector<int> source;
    const double k = 1.0 / std::sqrt(3.0);
    std::vector<Vec3> normals = {{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}};
    for (const auto& [n, d] : planes) {
        normals.push_back(n);
        const int id = static_cast<int>(normals.size()) - 1;
        if (!meshcol::clip_polytope(p, normals, d, id, merge, next, source)) return false;
        std::swap(p, next);
    }
    return true;
}

std::vector<std::pair<Vec3, double>> unit_cube_planes() {
    return {{{1, 0, 0}, 1}, {{-1, 0, 0}, 1}, {{0, 1, 0}, 1},
            {{0, -1, 0}, 1}, {{0, 0, 1}, 1}, {{0, 0, -1}, 1}};
}

// Every vertex is a corner (+-1, +-1, +-1) to 1e-12 and every corner is a vertex.
void check_cube(const PlanePolytope& p) {
    REQUIRE(p.size() == 8u);
    std::vector<int> seen(8, 0);
    for (const Vec3& v : p.vertices) {
        for (int a = 0; a < 3; ++a) CHECK_NEAR(std::abs(v[a]), 1.0, 1e-12);
        seen[(v.x > 0) + 2 * (v.y > 0) + 4 * (v.z > 0)] += 1;
    }
    for (int c = 0; c < 8; ++c) CHECK(seen[c] == 1);
}

}  // namespace

TEST_CASE("hull budget: a tetrahedron's corners lie on the three planes they name") {
    PlanePolytope p;
    big_tetrahedron(2.0, p);
    REQUIRE(p.size() == 4u);
    const double k = 1.0 / std::sqrt(3.0);
    const Vec3 normals[4] = {{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}};
    for (std::size_t i = 0; i < 4; ++i) {
        REQUIRE(p.plane_offsets[i + 1] - p.plane_offsets[i] == 3);
        for (int j = p.plane_offsets[i]; j < p.plane_offsets[i + 1]; ++j)
            CHECK_NEAR(meshcol::dot(normals[p.plane_ids[j]], p.vertices[i]), 2.0, 1e-12);
    }
}

TEST_CASE("hull budget: six clips of a tetrahedron make the cube, each corner on 3 planes") {
    PlanePolytope p;
    big_tetrahedron(10.0, p);
    REQUIRE(clip_all(p, unit_cube_planes()));
    check_cube(p);
    for (std::size_t i = 0; i < p.size(); ++i) {
        // the corner's three cube planes, the tetrahedron's planes cut away
        CHECK(p.plane_offsets[i + 1] - p.plane_offsets[i] == 3);
        for (int j = p.plane_offsets[i]; j < p.plane_offsets[i + 1]; ++j) CHECK(p.plane_ids[j] >= 4);
    }
}

TEST_CASE("hull budget: a repeated plane and a plane through vertices change nothing") {
    PlanePolytope p;
    big_tetrahedron(10.0, p);
    auto planes = unit_cube_planes();
    planes.push_back({{1, 0, 0}, 1});                           // the same plane again
    planes.push_back({Vec3{1, 1, 0} / std::sqrt(2.0), std::sqrt(2.0)});  // through an edge
    planes.push_back({Vec3{1, 1, 1} / std::sqrt(3.0), std::sqrt(3.0)});  // through a corner
    REQUIRE(clip_all(p, planes));
    check_cube(p);
}

TEST_CASE("hull budget: a cut deeper than the merge distance makes new vertices, a shallower "
          "one does not") {
    PlanePolytope p;
    big_tetrahedron(10.0, p);
    auto planes = unit_cube_planes();
    planes.push_back({Vec3{1, 1, 1} / std::sqrt(3.0), std::sqrt(3.0) - 1e-13});
    REQUIRE(clip_all(p, planes, 1e-11));
    check_cube(p);  // the corner moved 1e-13: its three new vertices merged into one
    PlanePolytope q;
    big_tetrahedron(10.0, q);
    planes.back().second = std::sqrt(3.0) - 0.5;  // cuts the corner (1, 1, 1) off
    REQUIRE(clip_all(q, planes));
    CHECK(q.size() == 10u);  // 7 corners and a triangle
    for (const Vec3& v : q.vertices)
        CHECK(meshcol::dot(Vec3{1, 1, 1}, v) <= 3.0 - 0.5 * std::sqrt(3.0) + 1e-12);
}

TEST_CASE("hull budget: a plane beyond every vertex leaves nothing") {
    PlanePolytope p;
    big_tetrahedron(1.0, p);
    PlanePolytope out;
    std::vector<int> source;
    const double k = 1.0 / std::sqrt(3.0);
    const std::vector<Vec3> normals = {{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}, {1, 0, 0}};
    CHECK(!meshcol::clip_polytope(p, normals, -100.0, 4, 1e-11, out, source));
}

TEST_CASE("hull budget: the loop on a cube's hull keeps within the budget, planes supporting") {
    // the exact hull: the unit cube as 12 triangles
    const Vec3 c[8] = {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1},
                       {-1, -1, 1},  {1, -1, 1},  {-1, 1, 1},  {1, 1, 1}};
    const int tri[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    std::vector<Vec3> facets;
    std::vector<double> equations;
    for (const auto& t : tri) {
        const Vec3 a = c[t[0]], b = c[t[1]], d = c[t[2]];
        Vec3 n = meshcol::cross(b - a, d - a);
        n = n / meshcol::norm(n);
        facets.insert(facets.end(), {a, b, d});
        equations.insert(equations.end(), {n.x, n.y, n.z, -meshcol::dot(n, a)});
    }
    const double k = 1.0 / std::sqrt(3.0);
    const double start[16] = {k, k, k, 3 * k, k, -k, -k, 3 * k, -k, k, -k, 3 * k, -k, -k, k, 3 * k};
    for (int budget : {4, 6, 8, 12}) {
        meshcol::BudgetInput in;
        in.hull_vertices = c;
        in.hull_vertex_count = 8;
        in.facets = facets.data();
        in.equations = equations.data();
        in.facet_count = 12;
        in.start = start;
        in.budget = budget;
        in.converged_distance = 1e-9 * std::sqrt(12.0);
        in.merge_distance = 1e-11 * std::sqrt(12.0);
        std::vector<double> planes;
        std::vector<Vec3> vertices;
        REQUIRE(meshcol::budget_planes(in, planes, vertices) == meshcol::BudgetStatus::OK);
        CHECK(vertices.size() >= 4);
        CHECK(vertices.size() <= static_cast<std::size_t>(budget));
        CHECK(planes.size() % 4 == 0);
        for (std::size_t i = 0; i < planes.size(); i += 4) {
            const Vec3 n{planes[i], planes[i + 1], planes[i + 2]};
            double support = -1e300;
            for (const Vec3& v : c) support = std::max(support, meshcol::dot(n, v));
            CHECK_NEAR(planes[i + 3], support, 1e-12);  // touches the cube, cube inside
            // the polytope returned is the planes' intersection: inside each, on three
            for (const Vec3& v : vertices) CHECK(meshcol::dot(n, v) <= planes[i + 3] + 1e-12);
        }
        for (const Vec3& v : vertices) {
            int on = 0;
            for (std::size_t i = 0; i < planes.size(); i += 4)
                on += std::abs(planes[i] * v.x + planes[i + 1] * v.y + planes[i + 2] * v.z -
                               planes[i + 3]) <= 1e-9;
            CHECK(on >= 3);
        }
    }
}
