// eval's yardstick (issue 14): trilinear mip-mapped views on both backends, views larger
// than the engine's limit rendered in tiles, the automatic view resolution and the noise
// floor, and the input curve's monotonicity on the shared assets.
#include <catch2/catch.hpp>

#include "cpu/gmsd.h"
#include "engine.h"
#include "eval/eval.h"
#include "eval/resize.h"
#include "io/asset.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "perceptual/triangle_view.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <cmath>
#include <cstdlib>
#include <random>

using namespace uvpress;

namespace {

// A square (-1..1 in x and y at z = 0) seen by an affine camera that maps it onto the
// whole image (clip w = 1), UVs from 0 to 1.
struct Square {
  std::vector<float> pos = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  std::vector<float> uv = {0, 1, 1, 1, 1, 0, 0, 0};
  std::vector<uint32_t> ix = {0, 1, 2, 0, 2, 3};
  engine::MeshRenderDesc desc(uint32_t size) const {
    engine::MeshRenderDesc d;
    d.width = d.height = size;
    d.cameras = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}};
    d.positions = pos.data(), d.vertex_count = 4, d.indices = ix.data(), d.triangle_count = 2, d.uvs = uv.data();
    return d;
  }
};

// A mip chain whose level l is the constant l / 10: the sampled value is then the level
// of detail over 10, so a render shows the LOD the kernel chose.
std::vector<float> lod_chain(uint32_t w, uint32_t h, uint32_t levels) {
  std::vector<float> t;
  for (uint32_t l = 0; l < levels; ++l) t.insert(t.end(), size_t(std::max(1u, w >> l)) * std::max(1u, h >> l), float(l) / 10);
  return t;
}

// The demo sheet with a `side`^2 texture of independent random grey texels: detail at
// the scale of one texel everywhere.
io::GltfFile noise_asset(uint32_t side, int grid = 4) {
  io::GltfFile f = pipeline::make_demo_asset({grid, 16});
  Image img;
  img.width = img.height = side, img.channels = 3;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < size_t(side) * side; ++i) {
    const float v = u(rng);
    img.pixels.insert(img.pixels.end(), {v, v, v});
  }
  f.image_bytes[0] = io::encode_image(img, "png");
  return f;
}

// The demo sheet (grid x grid quads, a 128^2 texture) as render_mesh takes it: its
// luminance texture and eval's 20 cameras.
struct DemoViews {
  io::GltfFile file;
  io::Asset asset;
  Image tex;
  std::vector<float> y;
  std::vector<std::array<float, 16>> cameras;
  explicit DemoViews(int grid)
      : file(pipeline::make_demo_asset({grid, 128})), asset(io::build_asset(file)),
        tex(io::decode_image(file.image_bytes[0], "demo")), y(luminance_plane(tex)) {
    const auto& p = asset.primitives.at(0);
    cameras = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  }
  engine::MeshRenderDesc desc() const {
    const auto& p = asset.primitives.at(0);
    engine::MeshRenderDesc d;
    d.positions = p.positions.data(), d.vertex_count = p.vertex_count();
    d.indices = p.indices.data(), d.triangle_count = p.triangle_count();
    d.uvs = p.uv_sets[0].uv.data();
    d.texture = y.data(), d.texture_width = tex.width, d.texture_height = tex.height;
    return d;
  }
};

}  // namespace

TEST_CASE("render_mesh trilinear: the level of detail is log2 of the texel footprint, blended between levels",
          "[eval][engine]") {
  auto cpu = engine::make_cpu_engine({});
  const Square sq;
  // A 160-texel texture on a 64-pixel square: 2.5 texels a pixel, lambda = log2 2.5.
  for (const uint32_t side : {160u, 64u, 32u}) {
    auto d = sq.desc(64);
    const uint32_t levels = engine::mip_chain_levels(side, side);
    const auto tex = lod_chain(side, side, levels);
    d.texture = tex.data(), d.texture_width = d.texture_height = side, d.mip_levels = levels;
    const auto r = cpu->render_mesh(d);
    const double want = std::max(0.0, std::log2(side / 64.0)) / 10;  // magnified: level 0
    for (size_t p = 0; p < r.pixels.size(); ++p) {
      REQUIRE(r.coverage[p] != engine::kNoMeshTriangle);
      REQUIRE(r.pixels[p] == Approx(want).margin(1e-5));
    }
  }
  // Perspective: the square tilted away (w grows with y). The LOD per pixel against
  // finite differences of the double-precision pixel -> texel map.
  auto d = sq.desc(96);
  d.cameras = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0.6f, 0, 1.7f}};
  const uint32_t side = 512, levels = engine::mip_chain_levels(side, side);
  const auto tex = lod_chain(side, side, levels);
  d.texture = tex.data(), d.texture_width = d.texture_height = side, d.mip_levels = levels;
  const auto r = cpu->render_mesh(d);
  // Pixel centre (x, y) -> square point: NDC (X, Y) = (px, py) / (0.6 py + 1.7).
  auto texel = [&](double x, double y, double out[2]) {
    const double X = 2 * x / 96 - 1, Y = 1 - 2 * y / 96;
    const double py = 1.7 * Y / (1 - 0.6 * Y), px = X * (0.6 * py + 1.7);
    out[0] = (px + 1) / 2 * side, out[1] = (1 - py) / 2 * side;
  };
  size_t checked = 0;
  for (uint32_t j = 8; j < 88; j += 5)
    for (uint32_t i = 8; i < 88; i += 5) {
      const size_t p = size_t(j) * 96 + i;
      if (r.coverage[p] == engine::kNoMeshTriangle) continue;
      double a[2], b[2], c[2], e[2];
      const double h = 1e-3;
      texel(i + 0.5 + h, j + 0.5, a), texel(i + 0.5 - h, j + 0.5, b), texel(i + 0.5, j + 0.5 + h, c),
          texel(i + 0.5, j + 0.5 - h, e);
      const double rho = std::max(std::hypot(a[0] - b[0], a[1] - b[1]), std::hypot(c[0] - e[0], c[1] - e[1])) / (2 * h);
      const double want = std::clamp(std::log2(rho), 0.0, double(levels - 1)) / 10;
      INFO("pixel " << i << "," << j << " rho " << rho);
      CHECK(r.pixels[p] == Approx(want).margin(2e-3));
      ++checked;
    }
  CHECK(checked > 100);
}

