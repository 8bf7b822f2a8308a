// q-c curves over 20 dodecahedron views (eval.h). How eval measures:
//
// - Cameras: 20, at the vertices of a regular dodecahedron around the mesh's bounding
//   sphere, looking at its centre, perspective (vertical field of view 30 degrees, the
//   sphere just inside the frame), square images of `resolution` pixels.
// - Resolution (auto, the default): views that resolve the reference texture. Texels per
//   screen pixel are measured per covered pixel of the 20 views at 512 px (isotropic: the
//   square root of a triangle's texel area over its screen area in that view); the side is
//   the smallest multiple of 16, at least 512, at which the `resolution_percentile` (95 %)
//   of the visible screen area is magnified or 1:1, capped at `resolution_cap` (2560: 20
//   reference views of 2560^2 floats are 500 MiB, and every render costs 25x a 512-px
//   one). Where the cap binds, the cap bounds pixels, not the side: each view is rolled
//   about its axis so that the asset's screen rectangle is smallest (the minimum-area
//   rectangle of its projected vertices, asset_roll: an oblique view of a long asset holds
//   it at a slant, and an upright box around it is mostly empty) and cropped to that
//   rectangle (2 pixels around), at the largest side up to the wanted one whose windows
//   hold no more pixels than 20 capped whole views. The roll turns only the pixel grid:
//   the view shows the same. CesiumMilkTruck wants 3440 px: upright crops reached 2944
//   (94 % of the surface resolved) at a 2048 cap and rolled ones 3072 (94 %); at 2560 its
//   rolled crops reach 3440 (95 %) with 5.2 M pixels a view. Cropping drops background
//   pixels from each view's GMSD pool, so it is used only where the cap binds: every other
//   asset's figures stay as they were. Views wider than the engine's 1024-px limit are
//   rendered in tiles (one camera a tile, all tiles of a view one size), which the engine
//   lays out as whole views (MeshRenderDesc::view_tiles_x), or eval stitches where the views
//   of a render differ in their grid.
//   Report: resolution (the whole view's side), resolution_capped (the wanted side was not
//   reached), resolution_cropped, view_pixels (rendered a view, on average),
//   texels_per_pixel (at the percentile and the median, at the chosen side),
//   resolved_fraction (share of the visible screen area magnified or 1:1 there). A fixed
//   --resolution renders whole views and reports the same.
//   At a side that resolves the texture, losing texels shows; at one that minifies it,
//   each pixel takes one sample of several texels and q is mostly aliasing pattern.
// - Renders: engine->render_mesh (CPU backend = oracle, Vulkan kernel render_mesh.comp).
//   Texture filter (`filter`): trilinear by default, as engines sample (the texture's mip
//   chain built as engines build it: box filter in linear light, see resize.h), so that
//   parts of the asset seen from afar are filtered rather than aliased; bilinear samples
//   level 0 only (the paper's renderer). Both in fp32 by hand, both backends alike.
// - Noise floor (report: noise_floor): how far q moves when only the sampling phase
//   does. The input resized to half its texels is scored as usual, again with the cameras
//   and the reference views shifted by a quarter pixel (two directions), and resized to
//   1, 2 and 3 texels more a side (the texel grid's phase; under 2 % more texels); the
//   largest change.
//   Differences in q below it are sampling phase, not texture, and are not claimed.
// - Reference: the input (first file) layout with its full texture, luminance.
// - Layouts: "input" (the reference's own UVs), with `paper_baseline` "input-rebaked" (the
//   same UVs, re-baked like every other layout: the paper's protocol, so figures can be set
//   beside the paper's), every other file (a glTF of the same mesh: reparam's output, an
//   xatlas or Blender layout), and with `flatten` the isometric layout ("flatten": charts
//   from the input's UV seams flattened by host/flatten's progressive solver, charts that
//   are not disks keep their input UVs scaled to their 3-D area, laid out on shelves at one
//   scale).
// - Each layout's full texture: the input's own; for every other layout, the reference
//   texture re-baked into its UVs (atlas::rebake) at the size where c_r = 1, when its triangles
//   correspond one to one with the reference's (same count, same corner positions);
//   otherwise the file's own texture.
// - Cost: image texels, what users pay for (every texel of the image in VRAM and on the
//   wire): c_r = W H / (W_ref H_ref), the reference's driving image. Each curve point also
//   carries the paper's c_r_chart (eq. 20-21: W H sum|uv triangle area|, texels under the
//   charts, relative to the reference's), which cannot see packing. For each c_r of the
//   grid the layout's texture keeps its aspect with W H = c_r W_ref H_ref (rounded).
// - Resize to that size: the input's texture as users' tools resize it, Lanczos-3
//   (resize.h), in stored sRGB values and in linear light, both evaluated, the one with the
//   lower mean log q over the grid kept (report: input_resize), so the baseline is the
//   strongest a user gets in one line; every other layout's full texture with that same
//   resize, so that curves differ by layout and not by filter (only "input-rebaked", the
//   paper's protocol, keeps the exact area (box) filter, bilinear when enlarging). Then the 20 views
//   are rendered and q = mean GMSD against the reference views (eq. 22-23), by
//   Engine::gmsd (any size).
// - As written: every other file is also scored with its own texture at its real size and
//   its own sampler (what a user would see), beside its curve (report: as_written).
// - Savings: for a layout A against B, the ratio c_A(q) / c_B(q) of the costs at which the
//   two curves reach the same q, log-log interpolated, geometric mean over B's curve
//   points inside A's q range.
// - Codec (`codec`, `--codec astc-6x6`): the textures the curves and the as-written scores
//   sample are first compressed and decoded again, every mip level on its own (the chain
//   built from the uncompressed level 0, then each level compressed, as a texture farm
//   does), sRGB profile (the driving texture is a colour texture): q after the codec, so
//   that curves compare at equal compressed bytes (with one codec, bytes go with texels;
//   each curve point carries `codec_bytes`, its levels' blocks). The reference views and
//   the noise floor stay uncompressed. Lit: data maps (normal, occlusion, metallic-roughness)
//   go through astcenc's linear profile, colour maps through sRGB.
// - Cost axis (`cost_axis`, `--cost-axis bytes`): the savings compare costs in bytes
//   instead of image texels. Every curve point's driving texture (as the views sample it:
//   its colour, or its grey when the reference image is grey; an alpha channel is not
//   counted) is encoded as the reference's driving image is (io::encode_settings_of: PNG,
//   paletted or not, or JPEG at its estimated quality and subsampling), with the strongest
//   encoder, and its bytes relative to the reference image's bytes in the file are the
//   cost (`bytes`, `bytes_ratio`); an as-written file counts its own image's bytes. A PNG's
//   bytes follow its content, not its texels (flat art halved costs more than half), so
//   the two axes can rank layouts differently, and a curve's bytes need not grow with its
//   texels: the savings read each curve's cheapest points (LayoutResult::cost_q). Not with
//   a codec, whose fixed-rate blocks go with texels.
// - Shading (`shading`, report: shading "unlit" | "lit", shading_requested, and
//   shading_warning when auto fell back): unlit, q reads the driving texture's luminance;
//   lit (lit.h), q reads the luminance of the views lit by a fixed rig through the asset's
//   normal, occlusion / metallic-roughness and emissive maps, so that losing those maps'
//   detail shows. Lit layouts are every map sharing the driving texture's UVs: at each c_r
//   every map is resized by the same factor as the driving texture (colour maps by the
//   input's resize, data maps by the same filter on their stored values), re-baked layouts
//   re-bake every map (normal maps rotated into the new UV frame where tangents come from
//   the UVs). Missing maps take glTF's defaults. auto (the default): lit when a material of
//   the reference has a normalTexture, else unlit, so assets without normal maps keep
//   their figures bit for bit. When lit, every curve point and as_written carries q (the
//   lit q), q_unlit and q_lit, and the report noise_floor_unlit and noise_floor_lit beside
//   noise_floor (the lit one); the savings and the as-written scores (reparam's guard) use q.
#include "eval.h"

#include "core/error.h"
#include "core/stopwatch.h"
#include "io/image_io.h"
#include "layout.h"
#include "lit.h"
#include "resize.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace uvpress::eval {

using detail::LayoutMesh;
using detail::MaterialMap;

std::vector<std::array<float, 16>> dodecahedron_cameras(const float* p, size_t n, double fov_degrees) {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t v = 0; v < n; ++v)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], double(p[3 * v + size_t(d)])), hi[d] = std::max(hi[d], double(p[3 * v + size_t(d)]));
  double c[3], radius = 0;
  for (int d = 0; d < 3; ++d) c[d] = n ? 0.5 * (lo[d] + hi[d]) : 0.0;
  for (size_t v = 0; v < n; ++v) {
    double r2 = 0;
    for (int d = 0; d < 3; ++d) r2 += (p[3 * v + size_t(d)] - c[d]) * (p[3 * v + size_t(d)] - c[d]);
    radius = std::max(radius, std::sqrt(r2));
  }
  if (!(radius > 0)) radius = 1;
  const double half = 0.5 * fov_degrees * M_PI / 180.0;
  const double dist = 1.02 * radius / std::sin(half);  // the sphere just inside the frame
  const double near = 0.5 * (dist - radius), far = dist + 2 * radius, fy = 1 / std::tan(half);
  // The 20 vertices of a regular dodecahedron: (+-1, +-1, +-1), (0, +-1/phi, +-phi),
  // (+-1/phi, +-phi, 0), (+-phi, 0, +-1/phi).
  const double phi = (1 + std::sqrt(5.0)) / 2, ip = 1 / phi;
  std::vector<std::array<double, 3>> dirs;
  for (int a : {-1, 1})
    for (int b : {-1, 1})
      for (int e : {-1, 1}) dirs.push_back({double(a), double(b), double(e)});
  for (int a : {-1, 1})
    for (int b : {-1, 1}) {
      dirs.push_back({0, a * ip, b * phi});
      dirs.push_back({a * ip, b * phi, 0});
      dirs.push_back({a * phi, 0, b * ip});
    }
  std::vector<std::array<float, 16>> out;
  for (auto dir : dirs) {
    const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double eye[3], f[3], up[3] = {0, 1, 0}, r[3], u[3];
    for (int d = 0; d < 3; ++d) f[d] = -dir[size_t(d)] / len, eye[d] = c[d] - dist * f[d];
    if (std::abs(f[1]) > 0.99) up[1] = 0, up[2] = 1;
    r[0] = f[1] * up[2] - f[2] * up[1], r[1] = f[2] * up[0] - f[0] * up[2], r[2] = f[0] * up[1] - f[1] * up[0];
    const double rl = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (double& x : r) x /= rl;
    u[0] = r[1] * f[2] - r[2] * f[1], u[1] = r[2] * f[0] - r[0] * f[2], u[2] = r[0] * f[1] - r[1] * f[0];
    // View rows (right, up, -forward), then the OpenGL perspective projection.
    double V[4][4] = {{r[0], r[1], r[2], 0}, {u[0], u[1], u[2], 0}, {-f[0], -f[1], -f[2], 0}, {0, 0, 0, 1}};
    for (int row = 0; row < 3; ++row) V[row][3] = -(V[row][0] * eye[0] + V[row][1] * eye[1] + V[row][2] * eye[2]);
    const double P[4][4] = {{fy, 0, 0, 0},
                            {0, fy, 0, 0},
                            {0, 0, (far + near) / (near - far), 2 * far * near / (near - far)},
                            {0, 0, -1, 0}};
    std::array<float, 16> m{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += P[i][k] * V[k][j];
        m[size_t(4 * i + j)] = float(s);
      }
    out.push_back(m);
  }
  return out;
}

