// The Vulkan backend of the Engine interface: kernels created once, buffers kept and
// reused across calls, batches chunked to the device's buffer limit, every chunk one
// command buffer with many dispatches and one fence.
#include "compute.h"
#include "layout.h"

#include "downsample2x2.spv.h"
#include "gmsd.spv.h"
#include "luminance.spv.h"
#include "view_prepare.spv.h"
#include "view_score.spv.h"
#include "render_mesh.spv.h"
#include "rebake.spv.h"
#include "cpu/gmsd.h"
#include "cpu/parallel_for.h"
#include "mesh_render.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace uvpress::engine {
namespace {

using shader::GmsdPush;
using shader::ImageBatchPush;
using shader::ViewPush;

// Words of view_score.comp's scratch slot per candidate (its OFF_* layout).
constexpr uint64_t kScoreSlotBytes = 4ull * shader::kViewScoreSlotWords;
constexpr uint32_t kScoreChunk = 1024;  // candidates per submit, at most
constexpr uint64_t kScoreScratchBytes = 256ull << 20;  // and at most this much scratch (~1 MiB a slot)
constexpr uint32_t kWorkgroup = 256;

// Workgroup size of the one-workgroup-per-item kernels (view_score, gmsd): a multiple of 8.
// GPUs want many invocations; lavapipe runs a workgroup on one thread, 8 lanes at a time,
// and switches between its 8-lane slices at every barrier, so there the smallest
// workgroup (one slice, 8) was fastest. But lavapipe 22.3 mis-ran view_score with 8 and
// 16 invocations once its tiles grew past 32 texels (a two-chart view at J = I rendered
// no pixel; the CPU oracle and 32+ invocations agree): CPU devices take 32 (not root-
// caused; tests/engine/test_views.cpp's seam case catches it). UVPRESS_VIEW_WORKGROUP
// overrides (benchmarks).
uint32_t item_workgroup(const vk::Context& context) {
  if (const char* e = std::getenv("UVPRESS_VIEW_WORKGROUP")) {
    const long v = std::strtol(e, nullptr, 10);
    if (v >= 8 && v <= 1024 && v % 8 == 0) return uint32_t(v);
    throw EngineError("UVPRESS_VIEW_WORKGROUP must be a multiple of 8 in 8..1024");
  }
  return context.info().type == "cpu" ? 32 : kWorkgroup;
}

// A view set on the device: descriptors and triangles whole, coverage and reference
// renders in pages of views that each fit one buffer.
struct VulkanViewSet final : ViewSet {
  struct Page {
    uint32_t first, count;
    std::unique_ptr<vk::Buffer> coverage, reference;
  };
  uint32_t size_ = 0;
  std::vector<ViewDesc> views;
  std::unique_ptr<vk::Buffer> view_buffer, triangle_buffer;
  std::vector<Page> pages;
  uint32_t size() const override { return size_; }
  uint32_t view_count() const override { return uint32_t(views.size()); }
};


constexpr uint32_t kLocal = 16;  // 16x16 invocations: 256 threads, fine on GPUs and lavapipe

uint32_t groups(uint32_t n, uint32_t local) { return (n + local - 1) / local; }

// ---- Whole-mesh renders (render_mesh.comp) ----
// Its own kernel and buffers, made on first use (eval is the only user). Views go in
// chunks whose set-up triangles, bins and outputs each fit one device buffer.
class MeshRenderer {
 public:
  MeshRenderer(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer)
      : context_(context), sequence_(sequence), max_buffer_(max_buffer),
        kernel_(context, render_mesh_spv, sizeof(render_mesh_spv), 6, sizeof(shader::MeshPush), shader::kMeshTile,
                shader::kMeshTile) {}