TEST_CASE("render_mesh trilinear: single-texel detail minified averages out, bilinear aliases", "[eval][engine]") {
  auto cpu = engine::make_cpu_engine({});
  const Square sq;
  // A 1-texel checkerboard (mean 0.5), 2.5 texels a pixel.
  const uint32_t side = 160;
  Image img;
  img.width = img.height = side, img.channels = 1;
  for (uint32_t y = 0; y < side; ++y)
    for (uint32_t x = 0; x < side; ++x) img.pixels.push_back(float((x + y) % 2));
  std::vector<float> chain;
  const uint32_t levels = engine::mip_chain_levels(side, side);
  for (const Image& l : eval::mip_chain(img, levels)) chain.insert(chain.end(), l.pixels.begin(), l.pixels.end());
  REQUIRE(chain.size() == engine::mip_chain_texels(side, side, levels));
  auto d = sq.desc(64);
  d.texture = chain.data(), d.texture_width = d.texture_height = side;
  auto spread = [](const auto& px) {
    const auto [lo, hi] = std::minmax_element(px.begin(), px.end());
    return *hi - *lo;
  };
  d.mip_levels = 1;
  const auto bilinear = cpu->render_mesh(d);
  d.mip_levels = levels;
  const auto trilinear = cpu->render_mesh(d);
  CHECK(spread(bilinear.pixels) > 0.2f);  // one sample of 2.5 x 2.5 texels: aliasing
  // Level 1 of a 1-texel checkerboard is mid-grey in linear light: 0.5 linear is 0.735 sRGB.
  for (float v : trilinear.pixels) REQUIRE(v == Approx(0.7354).margin(2e-3));
}

namespace {

// eval's 20 views of a primitive at 96 x 104 pixels (not square, not a multiple of the
// tile), its texture left to the caller.
engine::MeshRenderDesc views_of(const io::Primitive& p, uint32_t channels, bool repeat) {
  engine::MeshRenderDesc d;
  d.width = 96, d.height = 104;
  d.cameras = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  d.positions = p.positions.data(), d.vertex_count = p.vertex_count();
  d.indices = p.indices.data(), d.triangle_count = p.triangle_count();
  d.uvs = p.uv_sets[0].uv.data();
  d.channels = channels, d.repeat = repeat;
  return d;
}

}  // namespace

TEST_CASE("render_mesh: Vulkan (lavapipe, validation on) matches the CPU oracle with trilinear filtering",
          "[eval][engine]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  auto cpu = engine::make_cpu_engine({});
  io::GltfFile file = pipeline::make_demo_asset({16, 256});
  const io::Asset asset = io::build_asset(file);
  const Image tex = io::decode_image(file.image_bytes[0], "demo");
  const auto& p = asset.primitives.at(0);
  for (bool repeat : {false, true})
    for (uint32_t channels : {1u, 3u}) {
      std::vector<float> chain;
      const uint32_t levels = engine::mip_chain_levels(tex.width, tex.height);
      for (const Image& l : eval::mip_chain(tex, levels)) {
        const auto y = luminance_plane(l);
        if (channels == 1) chain.insert(chain.end(), y.begin(), y.end());
        else chain.insert(chain.end(), l.pixels.begin(), l.pixels.end());
      }
      engine::MeshRenderDesc d = views_of(p, channels, repeat);
      d.texture = chain.data(), d.texture_width = tex.width, d.texture_height = tex.height;
      d.mip_levels = levels;
      const auto a = cpu->render_mesh(d), b = vk->render_mesh(d);
      REQUIRE(a.coverage == b.coverage);
      float worst = 0;
      for (size_t k = 0; k < a.pixels.size(); ++k) worst = std::max(worst, std::abs(a.pixels[k] - b.pixels[k]));
      INFO("repeat " << repeat << ", channels " << channels << ": max |cpu - vulkan| = " << worst);
      // The level of detail goes through log2 on both sides (the GPU's is not correctly
      // rounded): values agree to the blend weight's rounding.
      CHECK(worst <= 1e-4f);
    }
  CHECK(vk->validation_errors() == 0);
}

