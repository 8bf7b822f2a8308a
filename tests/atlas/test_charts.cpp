#include <catch2/catch.hpp>

#include "atlas/charts.h"

using namespace uvpress;

TEST_CASE("A UV seam splits charts, split normals do not", "[atlas]") {
  // Two triangles sharing the edge (1,2) in space. Vertices 3 and 4 duplicate 1 and 2.
  const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const uint32_t idx[] = {0, 1, 2, 3, 5, 4};
  SECTION("same UVs on the duplicates: one chart (glTF split them for normals only)") {
    const float uv[] = {0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 1, 1};
    Mesh m = atlas::weld_uv_mesh(pos, uv, 6, idx, 6);
    CHECK(m.vertex_count() == 4);
    CHECK(m.uv_count() == 4);
    auto c = atlas::find_charts(m);
    CHECK(c.count == 1);
    CHECK(c.chart_of_triangle == std::vector<uint32_t>{0, 0});
  }
  SECTION("different UVs on the duplicates: a seam, two charts") {
    const float uv[] = {0, 0, 0.4f, 0, 0, 0.4f, 0.6f, 0.6f, 0.6f, 1, 1, 1};
    Mesh m = atlas::weld_uv_mesh(pos, uv, 6, idx, 6);
    CHECK(m.vertex_count() == 4);  // positions still welded: the seam is in UV only
    CHECK(m.uv_count() == 6);
    auto c = atlas::find_charts(m);
    CHECK(c.count == 2);
    CHECK(c.chart_of_triangle == std::vector<uint32_t>{0, 1});
  }
}
