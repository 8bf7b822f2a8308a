#include <catch2/catch.hpp>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/mesh_io.h"
#include "support.h"

#include <fstream>

using namespace uvpress;

namespace {

void write_text(const test::fs::path& p, const std::string& text) { std::ofstream(p) << text; }

}  // namespace

TEST_CASE("Shared disk meshes load with the counts SOURCES.md gives", "[io][mesh][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  struct Known {
    const char* file;
    size_t v, f;
    bool uvs;
  };
  for (Known k : {Known{"grid.off", 145, 256, false}, Known{"camelhead.off", 11381, 22704, false},
                  Known{"lilium.obj", 3389, 6590, false}, Known{"camel_b.obj", 2032, 3576, true},
                  Known{"punctured_sphere.obj", 114, 223, false}}) {
    INFO(k.file);
    Mesh m = io::read_mesh((*shared / "meshes" / k.file).string());
    CHECK(m.vertex_count() == k.v);
    CHECK(m.triangle_count() == k.f);
    CHECK(m.has_uvs() == k.uvs);
    if (k.uvs) CHECK(m.uv_count() == 2032);
  }
}

TEST_CASE("OBJ with UVs round-trips through write_obj", "[io][mesh]") {
  test::Scratch dir("obj");
  write_text(dir / "quad.obj",
             "# quad\nmtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n");
  Mesh m = io::read_mesh((dir / "quad.obj").string());
  REQUIRE(m.triangle_count() == 2);  // the quad is fan-split
  REQUIRE(m.has_uvs());
  io::write_obj(m, (dir / "out.obj").string());
  Mesh back = io::read_mesh((dir / "out.obj").string());
  CHECK(back.positions == m.positions);
  CHECK(back.uvs == m.uvs);
  CHECK(back.triangles == m.triangles);
  CHECK(back.uv_triangles == m.uv_triangles);
  // Negative (relative) indices mean the same faces.
  write_text(dir / "rel.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\n");
  CHECK(io::read_mesh((dir / "rel.obj").string()).triangles == std::vector<uint32_t>{0, 1, 2});
}

TEST_CASE("Malformed meshes give InputError naming the reason", "[io][mesh]") {
  test::Scratch dir("badmesh");
  write_text(dir / "range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  CHECK_THROWS_WITH(io::read_mesh((dir / "range.obj").string()), Catch::Contains("out of range"));
  write_text(dir / "nan.obj", "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CHECK_THROWS_WITH(io::read_mesh((dir / "nan.obj").string()), Catch::Contains("non-finite"));
  write_text(dir / "empty.obj", "# nothing\n");
  CHECK_THROWS_WITH(io::read_mesh((dir / "empty.obj").string()), Catch::Contains("no faces"));
  write_text(dir / "short.off", "OFF\n1000 2000 0\n0 0 0\n");
  CHECK_THROWS_WITH(io::read_mesh((dir / "short.off").string()), Catch::Contains("more than the file holds"));
  write_text(dir / "bad.off", "PLY\n");
  CHECK_THROWS_AS(io::read_mesh((dir / "bad.off").string()), InputError);
  CHECK_THROWS_WITH(io::read_mesh((dir / "none.obj").string()), Catch::Contains("not found"));
  write_text(dir / "mesh.stl", "solid");
  CHECK_THROWS_WITH(io::read_mesh((dir / "mesh.stl").string()), Catch::Contains("unsupported"));
}