namespace {

// The tile cameras of `views` k x k-tiled views (row-major per view), and fn(t, w) for every
// pixel: its index t in the render of those cameras (T x T a tile) and w in the views laid
// out whole (k T pixels a row).
std::vector<std::array<float, 16>> tile_cameras(const std::vector<std::array<float, 16>>& views, uint32_t k) {
  std::vector<std::array<float, 16>> out;
  for (const auto& m : views)
    for (uint32_t b = 0; b < k; ++b)
      for (uint32_t a = 0; a < k; ++a) out.push_back(eval::tile_camera(m, k, a, b));
  return out;
}
template <class Fn>
void for_each_tile_pixel(size_t views, uint32_t k, uint32_t T, Fn&& fn) {
  for (size_t v = 0; v < views; ++v)
    for (uint32_t b = 0; b < k; ++b)
      for (uint32_t a = 0; a < k; ++a)
        for (uint32_t j = 0; j < T; ++j)
          for (uint32_t i = 0; i < T; ++i)
            fn(((v * k + b) * k + a) * T * T + size_t(j) * T + i,
               v * k * k * T * T + (size_t(b) * T + j) * k * T + size_t(a) * T + i);
}

// check(engine, name) on the CPU backend, then on lavapipe where it starts (else the Vulkan
// half is skipped with a warning), with no validation error.
template <class Check>
void on_cpu_and_lavapipe(Check&& check) {
  auto cpu = engine::make_cpu_engine({});
  check(*cpu, "cpu");
  std::unique_ptr<engine::Engine> vk;
  try {
    vk = test::lavapipe();
  } catch (const engine::EngineError& e) {
    WARN(std::string("no lavapipe, the Vulkan half skipped: ") + e.what());
  }
  if (vk) {
    check(*vk, "lavapipe");
    CHECK(vk->validation_errors() == 0);
  }
}

}  // namespace

TEST_CASE("render_mesh: a view rendered as 2 x 2 tiles is the whole view, triangles past the guard band are clipped",
          "[eval][engine]") {
  auto cpu = engine::make_cpu_engine({});
  const DemoViews demo(2);  // 8 large triangles: most cross tile borders
  const auto& cams = demo.cameras;
  engine::MeshRenderDesc d = demo.desc();
  d.width = d.height = 1024;
  d.cameras = {cams[0], cams[7]};
  const auto whole = cpu->render_mesh(d);
  // 4 x 4 tiles of 256: a triangle spans far more than the guard band (256 px) past a tile.
  const uint32_t k = 4, T = 256;
  d.width = d.height = T;
  d.cameras = tile_cameras({cams[0], cams[7]}, k);
  const auto tiles = cpu->render_mesh(d);
  size_t same = 0, covered = 0, total = 0;
  float worst = 0;
  double sum = 0;
  for_each_tile_pixel(2, k, T, [&](size_t t, size_t w) {
    ++total;
    covered += whole.coverage[w] != engine::kNoMeshTriangle;
    if (tiles.coverage[t] != whole.coverage[w]) return;
    ++same;
    worst = std::max(worst, std::abs(tiles.pixels[t] - whole.pixels[w]));
    sum += std::abs(tiles.pixels[t] - whole.pixels[w]);
  });
  INFO(same << " of " << total << " pixels with the same coverage; value difference worst " << worst << ", mean "
            << sum / double(same));
  CHECK(covered > total / 4);
  // Vertices snap to 1/16 pixel in each frame; the tile frames are whole pixels apart, so
  // only rounding of the shifted matrices can move an edge.
  CHECK(double(same) >= 0.9995 * double(total));
  // A clipped piece's planes are solved over the unsnapped vertices (the whole view's over
  // the snapped ones): texel coordinates differ by a small fraction of a texel.
  CHECK(worst < 0.01f);
  CHECK(sum / double(same) < 1e-4);
}

TEST_CASE("render_mesh: view_tiles lays each view's tiles out whole, the same pixels as the tiles stitched by hand",
          "[eval][engine]") {
  const DemoViews demo(2);
  const auto& cams = demo.cameras;
  engine::MeshRenderDesc d = demo.desc();
  const uint32_t k = 4, T = 256;  // 4 x 4 tiles of a 1024-px view, two views
  d.width = d.height = T;
  d.cameras = tile_cameras({cams[0], cams[7]}, k);
  auto check = [&](engine::Engine& e, const char* name) {
    const auto tiles = e.render_mesh(d);
    engine::MeshRenderDesc w = d;
    w.view_tiles_x = w.view_tiles_y = k;
    const auto whole = e.render_mesh(w);
    REQUIRE(whole.pixels.size() == tiles.pixels.size());
    size_t moved = 0, covered = 0;
    for_each_tile_pixel(2, k, T, [&](size_t t, size_t at) {
      moved += whole.coverage[at] != tiles.coverage[t] || whole.pixels[at] != tiles.pixels[t];
      covered += whole.coverage[at] != engine::kNoMeshTriangle;
    });
    INFO(name << ": " << moved << " pixels differ from the tiles stitched by hand");
    CHECK(moved == 0);
    CHECK(covered > size_t(2) * k * k * T * T / 4);
    // A camera list that is not whole views is refused.
    w.cameras.pop_back();
    CHECK_THROWS_AS(e.render_mesh(w), engine::EngineError);
  };
  on_cpu_and_lavapipe(check);
}

