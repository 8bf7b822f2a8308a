// Whole-mesh renders on the CPU: the reference for render_mesh.comp (same integer
// rasterization, same fp32 operations in the same order per pixel) and the Engine default.
#include "mesh_render.h"

#include "backend.h"
#include "gmsd.h"
#include "parallel_for.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

namespace uvpress::engine {
namespace mesh {

namespace {

int32_t edge(int32_t ax, int32_t ay, int32_t bx, int32_t by, int32_t px, int32_t py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

bool owns_edge(int32_t ax, int32_t ay, int32_t bx, int32_t by) {
  const int32_t dx = bx - ax, dy = by - ay;
  return dy > 0 || (dy == 0 && dx < 0);
}

inline float plane(const float c[3], float fx, float fy) {
  float v = c[0] + c[1] * fx;
  v += c[2] * fy;
  return v;
}

// i wrapped into [0, n): most coordinates already are (one compare instead of a division).
int32_t wrap(int32_t i, int32_t n) {
  if (uint32_t(i) < uint32_t(n)) return i;
  const int32_t r = i % n;
  return r < 0 ? r + n : r;
}

// A texture as the sampler reads it: each mip level's texels, size, and the scale from
// level-0 texel centres to its own (level l: s_l + 0.5 = (s + 0.5) W_l / W), worked out
// once per texture rather than at every sample.
struct Sampler {
  struct Level {
    const float* texels;
    int32_t width, height;
    float scale_s, scale_t;
  };
  Level levels[32];
  uint32_t level_count = 1, channels = 1;
  bool repeat = false;

  explicit Sampler(const MeshRenderDesc& d) : level_count(d.mip_levels), channels(d.channels), repeat(d.repeat) {
    for (uint32_t l = 0; l < level_count; ++l) {
      Level& L = levels[l];
      L.width = int32_t(std::max(1u, d.texture_width >> l)), L.height = int32_t(std::max(1u, d.texture_height >> l));
      L.texels = d.texture + mip_chain_texels(d.texture_width, d.texture_height, l) * d.channels;
      L.scale_s = float(L.width) / float(d.texture_width);
      L.scale_t = float(L.height) / float(d.texture_height);
    }
  }

  // Adds weight x the bilinear sample of level `level` at level-0 texel coordinates (s, t)
  // to out (first: out = instead of +=). CC: the channel count (1..4), a constant so that
  // the per-channel loop unrolls: eval samples ten textures of one channel a pixel (Duck's
  // eval --flatten went 10.0 -> 7.9-8.5 s with this change alone).
  template <uint32_t CC>
  __attribute__((always_inline)) void bilinear(uint32_t level, float s, float t, float weight, float* out,
                                               bool first) const {
    const Level& L = levels[level];
    const int32_t TW = L.width, TH = L.height;
    if (level > 0) {
      s = (s + 0.5f) * L.scale_s - 0.5f;
      t = (t + 0.5f) * L.scale_t - 0.5f;
    }
    int32_t i0, j0, i1, j1;
    float fs, ft;
    if (repeat) {
      s = std::min(std::max(s, -16777216.0f), 16777216.0f);
      t = std::min(std::max(t, -16777216.0f), 16777216.0f);
      const float fs0 = std::floor(s), ft0 = std::floor(t);
      fs = s - fs0, ft = t - ft0;
      i0 = wrap(int32_t(fs0), TW), j0 = wrap(int32_t(ft0), TH);
      i1 = i0 + 1 == TW ? 0 : i0 + 1, j1 = j0 + 1 == TH ? 0 : j0 + 1;
    } else {
      s = std::min(std::max(s, 0.0f), float(TW - 1));
      t = std::min(std::max(t, 0.0f), float(TH - 1));
      const float fs0 = std::floor(s), ft0 = std::floor(t);
      fs = s - fs0, ft = t - ft0;
      i0 = int32_t(fs0), j0 = int32_t(ft0);
      i1 = std::min(i0 + 1, TW - 1), j1 = std::min(j0 + 1, TH - 1);
    }
    constexpr uint32_t C = CC;
    const float* t00 = L.texels + (size_t(j0) * size_t(TW) + size_t(i0)) * C;
    const float* t10 = L.texels + (size_t(j0) * size_t(TW) + size_t(i1)) * C;
    const float* t01 = L.texels + (size_t(j1) * size_t(TW) + size_t(i0)) * C;
    const float* t11 = L.texels + (size_t(j1) * size_t(TW) + size_t(i1)) * C;
    for (uint32_t c = 0; c < C; ++c) {
      float top = (1.0f - fs) * t00[c];
      top += fs * t10[c];
      float bottom = (1.0f - fs) * t01[c];
      bottom += fs * t11[c];
      float v = (1.0f - ft) * top;
      v += ft * bottom;
      if (first)
        out[c] = weight == 1.0f ? v : weight * v;
      else
        out[c] += weight * v;
    }
  }

  // The texture at texel coordinates (s, t), level of detail lambda (engine.h): level 0 when
  // lambda <= 0, else the two nearest levels blended.
  template <uint32_t CC>
  __attribute__((always_inline)) void trilinear(float s, float t, float lambda, float* out) const {
    const float lod = level_count > 1 ? std::min(lambda, float(level_count - 1)) : 0.0f;
    if (!(lod > 0.0f)) {
      bilinear<CC>(0, s, t, 1.0f, out, true);
      return;
    }
    const uint32_t l0 = uint32_t(std::floor(lod)), l1 = std::min(l0 + 1, level_count - 1);
    const float f = lod - float(l0);
    bilinear<CC>(l0, s, t, 1.0f - f, out, true);
    bilinear<CC>(l1, s, t, f, out, false);
  }
};

// What sampling needs at one pixel centre (cx, cy) of triangle r: the texel coordinates
// and the level of detail lambda = log2 rho before clamping (0 without mips).
struct Footprint {
  float s, t, lambda;
};
__attribute__((always_inline)) inline Footprint footprint(const MeshTriangle& r, float cx, float cy, bool mips) {
  const float fx = cx - float(r.x0) * 0.0625f, fy = cy - float(r.y0) * 0.0625f;
  const float iw = plane(r.inv_w, fx, fy);
  Footprint f;
  f.s = plane(r.s_w, fx, fy) / iw;
  f.t = plane(r.t_w, fx, fy) / iw;
  f.lambda = 0.0f;
  if (mips) {
    // d(s, t)/d(x, y) of s = S / Iw with S, Iw affine: (S_x - s Iw_x) / Iw.
    const float s_x = (r.s_w[1] - f.s * r.inv_w[1]) / iw, s_y = (r.s_w[2] - f.s * r.inv_w[2]) / iw;
    const float t_x = (r.t_w[1] - f.t * r.inv_w[1]) / iw, t_y = (r.t_w[2] - f.t * r.inv_w[2]) / iw;
    const float rho = std::max(std::sqrt(s_x * s_x + t_x * t_x), std::sqrt(s_y * s_y + t_y * t_y));
    // Magnified (rho <= 1, lambda <= 0) samples level 0 whatever lambda is: the sampler
    // and every texture's lambda_offset (<= 0: the space is the largest texture) keep it at
    // or below 0. Eval's views resolve 95 % of the surface, so most pixels skip the log.
    f.lambda = rho > 1.0f ? std::log2(rho) : 0.0f;
  }
  return f;
}

// One texture of Engine::render_mesh_textures against the texel space the views were set
// up in (the largest texture's): its texel coordinates are the space's scaled by (kx, ky)
// about texel centres, its level of detail the space's plus lambda_offset (engine.h);
// same_space: the space's own size, sampled from the space's coordinates as they are.
struct TextureInSpace {
  Sampler sampler;
  float kx = 1, ky = 1, lambda_offset = 0;
  bool same_space = true;
};

// The nearest triangle at each pixel of tile (tx, ty): best[(j - j0) kMeshTile + (i - i0)]
// is an index into setup.triangles, or kNoMeshTriangle where the pixel is empty.
// Visibility triangle by triangle over the rows of its snapped box only (the kernel walks
// the list pixel by pixel; the same updates in the same order per pixel, so the same
// winner): most triangles of a detailed mesh cover a few pixels of the tile. Each row is
// one pass over the tile's kMeshTile pixels, those outside the box masked: no branch per
// pixel, so the compiler runs the row in vector lanes (AVX2 where the CPU has it, chosen
// at load time); the integer edge tests are exact and the depth plane is the same fp32
// operations per pixel (engine/CMakeLists.txt: no contraction), so the same bits either way.
// Visibility is half of the shading time of a one-texture render (reparam's candidates).
__attribute__((target_clones("avx2", "default")))
void visible_in_tile(const MeshRenderDesc& d, const ViewSetup& setup, uint32_t tx, uint32_t ty, uint32_t* best_of) {
  const uint32_t bin = ty * tiles_x(d) + tx;
  const uint32_t first = setup.bin_offsets[bin], last = setup.bin_offsets[bin + 1];
  const uint32_t i0 = tx * shader::kMeshTile, i1 = std::min(d.width, (tx + 1) * shader::kMeshTile);
  const uint32_t j0 = ty * shader::kMeshTile, j1 = std::min(d.height, (ty + 1) * shader::kMeshTile);
  constexpr uint32_t T = shader::kMeshTile;
  float best_z_of[T * T] = {};
  std::fill(best_of, best_of + T * T, kNoMeshTriangle);
  // Pixel centres of the tile's columns, in 1/16 pixel and in pixels.
  int32_t px_of[T];
  float cx_of[T];
  for (uint32_t a = 0; a < T; ++a) px_of[a] = 16 * int32_t(i0 + a) + 8, cx_of[a] = float(i0 + a) + 0.5f;
  for (uint32_t k = first; k < last; ++k) {
    const uint32_t id = setup.bin_items[k];
    const MeshTriangle& r = setup.triangles[id];
    // Pixel centres (16 i + 8) inside the box, clamped to the tile.
    const int32_t bx0 = std::min({r.x0, r.x1, r.x2}), bx1 = std::max({r.x0, r.x1, r.x2});
    const int32_t by0 = std::min({r.y0, r.y1, r.y2}), by1 = std::max({r.y0, r.y1, r.y2});
    const int32_t lo_i = std::max(int32_t(i0), (bx0 - 8 + 15) >> 4), hi_i = std::min(int32_t(i1) - 1, (bx1 - 8) >> 4);
    const int32_t lo_j = std::max(int32_t(j0), (by0 - 8 + 15) >> 4), hi_j = std::min(int32_t(j1) - 1, (by1 - 8) >> 4);
    if (lo_i > hi_i) continue;
    // A pixel on an edge belongs to the triangle that owns the edge: e > -1 or e > 0.
    const int32_t bias0 = owns_edge(r.x1, r.y1, r.x2, r.y2) ? -1 : 0;
    const int32_t bias1 = owns_edge(r.x2, r.y2, r.x0, r.y0) ? -1 : 0;
    const int32_t bias2 = owns_edge(r.x0, r.y0, r.x1, r.y1) ? -1 : 0;
    const float x0 = float(r.x0) * 0.0625f, y0 = float(r.y0) * 0.0625f;
    const float w0 = r.inv_w[0], w1 = r.inv_w[1], w2 = r.inv_w[2];
    const int32_t ax = r.x0, ay = r.y0, bx = r.x1, by = r.y1, cx = r.x2, cy = r.y2;
    const int32_t a_lo = lo_i - int32_t(i0), a_hi = hi_i - int32_t(i0);
    for (int32_t j = lo_j; j <= hi_j; ++j) {
      const int32_t py = 16 * j + 8;
      const float fy = (float(j) + 0.5f) - y0;
      uint32_t* __restrict best = best_of + size_t(j - int32_t(j0)) * T;
      float* __restrict best_z = best_z_of + size_t(j - int32_t(j0)) * T;
      for (int32_t a = 0; a < int32_t(T); ++a) {
        const int32_t px = px_of[a];
        const int32_t e0 = edge(bx, by, cx, cy, px, py), e1 = edge(cx, cy, ax, ay, px, py), e2 = edge(ax, ay, bx, by, px, py);
        // plane(r.inv_w, fx, fy), written out.
        float z = w0 + w1 * (cx_of[a] - x0);
        z += w2 * fy;
        // Bitwise, not short-circuit: no branch in the lane.
        const int inside = (a >= a_lo) & (a <= a_hi) & (e0 > bias0) & (e1 > bias1) & (e2 > bias2);
        const int nearer = (best[a] == kNoMeshTriangle) | (z > best_z[a]);
        const int take = inside & nearer;
        best[a] = take ? id : best[a];
        best_z[a] = take ? z : best_z[a];
      }
    }
  }
}

// The m covered pixels of a tile (their footprints fp and positions at in the image)
// sampled from texture x into out, CC channels a pixel.
template <uint32_t CC>
__attribute__((always_inline)) inline void sample_tile(const TextureInSpace& x, const Footprint* fp, const size_t* at,
                                                       uint32_t m, float* out) {
  if (x.same_space) {
    for (uint32_t q = 0; q < m; ++q) x.sampler.trilinear<CC>(fp[q].s, fp[q].t, fp[q].lambda, out + at[q] * CC);
    return;
  }
  // Texel centres of the texture: s_k + 0.5 = (s + 0.5) kx, as between mip levels.
  for (uint32_t q = 0; q < m; ++q)
    x.sampler.trilinear<CC>((fp[q].s + 0.5f) * x.kx - 0.5f, (fp[q].t + 0.5f) * x.ky - 0.5f, fp[q].lambda + x.lambda_offset,
                            out + at[q] * CC);
}

// Shades tile (tx, ty) of one view for every texture: one visibility pass and one
// footprint per pixel, then every texture sampled; writes coverage (unless null) and pixels
// of the camera's image (width x height, at `coverage` and `pixels`, rows row_stride apart:
// a tile of a whole view, mesh::image_place; pixel (ox, oy) first: a buffer of the tile
// alone), texture k's pixels texture_stride floats after texture k - 1's. render_mesh.comp
// mirrors it, one texture, operation for operation.
__attribute__((target_clones("avx2", "default")))
void shade_tile(const MeshRenderDesc& d, const std::vector<TextureInSpace>& textures, const ViewSetup& setup,
                uint32_t tx, uint32_t ty, size_t texture_stride, size_t row_stride, uint32_t* coverage, float* pixels,
                uint32_t ox = 0, uint32_t oy = 0) {
  constexpr uint32_t T = shader::kMeshTile;
  uint32_t best_of[T * T];
  visible_in_tile(d, setup, tx, ty, best_of);
  bool mips = false;
  for (const TextureInSpace& k : textures) mips = mips || k.sampler.level_count > 1;
  const uint32_t C = d.channels;
  const uint32_t i0 = tx * T, i1 = std::min(d.width, (tx + 1) * T);
  const uint32_t j0 = ty * T, j1 = std::min(d.height, (ty + 1) * T);
  // The covered pixels' footprints first, then texture after texture (one texture's
  // levels stay in the cache while the tile samples it).
  size_t at[T * T];
  Footprint fp[T * T];
  uint32_t m = 0;
  bool empty_row[T] = {};
  for (uint32_t j = j0; j < j1; ++j)
    for (uint32_t i = i0; i < i1; ++i) {
      const uint32_t best = best_of[(j - j0) * T + (i - i0)];
      const size_t p = size_t(j - oy) * row_stride + (i - ox);
      if (best == kNoMeshTriangle) {
        if (coverage) coverage[p] = kNoMeshTriangle;
        empty_row[j - j0] = true;
        continue;
      }
      const MeshTriangle& r = setup.triangles[best];
      if (coverage) coverage[p] = r.index;
      at[m] = p, fp[m] = footprint(r, float(i) + 0.5f, float(j) + 0.5f, mips), ++m;
    }
  // Empty pixels are 0: each tile row that has one is cleared whole, texture by texture,
  // and its covered pixels then sampled over it. One contiguous run a row instead of a
  // store a pixel into every texture's image in turn (those scattered stores were a third
  // of the shading time of eval's ten-texture renders). A whole tile's row is a constant
  // size, which the compiler clears with a few vector stores (a memset call a row cost as
  // much as it saved).
  const size_t row_floats = size_t(i1 - i0) * C;
  const bool whole = i1 - i0 == T;
  for (size_t k = 0; k < textures.size(); ++k)
    for (uint32_t j = j0; j < j1; ++j) {
      if (!empty_row[j - j0]) continue;
      float* row = pixels + k * texture_stride + (size_t(j - oy) * row_stride + (i0 - ox)) * C;
      if (!whole) {
        std::fill(row, row + row_floats, 0.0f);
        continue;
      }
      switch (C) {
        case 1: std::memset(row, 0, T * sizeof(float)); break;
        case 2: std::memset(row, 0, 2 * T * sizeof(float)); break;
        case 3: std::memset(row, 0, 3 * T * sizeof(float)); break;
        default: std::memset(row, 0, 4 * T * sizeof(float)); break;
      }
    }
  for (size_t k = 0; k < textures.size(); ++k) {
    float* out = pixels + k * texture_stride;
    switch (C) {
      case 1: sample_tile<1>(textures[k], fp, at, m, out); break;
      case 2: sample_tile<2>(textures[k], fp, at, m, out); break;
      case 3: sample_tile<3>(textures[k], fp, at, m, out); break;
      default: sample_tile<4>(textures[k], fp, at, m, out); break;  // check_mesh_render: 1..4
    }
  }
}

}  // namespace
}  // namespace mesh

void size_mesh_renders(const MeshRenderDesc& d, MeshRenders& out, uint32_t textures) {
  check_mesh_render(d);
  out.width = d.width, out.height = d.height, out.count = uint32_t(d.cameras.size()), out.channels = d.channels;
  out.textures = textures;
  const size_t n = size_t(d.width) * d.height;
  out.coverage.resize(d.coverage ? n * out.count : 0);
  const auto [w, h] = view_size(d);
  const size_t views = d.cameras.size() / (size_t(d.view_tiles_x) * d.view_tiles_y);
  out.pixels.resize(size_t(w) * h * views * d.channels * textures);
}

namespace {

// Engine::render_mesh and render_mesh_textures on the CPU: the views set up in the texel
// space of the largest texture (the fewest rounding steps for the others), then tile rows
// of every view; results depend only on the work item, not on the thread count.
void render_on_cpu(const Engine& engine, const MeshRenderDesc& d, const std::vector<MeshTexture>& textures,
                   MeshRenders& out) {
  if (textures.empty()) throw EngineError("render_mesh_textures: no texture");
  size_t largest = 0;
  for (size_t k = 1; k < textures.size(); ++k)
    if (uint64_t(textures[k].width) * textures[k].height > uint64_t(textures[largest].width) * textures[largest].height)
      largest = k;
  std::vector<mesh::TextureInSpace> in_space;
  for (const MeshTexture& t : textures) {
    MeshRenderDesc dk = d;
    dk.cameras.clear(), dk.triangle_count = 0;  // the views are checked with `space` below
    dk.texture = t.texels, dk.texture_width = t.width, dk.texture_height = t.height, dk.mip_levels = t.mip_levels;
    check_mesh_render(dk);
    const double kx = double(t.width) / textures[largest].width, ky = double(t.height) / textures[largest].height;
    in_space.push_back({mesh::Sampler(dk), float(kx), float(ky), float(0.5 * std::log2(kx * ky)), kx == 1.0 && ky == 1.0});
  }
  MeshRenderDesc space = d;
  space.texture = textures[largest].texels;
  space.texture_width = textures[largest].width, space.texture_height = textures[largest].height;
  space.mip_levels = textures[largest].mip_levels;
  size_mesh_renders(space, out, uint32_t(textures.size()));
  const size_t n = size_t(d.width) * d.height, stride = n * out.count * d.channels;
  const uint32_t tx = mesh::tiles_x(d), ty = mesh::tiles_y(d);
  std::vector<mesh::ViewSetup> setups(out.count);
  const unsigned threads = host_threads(engine);
  parallel_for(out.count, threads, [&](uint32_t v) { setups[v] = mesh::setup_view(space, v); }, 1);
  if (!d.halve) {
    parallel_for(out.count * ty, threads, [&](uint32_t item) {
      const uint32_t v = item / ty, row = item % ty;
      const mesh::ImagePlace at = mesh::image_place(d, v);
      for (uint32_t a = 0; a < tx; ++a)
        mesh::shade_tile(space, in_space, setups[v], a, row, stride, at.row_stride,
                         d.coverage ? out.coverage.data() + at.origin : nullptr,
                         out.pixels.data() + at.origin * d.channels);
    }, 1);
    return;
  }
  // Halved (MeshRenderDesc::halve): each tile shaded into a buffer of its own, then
  // halved into place by gmsd_downsample. Tiles start on even pixels of their views (tile
  // and view-tile sides even, check_mesh_render), so a tile's 2 x 2 blocks are the view's,
  // and the zero padding of an odd side falls where the view ends.
  const size_t half_stride = out.pixels.size() / textures.size();  // a texture's halved views
  constexpr uint32_t T = shader::kMeshTile;
  parallel_for(out.count * ty, threads, [&](uint32_t item) {
    const uint32_t v = item / ty, row = item % ty;
    const mesh::ImagePlace at = mesh::image_place(d, v);
    thread_local std::vector<float> tile, half;
    tile.resize(textures.size() * T * T), half.resize(T * T / 4);
    const uint32_t th = std::min(T, d.height - row * T);
    for (uint32_t a = 0; a < tx; ++a) {
      const uint32_t tw = std::min(T, d.width - a * T), w2 = (tw + 1) / 2, h2 = (th + 1) / 2;
      mesh::shade_tile(space, in_space, setups[v], a, row, size_t(T) * T, tw, nullptr, tile.data(), a * T, row * T);
      for (size_t k = 0; k < textures.size(); ++k) {
        cpu::gmsd_downsample(tile.data() + k * T * T, tw, th, half.data());
        float* to = out.pixels.data() + k * half_stride + at.origin + size_t(row * T / 2) * at.row_stride + a * T / 2;
        // A whole tile's half rows are a constant size, copied inline (a memmove call for
        // every 8 floats was 3 % of Fox's eval).
        if (w2 == T / 2)
          for (uint32_t j = 0; j < h2; ++j) std::memcpy(to + j * at.row_stride, &half[size_t(j) * w2], T / 2 * sizeof(float));
        else
          for (uint32_t j = 0; j < h2; ++j) std::copy_n(&half[size_t(j) * w2], w2, to + j * at.row_stride);
      }
    }
  }, 1);
}

}  // namespace

unsigned host_threads(const Engine& engine) {
  const DeviceInfo device = engine.device();
  return std::max(1u, device.backend == "cpu" ? device.threads : std::thread::hardware_concurrency());
}

void Engine::render_mesh(const MeshRenderDesc& d, MeshRenders& out) {
  render_on_cpu(*this, d, {{d.texture, d.texture_width, d.texture_height, d.mip_levels}}, out);
}

void Engine::render_mesh_textures(const MeshRenderDesc& d, const std::vector<MeshTexture>& textures, MeshRenders& out) {
  render_on_cpu(*this, d, textures, out);
}

}  // namespace uvpress::engine