  MeshRenders render(const MeshRenderDesc& d) {
    MeshRenders out = sized_mesh_renders(d);
    const uint64_t n = uint64_t(d.width) * d.height;
    if (out.count == 0) return out;
    const uint64_t tex_bytes = 4ull * mip_chain_texels(d.texture_width, d.texture_height, d.mip_levels) * d.channels;
    if (tex_bytes > max_buffer_)
      throw EngineError("Vulkan render_mesh: the texture exceeds the device's largest buffer");
    vk::Buffer& texture = buffer(texture_, tex_bytes);
    std::memcpy(texture.data<float>(), d.texture, tex_bytes);
    const uint32_t tx = mesh::tiles_x(d), ty = mesh::tiles_y(d);
    const uint64_t bins = uint64_t(tx) * ty;
    std::vector<mesh::ViewSetup> setups(out.count);
    for (uint32_t v = 0; v < out.count; ++v) setups[v] = mesh::setup_view(d, v);
    for (uint32_t first = 0; first < out.count;) {
      // The longest run of views whose arrays fit.
      uint64_t tri = 0, items = 0;
      uint32_t count = 0;
      while (first + count < out.count) {
        const auto& s = setups[first + count];
        const uint64_t t2 = tri + s.triangles.size() * sizeof(shader::MeshTriangle), i2 = items + 4 * s.bin_items.size();
        const uint64_t pix = 4 * n * d.channels * (count + 1), offs = 4 * (bins * (count + 1) + 1);
        if (count > 0 && (t2 > max_buffer_ || i2 > max_buffer_ || pix > max_buffer_ || offs > max_buffer_)) break;
        if (count == 0 && (t2 > max_buffer_ || i2 > max_buffer_ || pix > max_buffer_))
          throw EngineError("Vulkan render_mesh: one view exceeds the device's largest buffer");
        tri = t2, items = i2, ++count;
      }
      vk::Buffer& triangles = buffer(triangles_, std::max<uint64_t>(tri, 4));
      vk::Buffer& offsets = buffer(offsets_, 4 * (bins * count + 1));
      vk::Buffer& bin_items = buffer(items_, std::max<uint64_t>(items, 4));
      vk::Buffer& coverage = buffer(coverage_, 4 * n * count);
      vk::Buffer& pixels = buffer(pixels_, 4 * n * d.channels * count);
      uint32_t t_base = 0, i_base = 0;
      for (uint32_t v = 0; v < count; ++v) {
        const auto& s = setups[first + v];
        std::memcpy(triangles.data<shader::MeshTriangle>() + t_base, s.triangles.data(),
                    s.triangles.size() * sizeof(shader::MeshTriangle));
        for (size_t k = 0; k < s.bin_items.size(); ++k) bin_items.data<uint32_t>()[i_base + k] = s.bin_items[k] + t_base;
        for (uint64_t b = 0; b < bins; ++b) offsets.data<uint32_t>()[v * bins + b] = s.bin_offsets[b] + i_base;
        t_base += uint32_t(s.triangles.size()), i_base += uint32_t(s.bin_items.size());
      }
      offsets.data<uint32_t>()[count * bins] = i_base;
      shader::MeshPush push{d.width,    d.height,          tx, ty, d.texture_width, d.texture_height, d.channels,
                            d.repeat ? 1u : 0u, d.mip_levels, 0, 0, 0};
      sequence_.begin();
      sequence_.dispatch(kernel_, {&triangles, &offsets, &bin_items, &texture, &coverage, &pixels}, &push, tx, ty, count);
      sequence_.submit_and_wait();
      std::memcpy(out.coverage.data() + first * n, coverage.data<uint32_t>(), 4 * n * count);
      std::memcpy(out.pixels.data() + first * n * d.channels, pixels.data<float>(), 4 * n * d.channels * count);
      first += count;
    }
    return out;
  }

 private:
  vk::Buffer& buffer(std::unique_ptr<vk::Buffer>& slot, uint64_t bytes) { return vk::reuse(context_, slot, bytes); }

  vk::Context& context_;
  vk::Sequence& sequence_;
  uint64_t max_buffer_;
  vk::Kernel kernel_;
  std::unique_ptr<vk::Buffer> texture_, triangles_, offsets_, items_, coverage_, pixels_;
};

// ---- Re-bake sampling (rebake.comp) ----
// Its own kernel and buffers, made on first use. The working source goes whole, split by
// texel index over four buffers; the new image goes in chunks of tile rows whose list
// entries, owners and texels each fit one buffer, every chunk one submit of several
// dispatches (kRebakeDispatchRows tile rows each, so no dispatch runs long on a GPU).
class Rebaker {
 public:
  Rebaker(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer)
      : context_(context), sequence_(sequence), max_buffer_(max_buffer),
        kernel_(context, rebake_spv, sizeof(rebake_spv), 8, sizeof(shader::RebakePush), kRebakeTile, kRebakeTile) {}