TEST_CASE("render_mesh without coverage: the same pixels, no coverage, tiled or not, one texture or several",
          "[eval][engine]") {
  // eval's unlit scores read only the pixels (MeshRenderDesc::coverage = false).
  const DemoViews demo(2);
  engine::MeshRenderDesc d = demo.desc();
  const uint32_t k = 2, T = 256;
  d.width = d.height = T;
  d.cameras = tile_cameras({demo.cameras[0], demo.cameras[7]}, k);
  d.view_tiles_x = d.view_tiles_y = k;
  auto check = [&](engine::Engine& e, const char* name) {
    INFO(name);
    engine::MeshRenderDesc bare = d;
    bare.coverage = false;
    const auto with = e.render_mesh(d), without = e.render_mesh(bare);
    CHECK(with.coverage.size() == with.pixels.size() / d.channels);
    CHECK(without.coverage.empty());
    CHECK(without.pixels == with.pixels);
    size_t covered = 0;
    for (uint32_t c : with.coverage) covered += c != engine::kNoMeshTriangle;
    CHECK(covered > with.coverage.size() / 4);
    const std::vector<engine::MeshTexture> two = {{d.texture, d.texture_width, d.texture_height, d.mip_levels},
                                                  {d.texture, d.texture_width, d.texture_height, d.mip_levels}};
    engine::MeshRenders many_with, many_without;
    e.render_mesh_textures(d, two, many_with);
    e.render_mesh_textures(bare, two, many_without);
    CHECK(many_without.coverage.empty());
    CHECK(many_without.pixels == many_with.pixels);
    CHECK(many_with.coverage == with.coverage);
  };
  on_cpu_and_lavapipe(check);
}

TEST_CASE("render_mesh halved: each view as GMSD's first step leaves it, bit for bit, tiled or not, odd sides too",
          "[eval][engine]") {
  // eval's unlit scores render their views halved (MeshRenderDesc::halve) and score them
  // as such (ImagePairs::halved): the same 2 x 2 means as gmsd_downsample of the whole
  // render, the same reference magnitudes and the same GMSD.
  const DemoViews demo(2);
  engine::MeshRenderDesc tiled = demo.desc();
  tiled.width = tiled.height = 256;
  tiled.cameras = tile_cameras({demo.cameras[0], demo.cameras[7]}, 2);
  tiled.view_tiles_x = tiled.view_tiles_y = 2;
  tiled.coverage = false;
  engine::MeshRenderDesc odd = demo.desc();  // one render a view, odd sides: zero padding
  odd.width = 301, odd.height = 203;
  odd.cameras = {demo.cameras[0], demo.cameras[7]};
  odd.coverage = false;
  // A second texture, darker: the two renders differ, so their GMSD is not 0.
  std::vector<float> darker(demo.y);
  for (float& v : darker) v *= 0.7f;
  auto check = [&](engine::Engine& e, const char* name) {
    INFO(name);
    for (const engine::MeshRenderDesc* d : {&tiled, &odd}) {
      INFO(d->width << " x " << d->height << " tiles, " << d->view_tiles_x << " x " << d->view_tiles_y << " a view");
      engine::MeshRenderDesc h = *d;
      h.halve = true;
      const std::vector<engine::MeshTexture> two = {{d->texture, d->texture_width, d->texture_height, 1},
                                                    {darker.data(), d->texture_width, d->texture_height, 1}};
      engine::MeshRenders whole, halved;
      e.render_mesh_textures(*d, two, whole);
      e.render_mesh_textures(h, two, halved);
      const uint32_t W = d->view_tiles_x * d->width, H = d->view_tiles_y * d->height, views = 2;
      const size_t n = size_t(W) * H, m = engine::Engine::gmsd_half_size(W, H);
      REQUIRE(whole.pixels.size() == 2 * views * n);
      REQUIRE(halved.pixels.size() == 2 * views * m);
      CHECK(halved.coverage.empty());
      std::vector<float> expect(m);
      size_t differ = 0, lit = 0;
      for (size_t i = 0; i < 2 * views; ++i) {
        engine::cpu::gmsd_downsample(whole.pixels.data() + i * n, W, H, expect.data());
        for (size_t p = 0; p < m; ++p) differ += expect[p] != halved.pixels[i * m + p], lit += expect[p] > 0;
      }
      CHECK(differ == 0);
      CHECK(lit > m / 2);  // the views show the asset
      // Texture 1 scored against texture 0's views, from whole renders and from halved ones.
      std::vector<float> magnitudes(views * m), from_half(views * m);
      e.gmsd_references({W, H, views, whole.pixels.data(), nullptr}, magnitudes.data());
      engine::ImagePairs half_references{W, H, views, halved.pixels.data(), nullptr};
      half_references.halved = true;
      e.gmsd_references(half_references, from_half.data());
      CHECK(from_half == magnitudes);
      engine::ImagePairs from_whole{W, H, views, magnitudes.data(), whole.pixels.data() + views * n};
      engine::ImagePairs from_halved{W, H, views, magnitudes.data(), halved.pixels.data() + views * m};
      from_halved.halved = true;
      const auto a = e.gmsd_against(from_whole), b = e.gmsd_against(from_halved);
      CHECK(a == b);
      CHECK(a[0] > 0.01f);
    }
    // Refused: coverage, several channels, odd sides of tiles laid out as one view.
    engine::MeshRenderDesc bad = tiled;
    bad.halve = true, bad.coverage = true;
    CHECK_THROWS_AS(e.render_mesh(bad), engine::EngineError);
    bad.coverage = false, bad.channels = 3;
    CHECK_THROWS_AS(e.render_mesh(bad), engine::EngineError);
    bad.channels = 1, bad.width = bad.height = 255;
    CHECK_THROWS_AS(e.render_mesh(bad), engine::EngineError);
  };
  on_cpu_and_lavapipe(check);
}

