// The polygon splitter (triangulate.hpp): fans of convex faces, ear clipping of the others,
// holes, reversed winding, and the message of every kind of bad count or index.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "check.hpp"
#include "meshcol/triangulate.hpp"

using namespace meshcol;

namespace {

std::vector<std::int64_t> split(const std::vector<double>& vertices,
                                const std::vector<std::int64_t>& counts,
                                const std::vector<std::int64_t>& indices,
                                const TriangulateOptions& options = {}) {
    const PolygonMesh mesh{vertices.data(), vertices.size() / 3, counts.data(), counts.size(),
                           indices.data(), indices.size()};
    return triangulate_polygons(mesh, options);
}

std::string refusal(const std::vector<std::int64_t>& counts,
                    const std::vector<std::int64_t>& indices) {
    const std::vector<double> triangle{0, 0, 0, 1, 0, 0, 0, 1, 0};
    try {
        split(triangle, counts, indices);
    } catch (const std::invalid_argument& error) {
        return error.what();
    }
    return "";
}

}  // namespace

TEST_CASE("triangulate: a square is fanned, reversed when asked") {
    const std::vector<double> square{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    CHECK(split(square, {4}, {0, 1, 2, 3}) == (std::vector<std::int64_t>{0, 1, 2, 0, 2, 3}));
    TriangulateOptions reverse;
    reverse.reverse = true;
    CHECK(split(square, {4}, {0, 1, 2, 3}, reverse) ==
          (std::vector<std::int64_t>{2, 1, 0, 3, 2, 0}));
}

TEST_CASE("triangulate: a dart is cut from its reflex corner") {
    const std::vector<double> dart{2, 1, 0, 0, 0.3, 0, -2, 1, 0, 0, 0, 0};
    CHECK(split(dart, {4}, {0, 1, 2, 3}) == (std::vector<std::int64_t>{3, 0, 1, 1, 2, 3}));
}

TEST_CASE("triangulate: points, edges and holes give no triangle") {
    const std::vector<double> triangle{0, 0, 0, 1, 0, 0, 0, 1, 0};
    CHECK(split(triangle, {0, 1, 2, 3}, {0, 0, 1, 0, 1, 2}) ==
          (std::vector<std::int64_t>{0, 1, 2}));
    TriangulateOptions holes;
    holes.holes = {3, -1, 99};
    CHECK(split(triangle, {0, 1, 2, 3}, {0, 0, 1, 0, 1, 2}, holes).empty());
}

TEST_CASE("triangulate: bad counts and indices are refused with one message") {
    CHECK(refusal({3, -1}, {0, 1, 2}) == "face 1 has a negative vertex count (-1)");
    CHECK(refusal({3, 3}, {0, 1, 2}) ==
          "face vertex counts add up to 6, but there are 3 face vertex indices");
    const std::int64_t huge = std::int64_t{1} << 62;
    CHECK(refusal({huge, huge, huge, huge}, {0, 1, 2}) ==
          "face vertex counts add up to more than 2^64, but there are 3 face vertex indices");
    CHECK(refusal({3}, {0, 1, 3}) ==
          "face vertex index 3 refers to a point the mesh does not have (3 points)");
    const std::vector<double> triangle{0, 0, 0, 1, 0, 0, 0, 1, 0};
    TriangulateOptions budget;
    budget.max_triangles = 0;
    CHECK_THROWS_AS(split(triangle, {3}, {0, 1, 2}, budget), std::overflow_error);
}