const char* to_string(TextureFilter filter) {
  return filter == TextureFilter::Trilinear ? "trilinear" : "bilinear";
}

std::optional<TextureFilter> parse_texture_filter(std::string_view text) {
  if (text == "trilinear") return TextureFilter::Trilinear;
  if (text == "bilinear") return TextureFilter::Bilinear;
  return std::nullopt;
}

std::optional<CostAxis> parse_cost_axis(std::string_view text) {
  if (text == "texels") return CostAxis::Texels;
  if (text == "bytes") return CostAxis::Bytes;
  return std::nullopt;
}

std::array<float, 16> window_camera(const std::array<float, 16>& m, double side, double x0, double y0, double w,
                                    double h) {
  // NDC x' = (side / w) x + (side - 2 x0) / w - 1, y' = (side / h) y + 1 - (side - 2 y0) / h:
  // rows 0 and 1 rescaled and shifted by row 3 (clip w).
  std::array<float, 16> t = m;
  const double kx = side / w, ky = side / h, sx = (side - 2.0 * x0) / w - 1.0, sy = 1.0 - (side - 2.0 * y0) / h;
  for (int c = 0; c < 4; ++c) {
    t[size_t(c)] = float(kx * double(m[size_t(c)]) + sx * double(m[size_t(12 + c)]));
    t[size_t(4 + c)] = float(ky * double(m[size_t(4 + c)]) + sy * double(m[size_t(12 + c)]));
  }
  return t;
}

std::array<float, 16> roll_camera(const std::array<float, 16>& m, double angle) {
  // Rows 0 and 1 (clip x, y) rotated; clip w, so the perspective divide, is unchanged.
  std::array<float, 16> t = m;
  const double c = std::cos(angle), s = std::sin(angle);
  for (int k = 0; k < 4; ++k) {
    const double x = m[size_t(k)], y = m[size_t(4 + k)];
    t[size_t(k)] = float(c * x - s * y);
    t[size_t(4 + k)] = float(s * x + c * y);
  }
  return t;
}

double asset_roll(const float* p, size_t n, const std::array<float, 16>& m) {
  using P = std::array<double, 2>;
  std::vector<P> pts;
  pts.reserve(n);
  for (size_t v = 0; v < n; ++v) {
    const auto c = clip_of(m, p + 3 * v);
    if (!(c[3] > 0)) return 0;
    pts.push_back({c[0] / c[3], c[1] / c[3]});
  }
  // Convex hull, Andrew's monotone chain (counter-clockwise, collinear points dropped).
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return 0;
  auto cross = [](const P& o, const P& a, const P& b) { return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]); };
  std::vector<P> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  if (hull.size() < 3) return 0;
  // Each hull edge as a side of the rectangle (the hull is small: a quadratic scan). The
  // first smallest wins, so the choice is the same on every run.
  double best_area = INFINITY, best_angle = 0;
  for (size_t e = 0; e < hull.size(); ++e) {
    const P& a = hull[e];
    const P& b = hull[(e + 1) % hull.size()];
    const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
    if (!(len > 0)) continue;
    const double dx = (b[0] - a[0]) / len, dy = (b[1] - a[1]) / len;
    double lo_d = INFINITY, hi_d = -INFINITY, lo_n = INFINITY, hi_n = -INFINITY;
    for (const P& q : hull) {
      const double d = q[0] * dx + q[1] * dy, nn = q[1] * dx - q[0] * dy;
      lo_d = std::min(lo_d, d), hi_d = std::max(hi_d, d), lo_n = std::min(lo_n, nn), hi_n = std::max(hi_n, nn);
    }
    const double area = (hi_d - lo_d) * (hi_n - lo_n);
    if (area < best_area) best_area = area, best_angle = -std::atan2(dy, dx);
  }
  // A quarter turn gives the same rectangle: the smallest roll of the four.
  const double quarter = M_PI / 2;
  best_angle -= std::round(best_angle / quarter) * quarter;
  if (best_angle <= -M_PI / 4) best_angle += quarter;
  return best_angle;
}

std::array<float, 16> tile_camera(const std::array<float, 16>& m, uint32_t k, uint32_t a, uint32_t b) {
  return window_camera(m, k, a, b, 1, 1);
}

Savings pixel_ratio_at_equal_q(const std::vector<std::pair<double, double>>& a,
                               const std::vector<std::pair<double, double>>& b, double noise_floor) {
  constexpr double kFloor = 1e-9;  // q = 0 (a perfect copy) has no logarithm
  // A's curve made non-increasing (its lower envelope from the left): cost at which A
  // first reaches q, log-log interpolated.
  std::vector<std::pair<double, double>> env;
  for (auto [c, q] : a) {
    q = std::max(q, kFloor);
    if (env.empty() || q < env.back().second) env.push_back({c, q});
  }
  Savings s;
  if (env.empty()) return s;
  const double q_hi = env.front().second, q_lo = env.back().second;
  double log_sum = 0;
  // A's q at cost c (log-log between its points; none outside its cost range).
  auto q_of_a = [&](double c) {
    for (size_t i = 1; i < a.size(); ++i)
      if (a[i - 1].first <= c && c <= a[i].first && a[i].first > a[i - 1].first) {
        const double t = std::log(c / a[i - 1].first) / std::log(a[i].first / a[i - 1].first);
        return std::exp(std::log(std::max(a[i - 1].second, kFloor)) * (1 - t) + std::log(std::max(a[i].second, kFloor)) * t);
      }
    return std::numeric_limits<double>::quiet_NaN();
  };
  for (auto [cb, qb] : b) {
    if (!(qb > kFloor) || qb > q_hi || qb < q_lo) continue;
    if (s.points == 0) s.q_lo = s.q_hi = qb;
    s.q_lo = std::min(s.q_lo, qb), s.q_hi = std::max(s.q_hi, qb);
    ++s.points;
    if (noise_floor > 0 && std::abs(q_of_a(cb) - qb) <= noise_floor) {  // NaN compares false
      ++s.ties;
      continue;  // log ratio 0
    }
    double ca = env.front().first;
    for (size_t i = 1; i < env.size(); ++i)
      if (env[i].second <= qb) {
        const double t = (std::log(env[i - 1].second) - std::log(qb)) / (std::log(env[i - 1].second) - std::log(env[i].second));
        ca = std::exp(std::log(env[i - 1].first) + t * (std::log(env[i].first) - std::log(env[i - 1].first)));
        break;
      }
    log_sum += std::log(ca / cb);
  }
  s.ratio = s.points ? std::exp(log_sum / double(s.points)) : std::numeric_limits<double>::quiet_NaN();
  return s;
}


namespace {

struct Timing {
  double textures = 0, render = 0, gmsd = 0, shading = 0;  // shading: lit views on the host
};

// A texture as the engine samples it: every level of its mip chain (one level when
// bilinear), `channels` floats a texel, level after level.
struct Texture {
  std::vector<float> texels;
  uint32_t width = 0, height = 0, levels = 1, channels = 1;
};

// `image` as eval's views sample it: its luminance (GMSD step 1 on the stored values),
// or with rgb its colour; with the trilinear filter the luminance of each level of the
// chain an engine would build (mip_chain: box in linear light), as a viewer sees it.
// With `codec`, each level is compressed and decoded again first (EvalOptions::codec).
// colour = false: a data texture (lit shading's normal and ORM maps), its chain boxed and
// its codec run on the stored values (astcenc's linear profile).
Texture view_texture(const Image& image, TextureFilter filter, bool rgb = false, const io::AstcOptions* codec = nullptr,
                     bool colour = true) {
  Texture t;
  t.width = image.width, t.height = image.height, t.channels = rgb ? 3 : 1;
  t.levels = filter == TextureFilter::Trilinear ? engine::mip_chain_levels(image.width, image.height) : 1;
  std::optional<io::AstcCodec> astc;
  if (codec) astc.emplace(colour, *codec);
  std::vector<Image> chain = mip_chain(image, t.levels, colour);
  size_t total = 0;
  for (const Image& level : chain) total += size_t(level.width) * level.height * t.channels;
  t.texels.reserve(total);
  for (Image& level : chain) {
    if (astc) {
      const auto blocks = astc->compress(level);
      level = astc->decompress(blocks.data(), blocks.size(), level.width, level.height, level.channels);
    }
    if (rgb) {
      for (size_t i = 0; i < size_t(level.width) * level.height; ++i)
        for (uint32_t c = 0; c < 3; ++c) t.texels.push_back(level.pixels[i * level.channels + std::min(c, level.channels - 1)]);
    } else {
      const auto y = luminance_plane(level);
      t.texels.insert(t.texels.end(), y.begin(), y.end());
    }
  }
  return t;
}

// Views are rendered in tiles of at most the engine's side, in chunks of whole views of
// about this many pixels, so that an evaluation at the cap never holds more than a few
// views at once beside the reference's.
constexpr size_t kChunkPixels = size_t(20) * 1024 * 1024;

uint32_t tiles_per_side(uint32_t res) { return (res + engine::kMeshRenderMaxSide - 1) / engine::kMeshRenderMaxSide; }

// One view as rendered: the window of its camera's side x side pixels that is rendered (the
// whole view, or where the resolution cap binds the asset's screen rectangle: eval.cpp,
// "Resolution"), cut into tiles_x x tiles_y tiles of equal size within the engine's limit,
// and where its pixels start among all the views' (views follow each other, each row-major).
struct ViewFrame {
  std::array<float, 16> camera;  // the whole view's
  uint32_t side = 0;             // the whole view's pixels a side
  bool cropped = false;          // false: the window is the whole view
  uint32_t x0 = 0, y0 = 0;       // the window's top-left pixel in the whole view
  uint32_t width = 0, height = 0, tiles_x = 1, tiles_y = 1;
  size_t offset = 0;  // pixels of the views before this one
  size_t pixels() const { return size_t(width) * height; }
  uint32_t tile_width() const { return width / tiles_x; }
  uint32_t tile_height() const { return height / tiles_y; }
  // The camera of tile (a, b), a from the left, b from the top.
  std::array<float, 16> tile(uint32_t a, uint32_t b) const {
    if (!cropped) return tiles_x == 1 ? camera : tile_camera(camera, tiles_x, a, b);
    return window_camera(camera, side, double(x0) + double(a) * tile_width(), double(y0) + double(b) * tile_height(),
                         tile_width(), tile_height());
  }
  // The camera of the whole window (pixel (i, j) of the view's image).
  std::array<float, 16> window() const { return cropped ? window_camera(camera, side, x0, y0, width, height) : camera; }
};

// Every camera's whole view, res x res, k x k tiles.
std::vector<ViewFrame> square_frames(const std::vector<std::array<float, 16>>& cameras, uint32_t res) {
  std::vector<ViewFrame> frames(cameras.size());
  const uint32_t k = tiles_per_side(res);
  for (size_t v = 0; v < cameras.size(); ++v) {
    ViewFrame& f = frames[v];
    f.camera = cameras[v], f.side = res, f.width = f.height = res, f.tiles_x = f.tiles_y = k;
    f.offset = v * size_t(res) * res;
  }
  return frames;
}

size_t total_pixels(const std::vector<ViewFrame>& frames) {
  return frames.empty() ? 0 : frames.back().offset + frames.back().pixels();
}

// The storage a chain of renders reuses: the engine's result and the views stitched from its
// tiles. Allocated afresh for every chunk, these buffers (up to kChunkPixels a chunk) cost
// about half of eval's time in page faults and zeroing (Duck on the CPU backend), more than
// the rasterization; an evaluation keeps one per level of nesting (Setup).
struct RenderScratch {
  engine::MeshRenders renders;
  engine::UninitializedVector<float> pixels;  // stitched views: every pixel written (or assigned 0)
  engine::UninitializedVector<uint32_t> coverage;