TEST_CASE("eval: auto resolution resolves single-texel detail that 512-px views minify", "[eval]") {
  // A 512^2 texture of single-texel noise on the demo sheet: the 512-px views minify it
  // (1.6 texels a pixel at the median, 3 at the 95th percentile).
  const io::GltfFile file = noise_asset(512);
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.cost_grid = {0.5, 1.0};
  o.artifacts = false;
  const eval::EvalResult automatic = eval::evaluate(file, {}, *cpu, o);
  o.resolution = 512, o.filter = eval::TextureFilter::Bilinear;
  const eval::EvalResult old = eval::evaluate(file, {}, *cpu, o);
  auto gap = [](const eval::EvalResult& r) {
    const auto& c = r.layouts[0].curve;
    return c[0].q - c[1].q;
  };
  const eval::ViewResolution &va = automatic.resolution, &vo = old.resolution;
  INFO("auto: " << va.resolution << " px, texels per pixel " << va.texels_per_pixel << " (median "
                << va.texels_per_pixel_median << "), resolved " << va.resolved_fraction << ", gap " << gap(automatic)
                << ", noise floor " << automatic.noise_floor());
  INFO("bilinear 512: texels per pixel " << vo.texels_per_pixel << " (median " << vo.texels_per_pixel_median
                                         << "), resolved " << vo.resolved_fraction << ", gap " << gap(old)
                                         << ", noise floor " << old.noise_floor());
  CHECK(automatic.to_json()["resolution_mode"] == "auto");
  CHECK(old.to_json()["resolution_mode"] == "fixed");
  CHECK(va.resolution >= 1024);
  CHECK(!va.capped);
  CHECK(va.resolved_fraction >= 0.95);
  CHECK(va.texels_per_pixel <= 1.0);
  CHECK(vo.texels_per_pixel_median > 1.4);  // the old views minify
  CHECK(vo.resolved_fraction < 0.4);
  // Halving the texels of single-texel detail is a loss the resolved views see beyond
  // their noise floor.
  REQUIRE(automatic.noise_floor_measured);
  CHECK(gap(automatic) > 3 * automatic.noise_floor());
}

TEST_CASE("eval: views larger than the engine's limit are tiled and score like one render", "[eval]") {
  // At 1280 px (2 x 2 tiles of 640) against 1024 px (one render): same asset, same
  // texture; q of a resize must be close (views differ only in resolution).
  const io::GltfFile file = pipeline::make_demo_asset({8, 256});
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.cost_grid = {0.25};
  o.artifacts = false;
  o.noise_floor = false;
  o.resolution = 1280;
  const eval::EvalResult tiled = eval::evaluate(file, {}, *cpu, o);
  CHECK(tiled.resolution.resolution == 1280);
  o.resolution = 1024;
  const eval::EvalResult one = eval::evaluate(file, {}, *cpu, o);
  const double a = tiled.layouts[0].curve[0].q, b = one.layouts[0].curve[0].q;
  INFO("q at 1280 (tiled) " << a << ", at 1024 " << b);
  CHECK(a > 0);
  CHECK(a == Approx(b).epsilon(0.25));
}

TEST_CASE("eval: a window camera renders exactly its part of the whole view", "[eval][engine]") {
  // A window neither square nor on a tile grid: pixel (i, j) of its render must be pixel
  // (x0 + i, y0 + j) of the whole view's.
  auto cpu = engine::make_cpu_engine({});
  const DemoViews demo(4);
  const auto& cams = demo.cameras;
  engine::MeshRenderDesc d = demo.desc();
  const uint32_t side = 600, x0 = 137, y0 = 201, w = 250, h = 130;
  d.width = d.height = side;
  d.cameras = {cams[3]};
  const auto whole = cpu->render_mesh(d);
  d.width = w, d.height = h;
  d.cameras = {eval::window_camera(cams[3], side, x0, y0, w, h)};
  const auto window = cpu->render_mesh(d);
  size_t same = 0, covered = 0;
  float worst = 0;
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      const size_t a = size_t(j) * w + i, b = size_t(y0 + j) * side + x0 + i;
      covered += whole.coverage[b] != engine::kNoMeshTriangle;
      if (window.coverage[a] != whole.coverage[b]) continue;
      ++same;
      worst = std::max(worst, std::abs(window.pixels[a] - whole.pixels[b]));
    }
  INFO(same << " of " << w * h << " pixels with the same coverage (" << covered << " covered); worst difference " << worst);
  CHECK(covered > size_t(w) * h / 4);
  CHECK(double(same) >= 0.999 * w * h);
  CHECK(worst < 0.01f);
}