  void run(const RebakeTexelsDesc& d, float* texels) {
    check_rebake_texels(d);
    const uint32_t W = d.width, H = d.height, C = d.channels, T = kRebakeTile;
    const uint32_t tx = (W + T - 1) / T, ty = (H + T - 1) / T;
    // The source: texels split over up to four buffers.
    const uint64_t n_src = uint64_t(d.source_width) * d.source_height;
    const uint64_t split = std::min<uint64_t>(n_src, max_buffer_ / (4ull * C));
    if (split == 0 || (n_src + split - 1) / split > 4)
      throw EngineError("Vulkan rebake_texels: the source exceeds four of the device's largest buffers");
    const vk::Buffer* src[4];
    for (uint32_t b = 0; b < 4; ++b) {
      const uint64_t first = b * split, count = first < n_src ? std::min(split, n_src - first) : 0;
      if (count == 0) {
        src[b] = &buffer(dummy_, 16);
        continue;
      }
      vk::Buffer& s = buffer(source_[b], 4ull * C * count);
      std::memcpy(s.data<float>(), d.source + first * C, 4ull * C * count);
      src[b] = &s;
    }
    const uint64_t tiles = uint64_t(tx) * ty;
    if (4 * (tiles + 1) > max_buffer_) throw EngineError("Vulkan rebake_texels: too many tiles for one buffer");
    vk::Buffer& starts = buffer(starts_, 4 * (tiles + 1));
    std::memcpy(starts.data<uint32_t>(), d.tile_start, 4 * (tiles + 1));

    const uint64_t row_texels = uint64_t(W) * T;  // texels per tile row (the last may hold fewer)
    auto entries_of = [&](uint32_t r0, uint32_t r1) {
      return uint64_t(d.tile_start[uint64_t(r1) * tx] - d.tile_start[uint64_t(r0) * tx]);
    };
    for (uint32_t row0 = 0; row0 < ty;) {
      // The longest run of tile rows whose arrays fit.
      uint32_t rows = 0;
      while (row0 + rows < ty) {
        const uint32_t r = rows + 1;
        const bool fits = sizeof(shader::RebakeEntry) * entries_of(row0, row0 + r) <= max_buffer_ &&
                          4 * row_texels * r <= max_buffer_ && 4ull * C * row_texels * r <= max_buffer_;
        if (!fits) {
          if (rows == 0) throw EngineError("Vulkan rebake_texels: one tile row exceeds the device's largest buffer");
          break;
        }
        rows = r;
      }
      const uint32_t base = d.tile_start[uint64_t(row0) * tx];
      const uint64_t n_entries = entries_of(row0, row0 + rows);
      const uint32_t y0 = row0 * T, y1 = std::min(H, (row0 + rows) * T);
      const uint64_t n_texels = uint64_t(y1 - y0) * W;
      vk::Buffer& entries = buffer(entries_, std::max<uint64_t>(16, sizeof(shader::RebakeEntry) * n_entries));
      vk::Buffer& owner = buffer(owner_, 4 * n_texels);
      vk::Buffer& out = buffer(texels_, 4ull * C * n_texels);
      shader::RebakeEntry* e = entries.data<shader::RebakeEntry>();
      for (uint64_t tile = uint64_t(row0) * tx; tile < uint64_t(row0 + rows) * tx; ++tile) {
        const double ox = double((tile % tx) * T), oy = double((tile / tx) * T);
        for (uint32_t k = d.tile_start[tile]; k < d.tile_start[tile + 1]; ++k)
          e[k - base] = make_entry(d.triangles[d.tile_list[k]], ox, oy);
      }
      std::memcpy(owner.data<uint32_t>(), d.owner + uint64_t(y0) * W, 4 * n_texels);

      sequence_.begin();
      for (uint32_t r = row0; r < row0 + rows; r += kRebakeDispatchRows) {
        const uint32_t n = std::min(kRebakeDispatchRows, row0 + rows - r);
        shader::RebakePush push{W, H, tx, r, row0, base, d.source_width, d.source_height, C,
                                wrap_code(d.wrap_s), wrap_code(d.wrap_t), d.premultiplied ? 1u : 0u,
                                uint32_t(split), 0, 0, 0};
        sequence_.dispatch(kernel_, {src[0], src[1], src[2], src[3], &entries, &starts, &owner, &out}, &push, tx, n,
                           1);
      }
      sequence_.submit_and_wait();
      const float* result = out.data<float>();
      const uint32_t* own = d.owner + uint64_t(y0) * W;
      for (uint64_t i = 0; i < n_texels; ++i)
        if (own[i] != kRebakeNoOwner) std::memcpy(texels + (uint64_t(y0) * W + i) * C, result + i * C, 4ull * C);
      row0 += rows;
    }
  }