  // Room for n elements in v, whose contents are not kept. A vector that grows copies
  // itself into fresh pages, and on these VMs a page's first touch costs about 40 times a
  // later write (1 GiB: 1.5-1.9 s to touch in huge pages, 0.05 s to set again): freed
  // first, then at least twice the old room (untouched room costs nothing), so that
  // renders of a few sizes settle in one buffer.
  template <class V>
  static void hold(V& v, size_t n) {
    if (v.capacity() >= n) return;
    const size_t room = std::max(n, 2 * v.capacity());
    v.clear(), v.shrink_to_fit();
    v.reserve(room);
  }
};

// Renders every view of `m` once per texture of `textures`, chunk by chunk: fn(first view,
// views, texture, pixels, coverage, halved) with the `views` views' images (each width x
// height x channels, one after the other) and their covered triangles, in `scratch` (valid
// until the next render into it). Chunks hold views of one tile size, at most `per_chunk`
// of them (0: about kChunkPixels for all the textures together). One texture is
// Engine::render_mesh; several, Engine::render_mesh_textures (each view rasterized once).
// Without `coverage` the renders have none (MeshRenderDesc::coverage) and fn is given null.
// With `halve` (one channel, no coverage: renders only scored), chunks whose views need no
// stitching are rendered halved (MeshRenderDesc::halve: each view (width + 1) / 2 x
// (height + 1) / 2) and fn is told so (halved = true); the others come whole.
template <class Fn>
void render_views(engine::Engine& engine, const LayoutMesh& m, const std::vector<const Texture*>& textures,
                  const std::vector<ViewFrame>& frames, Timing& timing, RenderScratch& scratch, Fn&& fn,
                  size_t per_chunk = 0, bool coverage = false, bool halve = false) {
  const uint32_t C = textures.front()->channels;
  const size_t K = textures.size();
  engine::MeshRenderDesc d;
  d.positions = m.positions.data(), d.vertex_count = m.positions.size() / 3;
  d.indices = m.indices.data(), d.triangle_count = m.indices.size() / 3;
  d.uvs = m.uvs.data();
  const Texture& t0 = *textures.front();
  d.texture = t0.texels.data(), d.texture_width = t0.width, d.texture_height = t0.height;
  d.channels = C, d.mip_levels = t0.levels;
  d.repeat = m.repeat;
  d.coverage = coverage;
  std::vector<engine::MeshTexture> mesh_textures;
  for (const Texture* t : textures) mesh_textures.push_back({t->texels.data(), t->width, t->height, t->levels});
  engine::MeshRenders& r = scratch.renders;
  auto& stitched = scratch.pixels;
  auto& stitched_coverage = scratch.coverage;
  // The chunks (first view, views) first, so that the storage is sized once for the largest:
  // a buffer that grows is copied into fresh pages, each touched for the first time.
  std::vector<std::pair<size_t, size_t>> chunks;
  size_t most = 0;  // rendered pixels of the largest chunk, a texture
  for (size_t first = 0; first < frames.size();) {
    const ViewFrame& f0 = frames[first];
    const size_t limit = per_chunk ? per_chunk : std::max<size_t>(1, kChunkPixels / (f0.pixels() * K));
    size_t views = 1;
    while (first + views < frames.size() && views < limit && frames[first + views].tile_width() == f0.tile_width() &&
           frames[first + views].tile_height() == f0.tile_height())
      ++views;
    size_t pixels = 0;
    for (size_t v = first; v < first + views; ++v)
      pixels += size_t(f0.tile_width()) * f0.tile_height() * frames[v].tiles_x * frames[v].tiles_y;
    chunks.emplace_back(first, views);
    most = std::max(most, pixels);
    first += views;
  }
  scratch.hold(r.pixels, most * C * K);
  if (coverage) scratch.hold(r.coverage, most);
  for (const auto& [first, views] : chunks) {
    const ViewFrame& f0 = frames[first];
    d.width = f0.tile_width(), d.height = f0.tile_height();
    d.cameras.clear();
    bool tiled = false;
    // Tiles that cover each view exactly, the same grid for every view of the chunk: the
    // engine lays them out as whole views itself (MeshRenderDesc::view_tiles_x), else they
    // are stitched below.
    bool in_place = true;
    for (size_t v = first; v < first + views; ++v) {
      const ViewFrame& f = frames[v];
      tiled = tiled || f.tiles_x * f.tiles_y > 1;
      in_place = in_place && f.tiles_x == f0.tiles_x && f.tiles_y == f0.tiles_y &&
                 f.tiles_x * f.tile_width() == f.width && f.tiles_y * f.tile_height() == f.height;
      for (uint32_t b = 0; b < f.tiles_y; ++b)
        for (uint32_t a = 0; a < f.tiles_x; ++a) d.cameras.push_back(f.tile(a, b));
    }
    in_place = in_place && tiled;
    d.view_tiles_x = in_place ? f0.tiles_x : 1, d.view_tiles_y = in_place ? f0.tiles_y : 1;
    // Halved where no view is stitched (tiled views: even tile sides, their 2 x 2 blocks the
    // view's). Views of a chunk are alike in size then.
    d.halve = halve && C == 1 && !coverage && (!tiled || (in_place && d.width % 2 == 0 && d.height % 2 == 0));
    const Stopwatch t_render;
    if (K == 1)
      engine.render_mesh(d, r);
    else
      engine.render_mesh_textures(d, mesh_textures, r);
    timing.render += t_render.seconds();
    const size_t T = size_t(d.width) * d.height, rendered = T * d.cameras.size();  // pixels a texture
    if (d.halve) {
      const size_t half = views * engine::Engine::gmsd_half_size(f0.width, f0.height);  // a texture's
      for (size_t k = 0; k < K; ++k) fn(first, views, k, r.pixels.data() + k * half, nullptr, true);
      continue;
    }
    if (!tiled || in_place) {
      for (size_t k = 0; k < K; ++k)
        fn(first, views, k, r.pixels.data() + k * rendered * C, coverage ? r.coverage.data() : nullptr, false);
      continue;
    }
    const size_t base = f0.offset;
    const size_t chunk = frames[first + views - 1].offset + frames[first + views - 1].pixels() - base;
    // Tiles cover a view whose sides they divide; the pixels past the last tile of any other
    // view are empty.
    bool covered = true;
    for (size_t v = first; v < first + views; ++v)
      covered = covered && frames[v].tiles_x * frames[v].tile_width() == frames[v].width &&
                frames[v].tiles_y * frames[v].tile_height() == frames[v].height;
    if (covered) {
      stitched.resize(chunk * C), stitched_coverage.resize(coverage ? chunk : 0);
    } else {
      stitched.assign(chunk * C, 0.0f);
      stitched_coverage.assign(coverage ? chunk : 0, engine::kNoMeshTriangle);
    }
    // Each tile's rows copied into place, tiles spread over the threads (disjoint rows of
    // the stitched views): a copy of every pixel that Fox's 2 x 2-tiled views made the
    // largest serial step of reparam's scoring.
    struct Placed {
      size_t view;
      uint32_t a, b;
    };
    std::vector<Placed> placed;
    for (size_t v = first; v < first + views; ++v)
      for (uint32_t b = 0; b < frames[v].tiles_y; ++b)
        for (uint32_t a = 0; a < frames[v].tiles_x; ++a) placed.push_back({v, a, b});
    for (size_t k = 0; k < K; ++k) {
#pragma omp parallel for schedule(static)
      for (long i = 0; i < long(placed.size()); ++i) {
        const size_t tile_index = size_t(i);
        const ViewFrame& f = frames[placed[tile_index].view];
        const uint32_t a = placed[tile_index].a, b = placed[tile_index].b;
        const float* tile = r.pixels.data() + (k * rendered + tile_index * T) * C;
        const uint32_t* tile_coverage = coverage ? r.coverage.data() + tile_index * T : nullptr;
        for (uint32_t j = 0; j < d.height; ++j) {
          const size_t row = f.offset - base + (size_t(b) * d.height + j) * f.width + size_t(a) * d.width;
          std::copy(tile + size_t(j) * d.width * C, tile + size_t(j + 1) * d.width * C, stitched.data() + row * C);
          if (k == 0 && coverage)
            std::copy(tile_coverage + size_t(j) * d.width, tile_coverage + size_t(j + 1) * d.width,
                      stitched_coverage.data() + row);
        }
      }
      fn(first, views, k, stitched.data(), coverage ? stitched_coverage.data() : nullptr, false);
    }
  }
}

// The same with one texture: fn(first view, views, pixels, coverage).
template <class Fn>
void render_views(engine::Engine& engine, const LayoutMesh& m, const Texture& tex, const std::vector<ViewFrame>& frames,
                  Timing& timing, RenderScratch& scratch, Fn&& fn, size_t per_chunk = 0, bool coverage = false) {
  render_views(engine, m, std::vector<const Texture*>{&tex}, frames, timing, scratch,
               [&](size_t first, size_t views, size_t, const float* px, const uint32_t* covered, bool) {
                 fn(first, views, px, covered);
               },
               per_chunk, coverage);
}

// fn(v) for every view v < count, views spread over the threads (each view writes only its
// own outputs: the same result for any thread count). The one place eval runs views in
// parallel on the host.
template <class Fn>
void for_each_view(size_t count, Fn&& fn) {
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(count); ++v) fn(size_t(v));
}

