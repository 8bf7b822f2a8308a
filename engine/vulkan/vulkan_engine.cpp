// The Vulkan backend of the Engine interface: kernels created once, buffers kept and
// reused across calls, batches chunked to the device's buffer limit, every chunk one
// command buffer with many dispatches and one fence.
#include "backend.h"
#include "compute.h"
#include "layout.h"

#include "downsample2x2.spv.h"
#include "gmsd.spv.h"
#include "luminance.spv.h"
#include "view_prepare.spv.h"
#include "view_score.spv.h"
#include "cpu/gmsd.h"
#include "cpu/parallel_for.h"
#include "mesh_renderer.h"
#include "rebaker.h"

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
    vk::Buffer& rgba = vk::reuse(context_, rgba_, 4 * n * per_chunk);
    vk::Buffer& full = vk::reuse(context_, full_, 4 * n * per_chunk, vk::HostAccess::Read);
    vk::Buffer& half = vk::reuse(context_, half_, 4 * n2 * per_chunk, vk::HostAccess::Read);
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
    if (pairs.count == 0 || (!pairs.sizes && n == 0)) return out;
    if (pairs.sizes || pairs.width > shader::kViewMaxSize || pairs.height > shader::kViewMaxSize) {
      // gmsd.comp holds one image per workgroup in shared memory (64 x 64 at most, one size
      // a dispatch): larger ones and pairs of their own sizes (eval's views) are scored by
      // the CPU reference, one image per thread.
      std::vector<size_t> at(pairs.count + 1, 0);
      for (uint32_t k = 0; k < pairs.count; ++k) at[k + 1] = at[k] + pairs.pixels(k);
      parallel_for(pairs.count, std::max(1u, std::thread::hardware_concurrency()), [&](uint32_t k) {
        const uint32_t w = pairs.sizes ? pairs.sizes[2 * k] : pairs.width, h = pairs.sizes ? pairs.sizes[2 * k + 1] : pairs.height;
        out[k] = cpu::gmsd<float>(pairs.first + at[k], pairs.second + at[k], w, h);
      }, 1);
      return out;
    }
    const uint64_t per_chunk = std::min<uint64_t>(pairs.count, max_buffer_ / (4 * n));
    vk::Buffer& a = vk::reuse(context_, pair_a_, 4 * n * per_chunk);
    vk::Buffer& b = vk::reuse(context_, pair_b_, 4 * n * per_chunk);
    vk::Buffer& o = vk::reuse(context_, pair_out_, 4 * per_chunk, vk::HostAccess::Read);
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
    vk::Buffer& cand = vk::reuse(context_, candidates_, sizeof(ViewCandidate) * chunk);
    vk::Buffer& scratch = vk::reuse(context_, scratch_, kScoreSlotBytes * chunk);
    vk::Buffer& results = vk::reuse(context_, results_, 8ull * chunk, vk::HostAccess::Read);  // gmsd, lattice
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
  using Engine::render_mesh;
  // render_mesh.comp renders whole views; MeshRenderDesc::halve is done on the host after.
  void render_mesh(const MeshRenderDesc& desc, MeshRenders& out) override {
    if (desc.halve) return halved(desc, {{desc.texture, desc.texture_width, desc.texture_height, desc.mip_levels}}, out);
    if (!mesh_renderer_) mesh_renderer_ = std::make_unique<MeshRenderer>(context_, sequence_, max_buffer_);
    mesh_renderer_->render(desc, out);
  }
  // One kernel render per texture (the GPU rasterizes faster than the host samples).
  void render_mesh_textures(const MeshRenderDesc& desc, const std::vector<MeshTexture>& textures,
                            MeshRenders& out) override {
    if (textures.empty()) throw EngineError("render_mesh_textures: no texture");
    if (desc.halve) return halved(desc, textures, out);
    MeshRenderDesc d = desc;
    for (size_t k = 0; k < textures.size(); ++k) {
      d.texture = textures[k].texels;
      d.texture_width = textures[k].width, d.texture_height = textures[k].height;
      d.mip_levels = textures[k].mip_levels;
      render_mesh(d, texture_scratch_);
      if (k == 0) {
        out.width = texture_scratch_.width, out.height = texture_scratch_.height;
        out.count = texture_scratch_.count, out.channels = texture_scratch_.channels;
        out.textures = uint32_t(textures.size());
        out.coverage = texture_scratch_.coverage;
        out.pixels.resize(texture_scratch_.pixels.size() * textures.size());
      }
      std::copy(texture_scratch_.pixels.begin(), texture_scratch_.pixels.end(),
                out.pixels.begin() + long(k * texture_scratch_.pixels.size()));
    }
  }

  void halved(const MeshRenderDesc& desc, const std::vector<MeshTexture>& textures, MeshRenders& out) {
    check_mesh_render(desc);
    MeshRenderDesc whole = desc;
    whole.halve = false;
    MeshRenders full;
    render_mesh_textures(whole, textures, full);
    halve_renders(desc, full, out);
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

  vk::Context context_;
  uint64_t max_buffer_;
  vk::Kernel luminance_, downsample_, gmsd_, view_prepare_, view_score_;
  vk::Sequence sequence_;
  std::unique_ptr<vk::Buffer> rgba_, full_, half_;
  std::unique_ptr<vk::Buffer> pair_a_, pair_b_, pair_out_;
  std::unique_ptr<vk::Buffer> candidates_, scratch_, results_;
  std::unique_ptr<MeshRenderer> mesh_renderer_;  // whole-mesh renders, made on first use
  MeshRenders texture_scratch_;                  // render_mesh_textures: one texture's renders
  std::unique_ptr<Rebaker> rebaker_;             // re-bake sampling, made on first use
};

}  // namespace

std::unique_ptr<Engine> make_vulkan_engine(DeviceRequest request, const EngineOptions& options) {
  if (request != DeviceRequest::Gpu && request != DeviceRequest::Lavapipe)
    throw EngineError("make_vulkan_engine takes --device gpu or lavapipe");
  return std::make_unique<VulkanEngine>(request, options);
}

}  // namespace uvpress::engine