 private:
  static constexpr uint32_t kRebakeDispatchRows = 8;

  static uint32_t wrap_code(int mode) {
    return mode == kRebakeWrapClampToEdge ? 1u : mode == kRebakeWrapMirroredRepeat ? 2u : 0u;
  }

  // x = hi + lo with hi on a grid of 2^-12 (see shader::RebakeEntry).
  static void split(double x, float& hi, float& lo) {
    hi = float(std::round(x * 4096.0) / 4096.0);
    lo = float(x - double(hi));
  }

  // Triangle t in the frame of the tile whose corner is (ox, oy), computed in double.
  static shader::RebakeEntry make_entry(const RebakeTriangle& t, double ox, double oy) {
    shader::RebakeEntry e{};
    for (int k = 0; k < 3; ++k) {
      const double ax = t.n[k][0] - ox, ay = t.n[k][1] - oy;
      const double bx = t.n[(k + 1) % 3][0] - ox, by = t.n[(k + 1) % 3][1] - oy;
      const double dx = bx - ax, dy = by - ay, len = std::hypot(dx, dy);
      const double ux = len > 0 ? dx / len : 0, uy = len > 0 ? dy / len : 0;
      split(ux, e.uh[2 * k], e.ul[2 * k]);
      split(uy, e.uh[2 * k + 1], e.ul[2 * k + 1]);
      // The kernel's tangent and normal are uh + ul: use exactly those.
      const double vx = double(e.uh[2 * k]) + e.ul[2 * k], vy = double(e.uh[2 * k + 1]) + e.ul[2 * k + 1];
      const double nx = -vy * t.sign, ny = vx * t.sign;
      split(nx * ax + ny * ay, e.ch[k], e.cl[k]);
      split(vx * ax + vy * ay, e.s0h[k], e.s0l[k]);
      split(vx * bx + vy * by, e.s1h[k], e.s1l[k]);
    }
    e.sign = float(t.sign);
    const double J[4] = {t.J[0][0], t.J[0][1], t.J[1][0], t.J[1][1]};
    for (int k = 0; k < 4; ++k) split(J[k], e.jh[k], e.jl[k]);
    const double dx = ox - t.n[0][0], dy = oy - t.n[0][1];
    const double sx = t.o0[0] + t.J[0][0] * dx + t.J[0][1] * dy, sy = t.o0[1] + t.J[1][0] * dx + t.J[1][1] * dy;
    const double fx = std::floor(sx), fy = std::floor(sy);
    e.oi[0] = int(fx), e.oi[1] = int(fy);
    e.of[0] = float(sx - fx), e.of[1] = float(sy - fy);
    e.ns = uint32_t(t.ns[0]) | uint32_t(t.ns[1]) << 16;
    return e;
  }

  vk::Buffer& buffer(std::unique_ptr<vk::Buffer>& slot, uint64_t bytes) { return vk::reuse(context_, slot, bytes); }