// The views `frames` as ImagePairs: their sizes, each pair's where the views differ (cropped).
struct ViewPairs {
  std::vector<uint32_t> sizes;
  engine::ImagePairs pairs;  // points into sizes: not to be copied
  ViewPairs(const ViewPairs&) = delete;
  ViewPairs& operator=(const ViewPairs&) = delete;
  ViewPairs(const float* first, const float* second, const ViewFrame* frames, size_t count, bool halved = false) {
    bool one_size = true;
    for (size_t v = 0; v < count; ++v) {
      sizes.insert(sizes.end(), {frames[v].width, frames[v].height});
      one_size = one_size && frames[v].width == frames[0].width && frames[v].height == frames[0].height;
    }
    pairs = {frames[0].width, frames[0].height, uint32_t(count), first, second};
    if (!one_size) pairs.sizes = sizes.data();
    pairs.halved = halved;
  }
};

// The gradient magnitudes (Engine::gmsd_references) of the reference views `frames`
// (pixels `ref`, one view after the other; halved: as MeshRenderDesc::halve leaves them)
// into `out`, one view's after another.
void reference_magnitudes(engine::Engine& engine, const float* ref, const ViewFrame* frames, size_t count, float* out,
                          Timing& timing, bool halved = false) {
  const Stopwatch t0;
  engine.gmsd_references(ViewPairs(ref, nullptr, frames, count, halved).pairs, out);
  timing.gmsd += t0.seconds();
}

// GMSD of the views `frames` (pixels `img`, one view after the other; halved: as
// MeshRenderDesc::halve leaves them) against the reference views' magnitudes `ref`
// (reference_magnitudes): one call.
void gmsd_views(engine::Engine& engine, const float* ref, const float* img, const ViewFrame* frames, size_t count,
                float* out, Timing& timing, bool halved = false) {
  const Stopwatch t0;
  const auto g = engine.gmsd_against(ViewPairs(ref, img, frames, count, halved).pairs);
  std::copy(g.begin(), g.end(), out);
  timing.gmsd += t0.seconds();
}

// Texture size at relative cost c_r in image texels: W H = c_r ref_texels, `aspect` kept.
// Sides are rounded to the nearest even number (from 16 texels; the reference's own side
// stays as it is): an odd side's mip chain drifts against level 0 from its first level on,
// and that, not the texels, then decides q — Duck resized to 359 x 359 scores 0.00089, to
// 360 x 360 0.00065 and to 362 x 362 0.00068 (noise floor 0.00014). A user resizing picks a
// sensible size; the curves, the resize's first, are not handicapped by a rounding. Each
// point's cost is its own W H (CurvePoint::c_r_actual).
std::pair<uint32_t, uint32_t> size_at(double c_r, double ref_texels, double aspect) {
  const double w = std::sqrt(c_r * ref_texels * aspect), h = w / aspect;
  auto side = [](double v, double full) {
    const double nearest = std::round(v);
    if (v < 16 || nearest == std::round(full)) return uint32_t(std::clamp(nearest, 1.0, 16384.0));
    return uint32_t(std::clamp(2 * std::round(v / 2), 2.0, 16384.0));
  };
  const double full_w = std::sqrt(ref_texels * aspect);
  return {side(w, full_w), side(h, full_w / aspect)};
}

// The reference's views as GMSD reads them (reference_magnitudes): unlit, and when the
// evaluation is lit the lit views too, each view's at[v] into them. A quarter of the
// views' pixels: Fox's 20 views at 1696 px took 230 MB as pixels, and their first touch
// was most of the time reparam's scorer took to set up.
struct ReferenceViews {
  engine::UninitializedVector<float> unlit, lit;  // every element written (reference_views)
  std::vector<size_t> at;                          // per view, and the total last
};

// What every evaluation of one reference shares: its layout, the cameras, the view
// resolution and filter, the shading, its views and its costs (image texels, and the
// paper's texels under the charts).
struct Setup {
  LayoutMesh ref;
  bool driving_forced = false;  // EvalOptions::driving_image chose ref.image
  std::vector<std::array<float, 16>> cameras;  // the whole views (contact sheets)
  std::vector<ViewFrame> frames;               // the views as scored
  TextureFilter filter = TextureFilter::Trilinear;
  ViewResolution resolution;
  bool lit = false;              // q is the lit q (EvalOptions::shading resolved)
  std::string shading_warning;   // auto fell back to unlit: why
  LightRig rig;
  ReferenceViews ref_views;
  // render_views' storage, kept across costs and candidates: every render's, and the maps'
  // renders nested inside the views' when lit. One buffer for all the renders that do not
  // nest, since fresh pages are the costly ones (RenderScratch::hold): Fox's eval --flatten
  // held three (views, many textures, a pair) of up to 180 MB each. Setup serves one thread
  // at a time.
  mutable RenderScratch scratch, map_scratch;
  double image_texels = 0, chart_texels = 0;
  double radius = 0;  // the largest extent of the bounding box
  std::optional<io::AstcOptions> codec;  // EvalOptions::codec
  double noise_floor_unlit = 0, noise_floor_lit = 0;  // both, when lit
};

// What one score renders: the driving texture's luminance (unlit) and, when lit, every
// map of the layout (RGB, in the order of LayoutMesh::maps).
struct LayoutTextures {
  Texture driving;
  std::vector<Texture> maps;
};

// q of one layout and texture set: `q` and `views` (GMSD per view) of the evaluation's
// shading, both shadings' q beside (q_lit = 0 when unlit).
struct Scores {
  double q = 0, q_unlit = 0, q_lit = 0;
  std::vector<float> views;
};

// A layout lit as lit.h says: its geometry with tangents (the file's, else derived from
// its UVs) and its materials.
LitSurface lit_surface(const LayoutMesh& m) {
  LitSurface surface;
  surface.positions = &m.positions, surface.indices = &m.indices;
  surface.normals = m.normals;
  surface.tangents = m.tangents.empty() ? vertex_tangents(m.positions, m.uvs, m.indices, m.normals) : m.tangents;
  surface.triangle_material = &m.triangle_material, surface.materials = &m.materials;
  return surface;
}

// Renders every view of `m` with `tex`: fn(first view, views, unlit luminance, lit
// luminance or null when unlit, halved), chunk by chunk. Unlit, the views come halved where
// they can (render_views: `halved` says so); the lit luminance is shaded on the host from
// each map's render of the same views and the unlit render's coverage, views in parallel
// (no shared sums: the same result for any thread count), all of them whole.
template <class Fn>
void render_scored_views(engine::Engine& engine, const Setup& s, const LayoutMesh& m, const LayoutTextures& tex,
                         const std::vector<ViewFrame>& frames, Timing& timing, Fn&& fn) {
  if (!s.lit) {
    render_views(engine, m, {&tex.driving}, frames, timing, s.scratch,
                 [&](size_t first, size_t views, size_t, const float* px, const uint32_t*, bool halved) {
                   fn(first, views, px, nullptr, halved);
                 },
                 0, false, true);
    return;
  }
  const LitSurface surface = lit_surface(m);
  size_t largest = 0;
  for (const ViewFrame& f : frames) largest = std::max(largest, f.pixels());
  // Each chunk holds the luminance and 3 channels of every map: fewer views a chunk.
  const size_t per_chunk = std::max<size_t>(1, kChunkPixels / (largest * (1 + 3 * tex.maps.size())));
  std::vector<std::vector<float>> map_px(tex.maps.size());
  std::vector<float> lit;
  render_views(
      engine, m, tex.driving, frames, timing, s.scratch,
      [&](size_t first, size_t views, const float* px, const uint32_t* coverage) {
        const std::vector<ViewFrame> chunk(frames.begin() + long(first), frames.begin() + long(first + views));
        const size_t base = chunk.front().offset, n = total_pixels(chunk) - base;
        for (size_t k = 0; k < tex.maps.size(); ++k)
          render_views(engine, m, tex.maps[k], chunk, timing, s.map_scratch,
                       [&](size_t, size_t, const float* mp, const uint32_t*) { map_px[k].assign(mp, mp + n * 3); },
                       views);
        const Stopwatch t0;
        lit.assign(n, 0.0f);
        for_each_view(views, [&](size_t v) {
          const ViewFrame& f = chunk[v];
          const size_t at = f.offset - base;
          std::vector<const float*> maps(tex.maps.size());
          for (size_t k = 0; k < maps.size(); ++k) maps[k] = map_px[k].data() + at * 3;
          lit_luminance(surface, s.rig, f.window(), f.width, f.height, coverage + at, maps, lit.data() + at);
        });
        timing.shading += t0.seconds();
        fn(first, views, px, lit.data(), false);
      },
      per_chunk, true);
}

double mean_of(const std::vector<float>& x) {
  double q = 0;
  for (float v : x) q += v;
  return x.empty() ? 0.0 : q / double(x.size());
}

// Mean GMSD of `m` textured with `tex` against the reference views: the one place eval
// turns textures into q. The noise floor passes cameras and reference views of its own
// (shifted by a fraction of a pixel).
Scores score_views(engine::Engine& engine, const Setup& s, const LayoutMesh& m, const LayoutTextures& tex,
                   Timing& timing, const std::vector<ViewFrame>* frames = nullptr,
                   const ReferenceViews* ref_views = nullptr) {
  const std::vector<ViewFrame>& views = frames ? *frames : s.frames;
  const ReferenceViews& ref = ref_views ? *ref_views : s.ref_views;
  std::vector<float> g(views.size()), g_lit(s.lit ? views.size() : 0);
  render_scored_views(engine, s, m, tex, views, timing, [&](size_t first, size_t count, const float* px, const float* lit,
                                                             bool halved) {
    const size_t at = ref.at[first];
    gmsd_views(engine, ref.unlit.data() + at, px, &views[first], count, g.data() + first, timing, halved);
    if (lit) gmsd_views(engine, ref.lit.data() + at, lit, &views[first], count, g_lit.data() + first, timing);
  });
  Scores r;
  r.q_unlit = mean_of(g), r.q_lit = mean_of(g_lit);
  r.q = s.lit ? r.q_lit : r.q_unlit;
  r.views = s.lit ? std::move(g_lit) : std::move(g);
  return r;
}