TEST_CASE("eval: where the resolution cap binds, views are cropped to the asset and resolve more for the same pixels",
          "[eval]") {
  // Single-texel noise wants about 1,500-px views; at a cap of 512 the whole views minify
  // it. Cropped to the sheet's screen rectangle, the same pixels resolve it finer.
  const io::GltfFile file = noise_asset(512);
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.cost_grid = {0.5, 1.0};
  o.artifacts = false;
  o.noise_floor = false;
  o.resolution_cap = 512;
  const eval::EvalResult cropped = eval::evaluate(file, {}, *cpu, o);
  o.resolution = 512;  // the whole views at the cap
  const eval::EvalResult whole = eval::evaluate(file, {}, *cpu, o);
  const eval::ViewResolution &vc = cropped.resolution, &vw = whole.resolution;
  auto gap = [](const eval::EvalResult& r) { return r.layouts[0].curve[0].q - r.layouts[0].curve[1].q; };
  INFO("cropped: side " << vc.resolution << ", " << vc.view_pixels << " pixels a view, resolved " << vc.resolved_fraction
                        << ", gap " << gap(cropped));
  INFO("whole at 512: resolved " << vw.resolved_fraction << ", gap " << gap(whole));
  CHECK(vc.cropped);
  CHECK(!vw.cropped);
  CHECK(vc.resolution > 512);
  CHECK(vc.view_pixels <= 512.0 * 512.0);  // no more pixels than the capped whole views
  CHECK(vc.view_pixels > 0.8 * 512.0 * 512.0);  // and the budget spent
  CHECK(vc.resolved_fraction > vw.resolved_fraction + 0.1);
  const auto report = cropped.to_json();
  CHECK(report["resolution_cropped"] == true);
  CHECK(report["view_pixels"].get<double>() == Approx(vc.view_pixels));
  // Halving the texels costs more q where the views resolve them.
  CHECK(gap(cropped) > gap(whole));
}

TEST_CASE("eval: on every shared asset the input curve never rises with c_r beyond the noise floor", "[eval][shared]") {
  const auto dir = test::shared_dir();
  if (!dir) UVPRESS_SKIP("no ../shared: the shared assets are not here");
  auto cpu = engine::make_cpu_engine({});
  size_t assets = 0;
  for (const char* rel : {"Duck/glTF-Binary/Duck.glb", "Fox/glTF/Fox.gltf", "CesiumMilkTruck/glTF/CesiumMilkTruck.gltf",
                          "MultiUVTest/glTF/MultiUVTest.gltf"}) {
    const auto path = *dir / "assets" / rel;
    if (std::string(rel).rfind("CesiumMilkTruck", 0) == 0 && !std::getenv("UVPRESS_SLOW_TESTS")) {
      // 3440-px views cropped to it: about 3 minutes on two cores. Measured monotone (README, Reading q).
      WARN("skipped " << rel << ": its 3440-px views take minutes; UVPRESS_SLOW_TESTS=1 runs it");
      continue;
    }
    if (!std::filesystem::exists(path)) {
      WARN("skipped " << path << ": not found");
      continue;
    }
    const io::GltfFile file = io::load_gltf(path.string());
    eval::EvalOptions o;  // the defaults users run: auto resolution, trilinear, the full grid
    o.artifacts = false;
    const eval::EvalResult r = eval::evaluate(file, {}, *cpu, o);
    REQUIRE(r.noise_floor_measured);
    const double floor = r.noise_floor();
    const auto& c = r.layouts[0].curve;
    INFO(rel << ": " << r.resolution.resolution << " px, resolved " << r.resolution.resolved_fraction
             << ", noise floor " << floor);
    CHECK(r.resolution.resolved_fraction >= 0.95);  // at the default cap, the truck's views rolled and cropped
    for (size_t k = 1; k < c.size(); ++k) {
      const double prev = c[k - 1].q, q = c[k].q;
      INFO("c_r " << c[k - 1].c_r << " -> " << c[k].c_r << ": q " << prev << " -> " << q);
      CHECK(q <= prev + floor);
    }
    ++assets;
  }
  CHECK(assets > 0);
}

namespace {

// NDC (x, y) of `positions` seen by `camera`, turned by `angle` about the view's centre.
std::vector<std::array<double, 2>> ndc_points(const std::vector<float>& positions, const std::array<float, 16>& m,
                                              double angle = 0) {
  std::vector<std::array<double, 2>> out;
  const double c = std::cos(angle), s = std::sin(angle);
  for (size_t v = 0; v < positions.size() / 3; ++v) {
    double h[4];
    for (int row = 0; row < 4; ++row)
      h[row] = double(m[size_t(4 * row)]) * positions[3 * v] + double(m[size_t(4 * row + 1)]) * positions[3 * v + 1] +
               double(m[size_t(4 * row + 2)]) * positions[3 * v + 2] + double(m[size_t(4 * row + 3)]);
    const double x = h[0] / h[3], y = h[1] / h[3];
    out.push_back({c * x - s * y, s * x + c * y});
  }
  return out;
}

double box_area(const std::vector<std::array<double, 2>>& pts) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const auto& p : pts)
    for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], p[size_t(d)]), hi[d] = std::max(hi[d], p[size_t(d)]);
  return (hi[0] - lo[0]) * (hi[1] - lo[1]);
}