  vk::Context& context_;
  vk::Sequence& sequence_;
  uint64_t max_buffer_;
  vk::Kernel kernel_;
  std::unique_ptr<vk::Buffer> source_[4], dummy_, starts_, entries_, owner_, texels_;
};

class VulkanEngine final : public Engine {
 public:
  VulkanEngine(DeviceRequest request, const EngineOptions& options)
      : context_(request, options.validation),
        max_buffer_(options.max_buffer_bytes ? std::min(options.max_buffer_bytes, context_.max_buffer_bytes())
                                             : context_.max_buffer_bytes()),
        luminance_(context_, luminance_spv, sizeof(luminance_spv), 2, sizeof(ImageBatchPush), kLocal, kLocal),
        downsample_(context_, downsample2x2_spv, sizeof(downsample2x2_spv), 2, sizeof(ImageBatchPush), kLocal,
                    kLocal),
        gmsd_(context_, gmsd_spv, sizeof(gmsd_spv), 3, sizeof(GmsdPush), item_workgroup(context_), 1),
        view_prepare_(context_, view_prepare_spv, sizeof(view_prepare_spv), 5, sizeof(ViewPush), kWorkgroup, 1),
        view_score_(context_, view_score_spv, sizeof(view_score_spv), 7, sizeof(ViewPush), item_workgroup(context_),
                    1),
        sequence_(context_) {}

  DeviceInfo device() const override { return context_.info(); }
  uint64_t validation_errors() const override { return context_.validation_errors(); }

  LuminanceBatch luminance(const Rgba8Batch& b) override {
    const uint64_t n = uint64_t(b.width) * b.height;
    const uint64_t n2 = uint64_t((b.width + 1) / 2) * ((b.height + 1) / 2);
    LuminanceBatch out;
    out.full.resize(n * b.count);
    out.half.resize(n2 * b.count);
    if (b.count == 0 || n == 0) return out;
    // RGBA8 in and float out are both 4 bytes a pixel: one image costs 4n bytes per buffer.
    const uint64_t per_chunk = std::min<uint64_t>(b.count, max_buffer_ / (4 * n));
    if (per_chunk == 0) throw EngineError("Vulkan: one image is larger than the device's largest buffer");
    vk::Buffer& rgba = buffer(rgba_, 4 * n * per_chunk);
    vk::Buffer& full = buffer(full_, 4 * n * per_chunk);
    vk::Buffer& half = buffer(half_, 4 * n2 * per_chunk);
    const uint32_t max_z = context_.limits().maxComputeWorkGroupCount[2];

    for (uint64_t first = 0; first < b.count; first += per_chunk) {
      const uint32_t count = uint32_t(std::min<uint64_t>(per_chunk, b.count - first));
      std::memcpy(rgba.data<uint32_t>(), b.pixels + first * n, 4 * n * count);
      sequence_.begin();
      for (uint32_t z = 0; z < count; z += max_z) {
        ImageBatchPush push{b.width, b.height, z, std::min(max_z, count - z)};
        sequence_.dispatch(luminance_, {&rgba, &full}, &push, groups(b.width, kLocal), groups(b.height, kLocal),
                           push.count);
      }
      sequence_.barrier();
      for (uint32_t z = 0; z < count; z += max_z) {
        ImageBatchPush push{b.width, b.height, z, std::min(max_z, count - z)};
        sequence_.dispatch(downsample_, {&full, &half}, &push, groups((b.width + 1) / 2, kLocal),
                           groups((b.height + 1) / 2, kLocal), push.count);
      }
      sequence_.submit_and_wait();
      std::memcpy(out.full.data() + first * n, full.data<float>(), 4 * n * count);
      std::memcpy(out.half.data() + first * n2, half.data<float>(), 4 * n2 * count);
    }
    return out;
  }