// score_views for each texture set of `textures` on one layout, the same scores: unlit,
// sets share one rasterization of every view (render_views with several textures: a curve
// costs one rasterization, a sampling per cost), as many at once as keep a chunk of two
// views within 2 kChunkPixels (Duck's 1248-px views: all ten costs; Fox's 1696: six);
// lit, one score_views each.
std::vector<Scores> score_views_many(engine::Engine& engine, const Setup& s, const LayoutMesh& m,
                                     const std::vector<LayoutTextures>& textures, Timing& timing) {
  std::vector<Scores> out;
  if (s.lit || textures.size() == 1) {
    for (const LayoutTextures& t : textures) out.push_back(score_views(engine, s, m, t, timing));
    return out;
  }
  const std::vector<ViewFrame>& views = s.frames;
  size_t largest = 1;
  for (const ViewFrame& f : views) largest = std::max(largest, f.pixels());
  // A batch's chunk of two views holds at most 2 kChunkPixels for all its textures.
  const size_t batch = std::max<size_t>(1, kChunkPixels / largest);
  for (size_t b = 0; b < textures.size(); b += batch) {
    const size_t e = std::min(textures.size(), b + batch);
    std::vector<const Texture*> driving;
    for (size_t k = b; k < e; ++k) driving.push_back(&textures[k].driving);
    std::vector<std::vector<float>> g(e - b, std::vector<float>(views.size()));
    // At least two views a chunk: GMSD runs a call's views in parallel.
    const size_t per_chunk = std::max<size_t>(2, 2 * kChunkPixels / (largest * driving.size()));
    render_views(engine, m, driving, views, timing, s.scratch,
                 [&](size_t first, size_t count, size_t k, const float* px, const uint32_t*, bool halved) {
                   gmsd_views(engine, s.ref_views.unlit.data() + s.ref_views.at[first], px, &views[first], count,
                              g[k].data() + first, timing, halved);
                 },
                 per_chunk, false, true);
    for (auto& x : g) {
      Scores r;
      r.q = r.q_unlit = mean_of(x);
      r.views = std::move(x);
      out.push_back(std::move(r));
    }
  }
  return out;
}

// The resize that brings a layout's textures to a cost: colour textures (the driving
// texture, base colour and emissive maps) and data textures (normal, occlusion,
// metallic-roughness: their stored values are linear, so a "linear light" resize of them
// is the stored-value one).
using Resize = std::function<Image(const Image&, uint32_t, uint32_t)>;
struct Resizer {
  Resize colour, data;
};

// `m`'s textures as the views sample them: `driving` (the driving texture at its size)
// and, when lit, every map of `m` brought to the same relative size (each map's sides
// scaled by driving's over m.full's) by `resize` (none: the maps at their own size, as
// written), after the codec when `with_codec`.
LayoutTextures layout_textures(const Setup& s, const LayoutMesh& m, const Image& driving, const Resizer* resize,
                               bool with_codec, Timing& timing) {
  const Stopwatch t0;
  const io::AstcOptions* codec = with_codec && s.codec ? &*s.codec : nullptr;
  LayoutTextures t;
  t.driving = view_texture(driving, s.filter, false, codec);
  if (s.lit)
    for (const MaterialMap& map : m.maps) {
      const bool colour = map.kind == atlas::RebakeRole::Color;
      if (!resize) {
        t.maps.push_back(view_texture(map.full, s.filter, true, codec, colour));
        continue;
      }
      const uint32_t w = uint32_t(std::max(1.0, std::round(double(map.full.width) * driving.width / m.full.width)));
      const uint32_t h = uint32_t(std::max(1.0, std::round(double(map.full.height) * driving.height / m.full.height)));
      const Image small = (colour ? resize->colour : resize->data)(map.full, w, h);
      t.maps.push_back(view_texture(small, s.filter, true, codec, colour));
    }
  timing.textures += t0.seconds();
  return t;
}

// ASTC bytes of `image`'s levels as the views sample them (0 without a codec).
uint64_t codec_bytes(const Setup& s, uint32_t width, uint32_t height) {
  if (!s.codec) return 0;
  const uint32_t levels = s.filter == TextureFilter::Trilinear ? engine::mip_chain_levels(width, height) : 1;
  uint64_t n = 0;
  for (uint32_t l = 0; l < levels; ++l)
    n += io::astc_bytes(std::max(1u, width >> l), std::max(1u, height >> l), s.codec->block_x, s.codec->block_y);
  return n;
}

// Every view of `m` textured with `tex`, its luminance, view after view (unlit, and lit
// when the evaluation is).
ReferenceViews reference_views(engine::Engine& engine, const Setup& s, const LayoutMesh& m, const LayoutTextures& tex,
                               const std::vector<ViewFrame>& frames, Timing& timing) {
  ReferenceViews out;
  out.at.assign(1, 0);
  for (const ViewFrame& f : frames) out.at.push_back(out.at.back() + engine::Engine::gmsd_half_size(f.width, f.height));
  out.unlit.resize(out.at.back());
  if (s.lit) out.lit.resize(out.unlit.size());
  render_scored_views(engine, s, m, tex, frames, timing, [&](size_t first, size_t views, const float* px, const float* lit,
                                                              bool halved) {
    reference_magnitudes(engine, px, &frames[first], views, out.unlit.data() + out.at[first], timing, halved);
    if (lit) reference_magnitudes(engine, lit, &frames[first], views, out.lit.data() + out.at[first], timing);
  });
  return out;
}

// score_views of `m` with `tex` on views `frames` of their own, against `m` with
// `reference` on those same views (the noise floor's shifted cameras). Unlit, both
// textures share one rasterization of each view, and the reference views are kept a chunk
// at a time; lit, the reference views are rendered whole first.
Scores score_against_own_reference(engine::Engine& engine, const Setup& s, const LayoutMesh& m,
                                   const LayoutTextures& reference, const LayoutTextures& tex,
                                   const std::vector<ViewFrame>& frames, Timing& timing) {
  if (s.lit) {
    const ReferenceViews ref = reference_views(engine, s, m, reference, frames, timing);
    return score_views(engine, s, m, tex, timing, &frames, &ref);
  }
  std::vector<float> g(frames.size()), ref_chunk;
  render_views(engine, m, {&reference.driving, &tex.driving}, frames, timing, s.scratch,
               [&](size_t first, size_t count, size_t k, const float* px, const uint32_t*, bool halved) {
                 if (k == 0) {  // texture 0 of a chunk comes before texture 1
                   size_t n = 0;
                   for (size_t v = first; v < first + count; ++v)
                     n += engine::Engine::gmsd_half_size(frames[v].width, frames[v].height);
                   ref_chunk.resize(n);
                   reference_magnitudes(engine, px, &frames[first], count, ref_chunk.data(), timing, halved);
                   return;
                 }
                 gmsd_views(engine, ref_chunk.data(), px, &frames[first], count, g.data() + first, timing, halved);
               },
               0, false, true);
  Scores r;
  r.q = r.q_unlit = mean_of(g);
  r.views = std::move(g);
  return r;
}