// The demo sheet stretched `stretch` times along x: a long strip that eval's oblique views
// see at a slant.
io::GltfFile stretched(io::GltfFile f, float stretch) {
  tinygltf::Model& m = f.model;
  const tinygltf::Accessor& a = m.accessors.at(size_t(m.meshes.at(0).primitives.at(0).attributes.at("POSITION")));
  const tinygltf::BufferView& bv = m.bufferViews.at(size_t(a.bufferView));
  auto* p = reinterpret_cast<float*>(m.buffers.at(size_t(bv.buffer)).data.data() + bv.byteOffset + a.byteOffset);
  for (size_t v = 0; v < a.count; ++v) p[3 * v] *= stretch;
  auto& acc = m.accessors.at(size_t(m.meshes.at(0).primitives.at(0).attributes.at("POSITION")));
  if (!acc.minValues.empty() && !acc.maxValues.empty()) acc.minValues[0] *= stretch, acc.maxValues[0] *= stretch;
  return f;
}

}  // namespace

TEST_CASE("eval: a rolled camera turns the view's image and asset_roll gives the smallest screen rectangle", "[eval]") {
  const io::GltfFile file = stretched(pipeline::make_demo_asset({8, 16}), 6);
  const io::Asset asset = io::build_asset(file);
  const auto& p = asset.primitives.at(0);
  const auto cams = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  size_t slanted = 0;
  for (size_t v = 0; v < cams.size(); ++v) {
    // roll_camera(m, a) projects every point where m's projection turned by a lies.
    const double probe = 0.3;
    const auto turned = ndc_points(p.positions, cams[v], probe), rolled = ndc_points(p.positions, eval::roll_camera(cams[v], probe));
    double worst = 0;
    for (size_t k = 0; k < turned.size(); ++k)
      worst = std::max({worst, std::abs(turned[k][0] - rolled[k][0]), std::abs(turned[k][1] - rolled[k][1])});
    CHECK(worst < 1e-5);
    // The chosen roll's rectangle against every roll by a tenth of a degree (brute force).
    const double roll = eval::asset_roll(p.positions.data(), p.vertex_count(), cams[v]);
    CHECK(std::abs(roll) <= M_PI / 4 + 1e-12);
    const double chosen = box_area(ndc_points(p.positions, cams[v], roll));
    double best = INFINITY;
    for (int k = 0; k < 900; ++k) best = std::min(best, box_area(ndc_points(p.positions, cams[v], k * M_PI / 1800)));
    INFO("view " << v << ": roll " << roll << ", area " << chosen << " (unrolled " << box_area(ndc_points(p.positions, cams[v]))
                 << ", best of 900 rolls " << best << ")");
    CHECK(chosen <= best * (1 + 1e-9));
    slanted += chosen < 0.8 * box_area(ndc_points(p.positions, cams[v]));
  }
  INFO(slanted << " of 20 views hold the strip in under 0.8 of their unrolled rectangle");
  CHECK(slanted >= 4);
  // No rectangle to turn: fewer than three distinct points, a line, a vertex behind the eye.
  const std::array<float, 16> flat = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};  // clip = (x, y, 0, 1)
  const std::vector<float> two = {0.1f, 0.2f, 0, 0.1f, 0.2f, 0, 0.5f, -0.3f, 0};
  const std::vector<float> line = {0, 0, 0, 0.2f, 0.1f, 0, 0.4f, 0.2f, 0, -0.2f, -0.1f, 0};
  CHECK(eval::asset_roll(two.data(), 3, flat) == 0);
  CHECK(eval::asset_roll(line.data(), 4, flat) == 0);
  std::array<float, 16> behind = flat;
  behind[15] = -1;  // clip w < 0 for every point
  const std::vector<float> square = {-0.5f, -0.2f, 0, 0.4f, -0.5f, 0, 0.5f, 0.2f, 0, -0.4f, 0.5f, 0};
  CHECK(eval::asset_roll(square.data(), 4, behind) == 0);
  // A square turned by 0.3 rad comes back upright: the roll undoes the turn.
  std::vector<float> turned;
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
    turned.insert(turned.end(), {float(0.4 * (std::cos(0.3) * x - std::sin(0.3) * y)), float(0.4 * (std::sin(0.3) * x + std::cos(0.3) * y)), 0.0f});
  CHECK(eval::asset_roll(turned.data(), 4, flat) == Approx(-0.3).margin(1e-6));
}

TEST_CASE("eval: where the cap binds the cropped views are rolled to the asset and a slanted strip resolves finer for the same pixels",
          "[eval]") {
  // A strip of single-texel noise wants views wider than a 512 cap. Cropped to axis-aligned
  // rectangles, no side above s_box fits the budget (its windows hold at least the
  // rectangles); rolled to each view's smallest rectangle, a larger one does.
  const io::GltfFile file = stretched(noise_asset(512, 8), 6);
  const io::Asset asset = io::build_asset(file);
  const auto& p = asset.primitives.at(0);
  const auto cams = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  double quarter_areas = 0;  // pixels of the axis-aligned rectangles at a side of 1
  for (const auto& m : cams) quarter_areas += box_area(ndc_points(p.positions, m)) / 4;
  const double budget = double(cams.size()) * 512.0 * 512.0, s_box = std::sqrt(budget / quarter_areas);
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.cost_grid = {1.0};
  o.artifacts = false;
  o.noise_floor = false;
  o.resolution_cap = 512;
  const eval::EvalResult r = eval::evaluate(file, {}, *cpu, o);
  INFO("side " << r.resolution.resolution << " against " << s_box << " for axis-aligned crops; " << r.resolution.view_pixels
               << " pixels a view, resolved " << r.resolution.resolved_fraction);
  CHECK(r.resolution.cropped);
  CHECK(r.resolution.view_pixels <= 512.0 * 512.0);
  CHECK(double(r.resolution.resolution) > 1.1 * s_box);
  CHECK(r.resolution.view_pixels > 0.8 * 512.0 * 512.0);  // the budget spent on windows that hold the strip
}