  std::vector<float> gmsd(const ImagePairs& pairs) override {
    std::vector<float> out(pairs.count);
    const uint64_t n = uint64_t(pairs.width) * pairs.height;
    if (pairs.count == 0 || n == 0) return out;
    if (pairs.width > shader::kViewMaxSize || pairs.height > shader::kViewMaxSize) {
      // gmsd.comp holds one image per workgroup in shared memory (64 x 64 at most): larger
      // ones (eval's views) are scored by the CPU reference, one image per thread.
      parallel_for(pairs.count, std::max(1u, std::thread::hardware_concurrency()), [&](uint32_t k) {
        out[k] = cpu::gmsd<float>(pairs.first + k * n, pairs.second + k * n, pairs.width, pairs.height);
      }, 1);
      return out;
    }
    const uint64_t per_chunk = std::min<uint64_t>(pairs.count, max_buffer_ / (4 * n));
    vk::Buffer& a = buffer(pair_a_, 4 * n * per_chunk);
    vk::Buffer& b = buffer(pair_b_, 4 * n * per_chunk);
    vk::Buffer& o = buffer(pair_out_, 4 * per_chunk);
    const uint32_t max_x = context_.limits().maxComputeWorkGroupCount[0];
    for (uint64_t first = 0; first < pairs.count; first += per_chunk) {
      const uint32_t count = uint32_t(std::min<uint64_t>(per_chunk, pairs.count - first));
      std::memcpy(a.data<float>(), pairs.first + first * n, 4 * n * count);
      std::memcpy(b.data<float>(), pairs.second + first * n, 4 * n * count);
      sequence_.begin();
      for (uint32_t x = 0; x < count; x += max_x) {
        GmsdPush push{pairs.width, pairs.height, x, std::min(max_x, count - x)};
        sequence_.dispatch(gmsd_, {&a, &b, &o}, &push, push.count, 1, 1);
      }
      sequence_.submit_and_wait();
      std::memcpy(out.data() + first, o.data<float>(), 4 * count);
    }
    return out;
  }

  std::unique_ptr<ViewSet> prepare_views(const ViewSetDesc& d) override {
    check_view_set(d);
    auto set = std::make_unique<VulkanViewSet>();
    set->size_ = d.size;
    set->views = d.views;
    if (d.views.empty()) return set;
    const uint64_t tex_bytes = 4ull * d.texture_width * d.texture_height;
    if (tex_bytes > max_buffer_)
      throw EngineError("Vulkan: the texture (" + std::to_string(d.texture_width) + "x" +
                        std::to_string(d.texture_height) + " floats) exceeds the device's largest buffer");
    set->view_buffer = upload(d.views.data(), d.views.size() * sizeof(ViewDesc));
    set->triangle_buffer = upload(d.triangles.data(), d.triangles.size() * sizeof(ViewTriangle));
    auto texture = upload(d.texture, tex_bytes);
    const uint64_t pixels = uint64_t(d.size) * d.size;
    // Reference floats bound a page: 4 bytes a pixel (coverage takes 1).
    const uint32_t per_page = uint32_t(std::min<uint64_t>(d.views.size(), max_buffer_ / (4 * pixels)));
    const uint32_t max_x = context_.limits().maxComputeWorkGroupCount[0];
    for (uint32_t first = 0; first < d.views.size(); first += per_page) {
      VulkanViewSet::Page page;
      page.first = first;
      page.count = std::min<uint32_t>(per_page, uint32_t(d.views.size()) - first);
      page.coverage = std::make_unique<vk::Buffer>(context_, pixels * page.count);
      page.reference = std::make_unique<vk::Buffer>(context_, 4 * pixels * page.count);
      sequence_.begin();
      for (uint32_t x = 0; x < page.count; x += max_x) {
        ViewPush push{d.size, first + x, std::min(max_x, page.count - x), d.texture_width, d.texture_height, first, 0, 0};
        sequence_.dispatch(view_prepare_,
                           {set->view_buffer.get(), set->triangle_buffer.get(), texture.get(), page.coverage.get(),
                            page.reference.get()},
                           &push, push.count, 1, 1);
      }
      sequence_.submit_and_wait();
      set->pages.push_back(std::move(page));
    }
    return set;
  }