// Texels of the reference texture per screen pixel, per covered pixel of every view at
// `res` (isotropic: sqrt of the ratio of a triangle's texel area to its screen area in
// that view, per triangle), ascending.
std::vector<float> texels_per_pixel(engine::Engine& engine, const LayoutMesh& ref,
                                    const std::vector<std::array<float, 16>>& cameras, uint32_t res, Timing& timing) {
  const size_t tris = ref.indices.size() / 3;
  std::vector<double> texel_area(tris);
  for (size_t t = 0; t < tris; ++t) texel_area[t] = detail::uv_area(ref.uvs, ref.indices, t) * ref.full.width * ref.full.height;
  Texture flat;  // coverage is all this render is for
  flat.width = flat.height = 1, flat.texels = {0.0f};
  engine::MeshRenderDesc d;
  d.width = d.height = res;
  d.cameras = cameras;
  d.positions = ref.positions.data(), d.vertex_count = ref.positions.size() / 3;
  d.indices = ref.indices.data(), d.triangle_count = tris;
  d.uvs = ref.uvs.data();
  d.texture = flat.texels.data(), d.texture_width = d.texture_height = 1, d.channels = 1;
  const Stopwatch t0;
  const auto r = engine.render_mesh(d);
  timing.render += t0.seconds();
  std::vector<float> out;
  std::vector<double> screen(tris);
  for (size_t v = 0; v < cameras.size(); ++v) {
    const auto& m = cameras[v];
    for (size_t t = 0; t < tris; ++t) {
      double X[3], Y[3];
      for (int k = 0; k < 3; ++k) {
        const float* p = ref.positions.data() + 3 * size_t(ref.indices[3 * t + size_t(k)]);
        const auto c = clip_of(m, p);
        X[k] = (c[0] / c[3] * 0.5 + 0.5) * res, Y[k] = (0.5 - 0.5 * c[1] / c[3]) * res;
      }
      screen[t] = 0.5 * std::abs((X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0]));
    }
    const size_t n = size_t(res) * res;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t t = r.coverage[v * n + i];
      if (t == engine::kNoMeshTriangle || !(screen[t] > 0)) continue;
      out.push_back(float(std::sqrt(texel_area[t] / screen[t])));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The asset's rectangle on screen in each view: NDC {x_lo, x_hi, y_lo, y_hi} of its
// vertices (eval's cameras hold the whole mesh in front of them), clamped to the view.
std::vector<std::array<double, 4>> screen_rectangles(const LayoutMesh& ref,
                                                     const std::vector<std::array<float, 16>>& cameras) {
  std::vector<std::array<double, 4>> out;
  for (const auto& m : cameras) {
    std::array<double, 4> r = {1, -1, 1, -1};
    for (size_t v = 0; v < ref.positions.size() / 3; ++v) {
      const float* p = ref.positions.data() + 3 * v;
      const auto c = clip_of(m, p);
      if (!(c[3] > 0)) return {};  // a vertex behind the eye: no rectangle to crop to
      r[0] = std::min(r[0], c[0] / c[3]), r[1] = std::max(r[1], c[0] / c[3]);
      r[2] = std::min(r[2], c[1] / c[3]), r[3] = std::max(r[3], c[1] / c[3]);
    }
    for (double& x : r) x = std::clamp(x, -1.0, 1.0);
    out.push_back(r);
  }
  return out;
}

// The views at `side` pixels a side cropped to the asset's rectangles: each window holds its
// rectangle and 2 pixels around it (the GMS gradient's reach), at least 16 pixels a side,
// in whole pixels of the whole view, cut into tiles of equal size within the engine's limit.
std::vector<ViewFrame> cropped_frames(const std::vector<std::array<float, 16>>& cameras,
                                      const std::vector<std::array<double, 4>>& rects, uint32_t side) {
  std::vector<ViewFrame> frames(cameras.size());
  size_t offset = 0;
  for (size_t v = 0; v < cameras.size(); ++v) {
    ViewFrame& f = frames[v];
    const auto& r = rects[v];
    f.camera = cameras[v], f.side = side, f.cropped = true;
    const double x_lo = (r[0] + 1) / 2 * side, x_hi = (r[1] + 1) / 2 * side;  // pixels from the left
    const double y_lo = (1 - r[3]) / 2 * side, y_hi = (1 - r[2]) / 2 * side;  // pixels from the top
    auto window = [&](double lo, double hi, uint32_t& origin, uint32_t& size, uint32_t& tiles) {
      const double first = std::max(0.0, std::floor(lo) - 2), last = std::min(double(side), std::ceil(hi) + 2);
      size = std::max<uint32_t>(16, uint32_t(last - first));
      tiles = tiles_per_side(size);
      size = (size + tiles - 1) / tiles * tiles;
      origin = uint32_t(first);
    };
    window(x_lo, x_hi, f.x0, f.width, f.tiles_x);
    window(y_lo, y_hi, f.y0, f.height, f.tiles_y);
    f.offset = offset;
    offset += f.pixels();
  }
  return frames;
}

// The views' resolution and frames (eval.cpp, "Resolution"). Where the cap binds, the views
// are rolled to the asset (asset_roll) and cropped to its screen rectangle instead, at the
// largest side (a multiple of 16, at most the wanted one and 2 kMaxResolution) whose windows
// hold no more pixels than the capped whole views would: the same memory and time, more of
// the texture resolved.
ViewResolution choose_resolution(engine::Engine& engine, const LayoutMesh& ref,
                                 const std::vector<std::array<float, 16>>& cameras, const EvalOptions& o,
                                 Timing& timing, std::vector<ViewFrame>& frames) {
  constexpr uint32_t kProbe = 512;  // the resolution texels per pixel are measured at
  const auto tpp = texels_per_pixel(engine, ref, cameras, kProbe, timing);
  ViewResolution r;
  r.percentile = o.resolution_percentile;
  auto at = [&](double p) { return tpp.empty() ? 0.0 : double(tpp[std::min(tpp.size() - 1, size_t(p * double(tpp.size())))]); };
  const double probe_tpp = at(o.resolution_percentile);
  frames.clear();
  if (o.resolution == 0) {
    // The smallest side, a multiple of 16 (and of the tile count), at which the percentile
    // is magnified or 1:1.
    uint32_t want = std::max<uint32_t>(512, uint32_t(std::ceil(kProbe * probe_tpp / 16.0)) * 16);
    r.capped = want > o.resolution_cap;
    if (r.capped) {
      // Each view rolled about its axis so that the asset's rectangle is smallest.
      auto rolled = cameras;
      for (auto& m : rolled) m = roll_camera(m, asset_roll(ref.positions.data(), ref.positions.size() / 3, m));
      const auto rects = screen_rectangles(ref, rolled);
      const size_t budget = cameras.size() * size_t(o.resolution_cap) * o.resolution_cap;
      for (uint32_t side = std::min(want, 2 * kMaxResolution) / 16 * 16; !rects.empty() && side > o.resolution_cap; side -= 16) {
        auto cropped = cropped_frames(rolled, rects, side);
        if (total_pixels(cropped) > budget) continue;
        frames = std::move(cropped);
        r.resolution = side, r.cropped = true, r.capped = side < want;
        break;
      }
    }
    if (frames.empty()) {
      want = std::min(want, o.resolution_cap);
      const uint32_t k = tiles_per_side(want);
      r.resolution = (want + 16 * k - 1) / (16 * k) * (16 * k);
    }
    r.automatic = true;
  } else {
    const uint32_t k = tiles_per_side(o.resolution);
    r.resolution = o.resolution / k * k;
  }
  if (frames.empty()) frames = square_frames(cameras, r.resolution);
  r.view_pixels = cameras.empty() ? 0 : double(total_pixels(frames)) / double(cameras.size());
  const double scale = double(kProbe) / r.resolution;  // texels per pixel at res = at probe x scale
  r.texels_per_pixel = probe_tpp * scale;
  r.texels_per_pixel_median = at(0.5) * scale;
  // Share of the visible screen area where a pixel covers at most one texel.
  const float limit = float(1.0 / scale);
  r.resolved_fraction = tpp.empty() ? 1.0
                                    : double(std::upper_bound(tpp.begin(), tpp.end(), limit) - tpp.begin()) / double(tpp.size());
  return r;
}

// The resizes eval uses (see Resizer): the paper's area filter, and users' Lanczos-3 in
// stored sRGB values or in linear light.
Resizer area_resize() {
  const Resize area = [](const Image& i, uint32_t w, uint32_t h) { return resize_area(i, w, h); };
  return {area, area};
}
Resizer lanczos_resize(bool linear_light) {
  const Resize stored = [](const Image& i, uint32_t w, uint32_t h) { return resize_lanczos3(i, w, h, false); };
  if (!linear_light) return {stored, stored};
  return {[](const Image& i, uint32_t w, uint32_t h) { return resize_lanczos3(i, w, h, true); }, stored};
}

Setup set_up(const io::GltfFile& reference, engine::Engine& engine, const EvalOptions& o, Timing& timing) {
  if (o.cost_grid.empty()) throw InputError(reference.path, "empty cost grid");
  for (double c : o.cost_grid)
    if (!(c > 0 && c <= 4)) throw InputError(reference.path, "cost grid values must lie in (0, 4]");
  if (o.resolution != 0 && (o.resolution < 8 || o.resolution > kMaxResolution))
    throw InputError(reference.path, "resolution must be 8.." + std::to_string(kMaxResolution) + " or auto");
  if (o.resolution_cap < 512 || o.resolution_cap > kMaxResolution)
    throw InputError(reference.path, "resolution cap must be 512.." + std::to_string(kMaxResolution));
  if (!(o.resolution_percentile > 0 && o.resolution_percentile <= 1))
    throw InputError(reference.path, "resolution percentile must lie in (0, 1]");
  Setup s;
  // Shading: auto lights assets whose materials have a normal map (the maps the unlit q
  // cannot see); the others keep the unlit path, untouched. A reference that cannot be lit
  // (a map on another UV set, a normal map without RGB) is an error when lit was asked for,
  // and under auto falls back to unlit with a warning in the report.
  const bool want_lit = o.shading == Shading::Lit || (o.shading == Shading::Auto && detail::has_normal_map(reference));
  s.ref = detail::extract_layout(reference, "input", want_lit, o.driving_image);
  s.driving_forced = o.driving_image >= 0;
  if (want_lit && !s.ref.lit_problem.empty()) {
    if (o.shading == Shading::Lit) throw InputError(reference.path, "cannot evaluate lit: " + s.ref.lit_problem);
    s.shading_warning = "lit shading skipped, q is unlit: " + s.ref.lit_problem;
  } else {
    s.lit = want_lit;
  }
  s.rig = default_light_rig();
  const LayoutMesh& ref = s.ref;
  s.cameras = dodecahedron_cameras(ref.positions.data(), ref.positions.size() / 3, o.fov_degrees);
  s.filter = o.filter;
  s.image_texels = double(ref.full.width) * ref.full.height;
  s.chart_texels = s.image_texels * ref.uv_area;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t v = 0; v < ref.positions.size() / 3; ++v)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], double(ref.positions[3 * v + size_t(d)])), hi[d] = std::max(hi[d], double(ref.positions[3 * v + size_t(d)]));
  for (int d = 0; d < 3; ++d) s.radius = std::max(s.radius, hi[d] - lo[d]);
  s.resolution = choose_resolution(engine, ref, s.cameras, o, timing, s.frames);
  const uint32_t res = s.resolution.resolution;
  const LayoutTextures ref_tex = layout_textures(s, ref, ref.full, nullptr, false, timing);
  s.ref_views = reference_views(engine, s, ref, ref_tex, s.frames, timing);
  if (o.noise_floor) {
    // How far q moves when only the sampling phase does: the input resized to half its
    // texels (Lanczos-3) scored as usual, again with the cameras and the reference views
    // shifted by a quarter pixel (two directions), and resized to 1, 2 and 3 texels more a
    // side; the largest change. Differences between layouts below it are not claimed.
    // Lit: every map resized alike, both shadings' floors measured (noise_floor is the
    // evaluation's shading's).
    const Resizer users = lanczos_resize(false);
    auto [W, H] = size_at(0.5, s.image_texels, double(ref.full.width) / ref.full.height);
    // The half-size texture and its texel-phase variants (below) share one rasterization.
    std::vector<LayoutTextures> phases;
    for (uint32_t more = 0; more <= 3; ++more)
      phases.push_back(layout_textures(s, ref, resize_lanczos3(ref.full, W + more, H + more, false), &users, false, timing));
    const std::vector<Scores> phase_q = score_views_many(engine, s, ref, phases, timing);
    const LayoutTextures& half = phases[0];
    const Scores& q = phase_q[0];
    auto widen = [&](const Scores& other) {
      s.noise_floor_unlit = std::max(s.noise_floor_unlit, std::abs(other.q_unlit - q.q_unlit));
      s.noise_floor_lit = std::max(s.noise_floor_lit, std::abs(other.q_lit - q.q_lit));
    };
    for (const double dy : {0.25, -0.25}) {
      auto jittered = s.frames;
      const double sx = 2.0 * 0.25 / res, sy = 2.0 * dy / res;  // NDC units of the whole view
      for (auto& f : jittered) {
        auto& m = f.camera;
        for (int c = 0; c < 4; ++c) {
          m[size_t(c)] = float(double(m[size_t(c)]) + sx * double(m[size_t(12 + c)]));
          m[size_t(4 + c)] = float(double(m[size_t(4 + c)]) + sy * double(m[size_t(12 + c)]));
        }
      }
      widen(score_against_own_reference(engine, s, ref, ref_tex, half, jittered, timing));
    }
    // The texel grid's phase too: one, two and three texels more a side (under 2 % more
    // texels: no trend to see) move every edge of the resized texture against the screen.
    for (uint32_t more = 1; more <= 3; ++more) widen(phase_q[more]);
    s.resolution.noise_floor = s.lit ? s.noise_floor_lit : s.noise_floor_unlit;
  }
  s.codec = o.codec;  // after the reference views and the noise floor: those stay uncompressed
  return s;
}