TEST_CASE("render_mesh_textures: every texture as render_mesh renders it, one rasterization, on both backends",
          "[eval][engine]") {
  // eval scores a layout at ten costs from one rasterization of each view: the CPU backend
  // samples every texture from the largest's texel coordinates, scaled. Against render_mesh
  // with each texture on its own: the largest bit for bit, those of the same aspect to fp32
  // rounding of the coordinates, one whose sides were rounded apart to the level-of-detail
  // offset that costs (engine.h), and a one-level texture (bilinear) too.
  auto cpu = engine::make_cpu_engine({});
  auto cpu1 = engine::make_cpu_engine({false, 0, 1});
  std::unique_ptr<engine::Engine> vk;
  try {
    vk = test::lavapipe();
  } catch (const engine::EngineError& e) {
    WARN(std::string("no lavapipe, the Vulkan half skipped: ") + e.what());
  }
  io::GltfFile file = pipeline::make_demo_asset({16, 256});
  const io::Asset asset = io::build_asset(file);
  const Image full = io::decode_image(file.image_bytes[0], "demo");
  const auto& p = asset.primitives.at(0);
  struct Size {
    uint32_t w, h, levels;  // levels 0: the full chain
  };
  const std::vector<Size> sizes = {{128, 128, 0}, {256, 256, 0}, {64, 64, 0}, {181, 180, 0}, {100, 100, 1}};
  for (bool repeat : {false, true})
    for (uint32_t channels : {1u, 3u}) {
      std::vector<std::vector<float>> chains;
      std::vector<engine::MeshTexture> textures;
      for (const Size& s : sizes) {
        const Image img = eval::resize_lanczos3(full, s.w, s.h, false);
        const uint32_t levels = s.levels ? s.levels : engine::mip_chain_levels(s.w, s.h);
        std::vector<float> chain;
        for (const Image& l : eval::mip_chain(img, levels)) {
          const auto y = luminance_plane(l);
          if (channels == 1) chain.insert(chain.end(), y.begin(), y.end());
          else chain.insert(chain.end(), l.pixels.begin(), l.pixels.end());
        }
        chains.push_back(std::move(chain));
        textures.push_back({chains.back().data(), s.w, s.h, levels});
      }
      engine::MeshRenderDesc d = views_of(p, channels, repeat);
      engine::MeshRenders many;
      cpu->render_mesh_textures(d, textures, many);
      REQUIRE(many.textures == textures.size());
      REQUIRE(many.count == 20);
      const size_t per_texture = size_t(d.width) * d.height * many.count * channels;
      REQUIRE(many.pixels.size() == per_texture * textures.size());
      engine::MeshRenders one_thread;
      cpu1->render_mesh_textures(d, textures, one_thread);
      CHECK(one_thread.pixels == many.pixels);  // the same bits on any thread count
      for (size_t k = 0; k < textures.size(); ++k) {
        d.texture = textures[k].texels, d.texture_width = textures[k].width, d.texture_height = textures[k].height;
        d.mip_levels = textures[k].mip_levels;
        const auto alone = cpu->render_mesh(d);
        REQUIRE(alone.coverage == many.coverage);
        float worst = 0;
        for (size_t i = 0; i < per_texture; ++i)
          worst = std::max(worst, std::abs(alone.pixels[i] - many.pixels[k * per_texture + i]));
        INFO("repeat " << repeat << ", channels " << channels << ", texture " << sizes[k].w << "x" << sizes[k].h
                       << ": max |alone - many| = " << worst);
        if (k == 1) {
          CHECK(worst == 0.0f);  // the largest: the space the views were set up in
        } else if (sizes[k].w != sizes[k].h) {
          // Its level of detail is off by half log2 of its sides' ratios against the
          // largest's; a pixel's value moves by at most that times its two levels' difference.
          const double offset = 0.5 * std::abs(std::log2((181.0 / 256) / (180.0 / 256)));
          CHECK(worst <= offset + 1e-4);
          CHECK(worst > 0.0f);
        } else {
          CHECK(worst <= 1e-4f);
        }
      }
      if (vk) {
        // The Vulkan backend renders each texture with its kernel: within the aspect offset
        // above and the kernel's rounding of CPU's.
        engine::MeshRenders on_vk;
        vk->render_mesh_textures(d, textures, on_vk);
        REQUIRE(on_vk.coverage == many.coverage);
        float worst = 0;
        for (size_t i = 0; i < many.pixels.size(); ++i) worst = std::max(worst, std::abs(on_vk.pixels[i] - many.pixels[i]));
        INFO("vulkan: max |cpu - vulkan| = " << worst);
        CHECK(worst <= 5e-3f);
        CHECK(vk->validation_errors() == 0);
      }
    }
}