  void score_views(ViewSet& views, const ViewCandidate* c, size_t count, float* gmsd, ViewImages* images,
                   float* lattice) override {
    auto* set = dynamic_cast<VulkanViewSet*>(&views);
    if (!set) throw EngineError("score_views: the view set belongs to another engine");
    const uint32_t S = set->size_;
    const size_t pixels = size_t(S) * S;
    for (size_t k = 0; k < count; ++k)
      if (c[k].view >= set->view_count()) throw EngineError("score_views: candidate names a view that does not exist");
    if (images) {
      images->coverage.resize(pixels * count), images->reference.resize(pixels * count);
      images->candidate.resize(pixels * count);
    }
    if (count == 0) return;
    const uint32_t chunk = uint32_t(
        std::min<uint64_t>({kScoreChunk, count, std::min(max_buffer_, kScoreScratchBytes) / kScoreSlotBytes}));
    vk::Buffer& cand = buffer(candidates_, sizeof(ViewCandidate) * chunk);
    vk::Buffer& scratch = buffer(scratch_, kScoreSlotBytes * chunk);
    vk::Buffer& results = buffer(results_, 8ull * chunk);  // gmsd, lattice
    for (const auto& page : set->pages) {
      // This page's candidates, in input order.
      std::vector<uint32_t> mine;
      for (size_t k = 0; k < count; ++k)
        if (c[k].view >= page.first && c[k].view < page.first + page.count) mine.push_back(uint32_t(k));
      for (size_t first = 0; first < mine.size(); first += chunk) {
        const uint32_t n = uint32_t(std::min<size_t>(chunk, mine.size() - first));
        for (uint32_t k = 0; k < n; ++k) cand.data<ViewCandidate>()[k] = c[mine[first + k]];
        sequence_.begin();
        ViewPush push{S, 0, n, 0, 0, page.first, images ? 1u : 0u, 0};
        sequence_.dispatch(view_score_,
                           {set->view_buffer.get(), set->triangle_buffer.get(), &cand, page.coverage.get(),
                            page.reference.get(), &scratch, &results},
                           &push, n, 1, 1);
        sequence_.submit_and_wait();
        for (uint32_t k = 0; k < n; ++k) {
          const uint32_t out = mine[first + k];
          gmsd[out] = results.data<float>()[2 * k];
          if (lattice) lattice[out] = results.data<float>()[2 * k + 1];
          if (!images) continue;
          const uint32_t local = c[out].view - page.first;
          std::memcpy(&images->coverage[out * pixels], page.coverage->data<uint8_t>() + local * pixels, pixels);
          std::memcpy(&images->reference[out * pixels], page.reference->data<float>() + local * pixels, 4 * pixels);
          // Candidate render: OFF_CAND of the slot.
          const float* slot = scratch.data<float>() + k * (kScoreSlotBytes / 4) +
                              2 * shader::kViewMaxSize * shader::kViewMaxSize;
          std::memcpy(&images->candidate[out * pixels], slot, 4 * pixels);
        }
      }
    }
  }

  // Whole-mesh renders: see MeshRenderer.
  MeshRenders render_mesh(const MeshRenderDesc& desc) override {
    if (!mesh_renderer_) mesh_renderer_ = std::make_unique<MeshRenderer>(context_, sequence_, max_buffer_);
    return mesh_renderer_->render(desc);
  }

  // Re-bake sampling: see Rebaker.
  void rebake_texels(const RebakeTexelsDesc& desc, float* texels) override {
    if (!rebaker_) rebaker_ = std::make_unique<Rebaker>(context_, sequence_, max_buffer_);
    rebaker_->run(desc, texels);
  }

 private:
  std::unique_ptr<vk::Buffer> upload(const void* data, uint64_t bytes) {
    auto b = std::make_unique<vk::Buffer>(context_, std::max<uint64_t>(bytes, 4));
    std::memcpy(b->data<uint8_t>(), data, bytes);
    return b;
  }

  // Keeps a buffer across calls and grows it only when a call needs more.
  vk::Buffer& buffer(std::unique_ptr<vk::Buffer>& slot, uint64_t bytes) { return vk::reuse(context_, slot, bytes); }

  vk::Context context_;
  uint64_t max_buffer_;
  vk::Kernel luminance_, downsample_, gmsd_, view_prepare_, view_score_;
  vk::Sequence sequence_;
  std::unique_ptr<vk::Buffer> rgba_, full_, half_;
  std::unique_ptr<vk::Buffer> pair_a_, pair_b_, pair_out_;
  std::unique_ptr<vk::Buffer> candidates_, scratch_, results_;
  std::unique_ptr<MeshRenderer> mesh_renderer_;  // whole-mesh renders, made on first use
  std::unique_ptr<Rebaker> rebaker_;             // re-bake sampling, made on first use
};

}  // namespace

std::unique_ptr<Engine> make_vulkan_engine(DeviceRequest request, const EngineOptions& options) {
  if (request != DeviceRequest::Gpu && request != DeviceRequest::Lavapipe)
    throw EngineError("make_vulkan_engine takes --device gpu or lavapipe");
  return std::make_unique<VulkanEngine>(request, options);
}

}  // namespace uvpress::engine