// A layout as written: its own textures at their real size, its own sampler.
Scored score_own(engine::Engine& engine, const Setup& s, const LayoutMesh& own, Timing& timing) {
  if (s.lit && !own.lit_problem.empty()) throw InputError(own.file, "cannot evaluate lit: " + own.lit_problem);
  Scored r;
  const double texels = double(own.full.width) * own.full.height;
  r.c_r = texels / s.image_texels;
  r.c_r_chart = texels * own.uv_area / s.chart_texels;
  Scores q = score_views(engine, s, own, layout_textures(s, own, own.full, nullptr, true, timing), timing);
  r.q = q.q, r.q_unlit = q.q_unlit, r.q_lit = q.q_lit, r.lit = s.lit;
  r.q_views = std::move(q.views);
  return r;
}

// A 5 x 4 sheet of RGB renders (values clamped to [0,1]).
Image contact_sheet(engine::Engine& engine, const LayoutMesh& m, const Image& texture,
                    const std::vector<std::array<float, 16>>& cameras, uint32_t thumb, TextureFilter filter) {
  const Texture tex = view_texture(texture, filter, true);
  std::vector<float> pixels(cameras.size() * thumb * thumb * 3);
  Timing ignored;
  RenderScratch scratch;
  render_views(engine, m, tex, square_frames(cameras, thumb), ignored, scratch, [&](size_t first, size_t views, const float* px, const uint32_t*) {
    std::copy(px, px + views * thumb * thumb * 3, pixels.data() + first * thumb * thumb * 3);
  });
  Image sheet;
  const uint32_t cols = 5, rows = uint32_t((cameras.size() + cols - 1) / cols);
  sheet.width = cols * thumb, sheet.height = rows * thumb, sheet.channels = 3, sheet.bits = 8;
  sheet.pixels.assign(size_t(sheet.width) * sheet.height * 3, 0.0f);
  for (size_t v = 0; v < cameras.size(); ++v)
    for (uint32_t j = 0; j < thumb; ++j)
      for (uint32_t i = 0; i < thumb; ++i)
        for (uint32_t c = 0; c < 3; ++c) {
          const size_t x = (v % cols) * thumb + i, y = (v / cols) * thumb + j;
          sheet.pixels[(y * sheet.width + x) * 3 + c] =
              std::clamp(pixels[((v * thumb + j) * thumb + i) * 3 + c], 0.0f, 1.0f);
        }
  return sheet;
}

// The layout in UV space, each triangle coloured by log2 of its texel density relative to
// the layout's mean (blue: fewer texels per surface area, red: more), on dark grey.
Image uv_plot(const LayoutMesh& m, double aspect, double* spread) {
  const uint32_t W = aspect >= 1 ? 512 : uint32_t(std::max(64.0, std::round(512 * aspect)));
  const uint32_t H = aspect >= 1 ? uint32_t(std::max(64.0, std::round(512 / aspect))) : 512;
  Image img;
  img.width = W, img.height = H, img.channels = 3, img.bits = 8;
  img.pixels.assign(size_t(W) * H * 3, 0.18f);
  const double mean = m.uv_area / m.area3d;
  double wsum = 0, w2 = 0;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const double a3 = detail::area3d(m.positions, m.indices, t), a2 = detail::uv_area(m.uvs, m.indices, t);
    if (!(a3 > 0)) continue;
    // Density is per length: half the log of the area ratio.
    const double l = std::clamp(0.5 * std::log2(std::max(a2, 1e-30) / a3 / mean), -2.0, 2.0);
    wsum += a3, w2 += a3 * l * l;
    const double x = std::abs(l) / 2;
    const float rgb[3] = {float(l > 0 ? 1.0 : 1.0 - 0.8 * x), float(1.0 - 0.8 * x), float(l < 0 ? 1.0 : 1.0 - 0.8 * x)};
    double px[3], py[3];
    for (int k = 0; k < 3; ++k) {
      double u = m.uvs[2 * size_t(m.indices[3 * t + size_t(k)])], v = m.uvs[2 * size_t(m.indices[3 * t + size_t(k)]) + 1];
      if (m.repeat) u -= std::floor(u), v -= std::floor(v);  // tiled layouts folded into one tile
      px[k] = u * W, py[k] = v * H;
    }
    const double det = (px[1] - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (py[1] - py[0]);
    if (std::abs(det) < 1e-12) continue;
    const int i0 = std::max(0, int(std::floor(std::min({px[0], px[1], px[2]})))),
              i1 = std::min(int(W) - 1, int(std::ceil(std::max({px[0], px[1], px[2]}))));
    const int j0 = std::max(0, int(std::floor(std::min({py[0], py[1], py[2]})))),
              j1 = std::min(int(H) - 1, int(std::ceil(std::max({py[0], py[1], py[2]}))));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double x0 = i + 0.5, y0 = j + 0.5;
        const double b1 = ((x0 - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (y0 - py[0])) / det;
        const double b2 = ((px[1] - px[0]) * (y0 - py[0]) - (x0 - px[0]) * (py[1] - py[0])) / det;
        if (b1 < 0 || b2 < 0 || b1 + b2 > 1) continue;
        // Thin dark edges show the triangles.
        const double edge = std::min({b1, b2, 1 - b1 - b2}) * std::abs(det) /
                            std::max({std::hypot(px[1] - px[0], py[1] - py[0]), std::hypot(px[2] - px[0], py[2] - py[0]),
                                      std::hypot(px[2] - px[1], py[2] - py[1])});
        const float shade = edge < 0.35 ? 0.55f : 1.0f;
        for (int c = 0; c < 3; ++c) img.pixels[(size_t(j) * W + size_t(i)) * 3 + size_t(c)] = rgb[c] * shade;
      }
  }
  if (spread) *spread = wsum > 0 ? std::sqrt(w2 / wsum) : 0;
  return img;
}

}  // namespace

struct AsWrittenScorer::State {
  engine::Engine& engine;
  Timing timing;
  Setup setup;
};

AsWrittenScorer::AsWrittenScorer(const io::GltfFile& reference, engine::Engine& engine, const EvalOptions& o)
    : state_(new State{engine, {}, {}}) {
  state_->setup = set_up(reference, engine, o, state_->timing);
}

AsWrittenScorer::~AsWrittenScorer() = default;

Scored AsWrittenScorer::score(const io::GltfFile& candidate) {
  return score_own(state_->engine, state_->setup,
                   detail::extract_layout(candidate, "candidate", state_->setup.lit,
                                          state_->setup.driving_forced ? state_->setup.ref.image : -1),
                   state_->timing);
}

const ViewResolution& AsWrittenScorer::resolution() const { return state_->setup.resolution; }

Shading AsWrittenScorer::shading() const { return state_->setup.lit ? Shading::Lit : Shading::Unlit; }

const std::string& AsWrittenScorer::shading_warning() const { return state_->setup.shading_warning; }

int AsWrittenScorer::driving_image() const { return state_->setup.ref.image; }

Scored score_as_written(const io::GltfFile& reference, const io::GltfFile& candidate, engine::Engine& engine,
                        const EvalOptions& o) {
  return AsWrittenScorer(reference, engine, o).score(candidate);
}

EvalResult evaluate(const io::GltfFile& reference, const std::vector<LayoutInput>& others, engine::Engine& engine,
                    const EvalOptions& o, EvalArtifacts* artifacts, const Progress& progress) {
  const Stopwatch t_start;
  Timing timing;
  const bool bytes_axis = o.cost_axis == CostAxis::Bytes;
  if (bytes_axis && o.codec)
    throw InputError(reference.path, "--cost-axis bytes counts the input's own codec (PNG or JPEG); with --codec the cost "
                                     "is the codec's fixed-rate blocks, which go with texels: use --cost-axis texels");
  const Setup s = set_up(reference, engine, o, timing);
  const LayoutMesh& ref = s.ref;
  const auto& cameras = s.cameras;
  // The bytes axis (see "Cost axis" above): textures encoded as the reference's image is.
  const std::vector<uint8_t>& reference_bytes = reference.image_bytes.at(size_t(ref.image));
  const io::EncodeSettings encoding = io::encode_settings_of(reference_bytes);
  const bool grey = bytes_axis && io::read_image_header(reference_bytes, reference.path).channels <= 2;
  auto encoded_bytes = [&](const Image& rgb) -> uint64_t {
    Image tex = rgb;
    tex.bits = ref.full.bits;
    if (grey) {
      tex.channels = 1;
      for (size_t i = 0; i < size_t(tex.width) * tex.height; ++i) tex.pixels[i] = rgb.pixels[3 * i];
      tex.pixels.resize(size_t(tex.width) * tex.height);
    }
    return io::encode_image(tex, encoding).size();
  };

  // The layouts with their full textures and aspects.
  struct Entry {
    LayoutMesh mesh;
    double aspect = 1;
    bool users_resize = false;  // the input: resized as users' tools do (the variant that scores better)
    bool paper_filter = false;  // input-rebaked: area-filtered to each c_r as in the paper's protocol
    bool scored_as_written = false;
    Scored as_written;
    uint32_t written_size[2] = {0, 0};  // the file's own texture (full is re-baked later)
    uint64_t written_bytes = 0;         // ... and its encoded bytes
    std::optional<std::string> rebake;  // how the full texture was re-baked
    nlohmann::ordered_json isometric;  // the isometric layout's flatten summary
  };
  std::vector<Entry> layouts;
  {
    Entry e;
    e.mesh = ref, e.aspect = double(ref.full.width) / ref.full.height, e.users_resize = true;
    layouts.push_back(std::move(e));
  }
  auto rebake_into = [&](Entry& e) {
    auto [W, H] = size_at(1.0, s.image_texels, e.aspect);
    const Stopwatch t0;
    std::string method;
    e.mesh.full = detail::rebake_from(ref, e.mesh, W, H, &method);
    if (s.lit) {
      // Every map of the reference's materials re-baked into this layout at the same
      // relative size (its triangles are the reference's, one to one).
      e.mesh.maps.clear();
      for (const auto& map : ref.maps) {
        detail::MaterialMap baked;
        baked.kind = map.kind;
        const uint32_t w = uint32_t(std::max(1.0, std::round(double(map.full.width) * W / ref.full.width)));
        const uint32_t h = uint32_t(std::max(1.0, std::round(double(map.full.height) * H / ref.full.height)));
        baked.full = detail::rebake_map_from(ref, map, e.mesh, w, h);
        e.mesh.maps.push_back(std::move(baked));
      }
      e.mesh.materials = ref.materials, e.mesh.triangle_material = ref.triangle_material;
      e.mesh.lit_problem.clear();
    }
    timing.textures += t0.seconds();
    e.mesh.texture_source = "rebaked";
    e.rebake = method;
  };
  if (o.paper_baseline) {
    // The paper's protocol (§5.1): the input layout re-baked and area-filtered like every
    // other layout, so its losses are the ones the others pay too.
    Entry e;
    e.mesh = ref, e.mesh.name = "input-rebaked", e.aspect = double(ref.full.width) / ref.full.height;
    e.paper_filter = true;
    rebake_into(e);
    layouts.push_back(std::move(e));
  }
  for (const auto& other : others) {
    Entry e;
    e.mesh = detail::extract_layout(*other.file, other.name, s.lit);
    if (e.mesh.indices.size() != ref.indices.size())
      throw InputError(other.file->path, "not the same mesh as " + reference.path + " (" +
                                             std::to_string(e.mesh.indices.size() / 3) + " textured triangles, not " +
                                             std::to_string(ref.indices.size() / 3) + ")");
    e.aspect = double(e.mesh.full.width) / e.mesh.full.height;
    // What the user will see: the file's own texture at its real size, its own sampler.
    if (progress) progress("as written " + e.mesh.name, 0, 1);
    e.as_written = score_own(engine, s, e.mesh, timing);
    e.scored_as_written = true;
    e.written_size[0] = e.mesh.full.width, e.written_size[1] = e.mesh.full.height;
    e.written_bytes = other.file->image_bytes.at(size_t(e.mesh.image)).size();
    if (detail::same_triangles(ref, e.mesh, 1e-5 * s.radius)) {
      rebake_into(e);
    } else {
      e.mesh.texture_source = "own";
    }
    e.mesh.repeat = ref.repeat;
    layouts.push_back(std::move(e));
  }
  if (o.flatten) {
    if (progress) progress("flatten", 0, 1);
    Entry e;
    e.mesh = ref;
    e.mesh.name = "flatten", e.mesh.file = "";
    nlohmann::ordered_json info;
    e.mesh.uvs = detail::isometric_uvs(ref, &e.aspect, &info);
    e.mesh.uv_area = 0;
    for (size_t t = 0; t < e.mesh.indices.size() / 3; ++t) e.mesh.uv_area += detail::uv_area(e.mesh.uvs, e.mesh.indices, t);
    e.mesh.repeat = false;
    e.mesh.tangents.clear();  // new UVs: the frame comes from them (normal maps re-baked into it)
    e.isometric = std::move(info);
    rebake_into(e);
    layouts.push_back(std::move(e));
  }

  // Contact sheet cost: the grid point nearest the request (default 0.25).
  const double want = o.contact_cost > 0 ? o.contact_cost : 0.25;
  double contact = o.cost_grid.front();
  for (double c : o.cost_grid)
    if (std::abs(std::log(c / want)) < std::abs(std::log(contact / want))) contact = c;
  const uint32_t thumb = std::clamp<uint32_t>(o.thumbnail, 8, 1024);
  if (artifacts && o.artifacts) {
    artifacts->reference_contact = contact_sheet(engine, ref, ref.full, cameras, thumb, o.filter);
    artifacts->layouts.clear();
  }

  EvalResult r;
  r.asset = reference.path;
  r.device = engine.device();
  r.views = cameras.size();
  r.resolution = s.resolution;
  r.resolution_cap = o.resolution_cap;
  r.noise_floor_measured = o.noise_floor;
  r.fov_degrees = o.fov_degrees;
  r.filter = o.filter;
  r.lit = s.lit;
  r.shading_requested = o.shading;
  r.shading_warning = s.shading_warning;
  if (s.lit && o.noise_floor) r.noise_floor_unlit = s.noise_floor_unlit, r.noise_floor_lit = s.noise_floor_lit;
  r.triangles = ref.indices.size() / 3;
  r.reference = {reference.path, ref.image,     ref.full.width,    ref.full.height,
                 ref.uv_area,    s.image_texels, s.chart_texels, reference_bytes.size(),
                 bytes_axis ? io::describe(encoding) : std::string()};
  r.cost_axis = o.cost_axis;
  r.codec = o.codec;
  r.cost_grid = o.cost_grid;
  r.contact_c_r = contact;

  const Resizer area = area_resize(), lanczos_srgb = lanczos_resize(false), lanczos_linear = lanczos_resize(true);
  const Resizer* users = nullptr;  // the input's winning resize, once its curve is done (it comes first)
  struct Curve {
    std::vector<CurvePoint> points;
    double mean_log_q = 0;
  };
  size_t step = 0;
  const size_t steps = (layouts.size() + 1) * o.cost_grid.size();
  auto run_curve = [&](const LayoutMesh& m, double aspect, const Resizer& resize, bool encode = true) {
    // Unlit, every cost's textures first, then one scoring of them all (score_views_many);
    // lit, cost by cost (each cost's maps are three channels a map: ten at once would hold
    // gigabytes for a 2048-px asset, and lit curves render each cost on its own anyway).
    const size_t group = s.lit ? 1 : o.cost_grid.size();
    std::vector<Scores> scores;
    std::vector<std::optional<uint64_t>> bytes(o.cost_grid.size());  // along bytes, where encoded here
    for (size_t first = 0; first < o.cost_grid.size(); first += group) {
      std::vector<LayoutTextures> textures;
      for (size_t i = first; i < std::min(o.cost_grid.size(), first + group); ++i) {
        auto [W, H] = size_at(o.cost_grid[i], s.image_texels, aspect);
        const Stopwatch t0;
        const Image tex = resize.colour(m.full, W, H);
        if (bytes_axis && encode) bytes[i] = encoded_bytes(tex);
        timing.textures += t0.seconds();
        textures.push_back(layout_textures(s, m, tex, &resize, true, timing));
      }
      if (progress) progress("curve " + m.name, step, steps);
      for (Scores& sc : score_views_many(engine, s, m, textures, timing)) scores.push_back(std::move(sc));
      step += textures.size();
    }
    Curve c;
    for (size_t i = 0; i < o.cost_grid.size(); ++i) {
      const double c_r = o.cost_grid[i];
      auto [W, H] = size_at(c_r, s.image_texels, aspect);
      Scores& sc = scores[i];
      CurvePoint p;
      p.c_r = c_r;
      p.c_r_actual = double(W) * H / s.image_texels;
      p.c_r_chart = double(W) * H * m.uv_area / s.chart_texels;
      p.width = W, p.height = H;
      p.q = sc.q;
      if (s.lit) p.q_unlit = sc.q_unlit, p.q_lit = sc.q_lit;
      p.q_views = std::move(sc.views);
      if (s.codec) p.codec_bytes = codec_bytes(s, W, H);
      if (bytes[i]) p.bytes = bytes[i], p.bytes_ratio = double(*bytes[i]) / double(reference_bytes.size());
      c.mean_log_q += std::log(std::max(p.q, 1e-9)) / double(o.cost_grid.size());  // q = 0: a perfect copy
      c.points.push_back(std::move(p));
    }
    return c;
  };

  for (auto& e : layouts) {
    const LayoutMesh& m = e.mesh;
    LayoutResult L;
    L.name = m.name;
    L.file = m.file;
    L.texture = m.texture_source;
    L.full_size[0] = m.full.width, L.full_size[1] = m.full.height;
    L.uv_area = m.uv_area;
    Image plot = uv_plot(m, e.aspect, &L.texel_density_spread_log2);
    L.isometric = std::move(e.isometric);
    L.rebake = e.rebake;
    Curve curve;
    const Resizer* resize = &area;
    if (e.users_resize) {
      // The baseline a user gets from a one-line resize: Lanczos-3 in stored sRGB values
      // (most tools) or in linear light (careful ones), whichever scores better over the
      // grid, so a layout that beats it beats both.
      Curve srgb = run_curve(m, e.aspect, lanczos_srgb, false), linear = run_curve(m, e.aspect, lanczos_linear, false);
      const bool use_linear = linear.mean_log_q < srgb.mean_log_q;
      r.input_resize = use_linear ? "lanczos3-linear" : "lanczos3-srgb";
      L.resize = r.input_resize;
      L.resize_mean_log_q = std::make_pair(srgb.mean_log_q, linear.mean_log_q);
      curve = use_linear ? std::move(linear) : std::move(srgb);
      resize = users = use_linear ? &lanczos_linear : &lanczos_srgb;
      if (bytes_axis)  // only the variant kept is encoded (each encoding is the costly part)
        for (CurvePoint& p : curve.points) {
          const Stopwatch t0;
          p.bytes = encoded_bytes(resize->colour(m.full, p.width, p.height));
          p.bytes_ratio = double(*p.bytes) / double(reference_bytes.size());
          timing.textures += t0.seconds();
        }
    } else if (users && !e.paper_filter) {
      // Every other layout's full texture is brought to each c_r by the same resize as the
      // input's, so the curves differ by their layouts (and their full textures), not by
      // the filter that shrinks them.
      curve = run_curve(m, e.aspect, *users);
      resize = users;
      L.resize = r.input_resize;
    } else {
      curve = run_curve(m, e.aspect, area);
      L.resize = "area";
    }
    if (e.scored_as_written) {
      CurvePoint w;
      w.c_r = e.as_written.c_r, w.c_r_chart = e.as_written.c_r_chart, w.q = e.as_written.q;
      w.q_unlit = e.as_written.q_unlit, w.q_lit = e.as_written.q_lit;
      w.width = e.written_size[0], w.height = e.written_size[1];
      w.q_views = std::move(e.as_written.q_views);
      if (bytes_axis) w.bytes = e.written_bytes, w.bytes_ratio = double(e.written_bytes) / double(reference_bytes.size());
      L.as_written = std::move(w);
    }
    L.curve = std::move(curve.points);
    if (artifacts && o.artifacts) {
      auto [W, H] = size_at(contact, s.image_texels, e.aspect);
      LayoutArtifacts a;
      a.name = m.name;
      a.contact = contact_sheet(engine, m, resize->colour(m.full, W, H), cameras, thumb, o.filter);
      a.uv_plot = plot;
      artifacts->layouts.push_back(std::move(a));
    }
    r.layouts.push_back(std::move(L));
  }

  // Savings: every layout against the input's, and against the paper's baseline and the
  // isometric layout when present.
  std::vector<size_t> bases = {0};
  if (o.paper_baseline) bases.push_back(1);
  if (o.flatten) bases.push_back(layouts.size() - 1);
  for (size_t b : bases)
    for (size_t a = 0; a < layouts.size(); ++a) {
      if (a == b || (b != 0 && a == 0)) continue;
      r.savings.push_back({r.layouts[a].name, r.layouts[b].name,
                           pixel_ratio_at_equal_q(r.layouts[a].cost_q(o.cost_axis), r.layouts[b].cost_q(o.cost_axis),
                                                  s.resolution.noise_floor)});
    }
  r.seconds = {timing.textures, timing.render, timing.gmsd, timing.shading, t_start.seconds()};
  if (progress) progress("done", steps, steps);
  return r;
}

}  // namespace uvpress::eval
