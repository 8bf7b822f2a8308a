// The native CPU backend: every kernel with the same semantics as its GLSL twin (same
// formulas, same summation order, fp32), parallel over images. It is the oracle the Vulkan
// path is tested against and the fast path on machines without a GPU.
#include "backend.h"
#include "gmsd.h"
#include "parallel_for.h"
#include "views.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>

namespace uvpress::engine {
namespace {

// luminance.comp
void luminance_image(const uint32_t* rgba, uint32_t w, uint32_t h, float* y) {
  for (uint32_t i = 0; i < w * h; ++i) {
    uint32_t c = rgba[i];
    float r = float(c & 0xffu), g = float((c >> 8) & 0xffu), b = float((c >> 16) & 0xffu);
    float y8 = 0.299f * r;  // written as separate statements so the compiler cannot fuse
    y8 += 0.587f * g;
    y8 += 0.114f * b;
    y[i] = y8 * (1.0f / 255.0f);
  }
}

// downsample2x2.comp
void downsample_image(const float* y, uint32_t w, uint32_t h, float* d) {
  uint32_t w2 = (w + 1) / 2, h2 = (h + 1) / 2;
  auto at = [&](uint32_t x, uint32_t yy) { return (x < w && yy < h) ? y[yy * w + x] : 0.0f; };
  for (uint32_t j = 0; j < h2; ++j)
    for (uint32_t i = 0; i < w2; ++i) {
      float s = at(2 * i, 2 * j) + at(2 * i + 1, 2 * j);
      s += at(2 * i, 2 * j + 1);
      s += at(2 * i + 1, 2 * j + 1);
      d[j * w2 + i] = 0.25f * s;
    }
}

struct CpuViewSet final : ViewSet {
  ViewSetDesc desc;  // texture pointer dropped after prepare
  std::vector<uint8_t> coverage;
  std::vector<float> reference;
  std::vector<cpu::ViewPixels> pixels;  // per view: what every candidate's tile map starts from
  uint32_t size() const override { return desc.size; }
  uint32_t view_count() const override { return uint32_t(desc.views.size()); }
};

class CpuEngine final : public Engine {
 public:
  explicit CpuEngine(const EngineOptions& o)
      : threads_(o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency())) {}

  DeviceInfo device() const override { return {"cpu", "native C++", "cpu", threads_}; }

  LuminanceBatch luminance(const Rgba8Batch& b) override {
    const size_t n = size_t(b.width) * b.height, n2 = size_t((b.width + 1) / 2) * ((b.height + 1) / 2);
    LuminanceBatch out;
    out.full.resize(n * b.count);
    out.half.resize(n2 * b.count);
    parallel_for(b.count, threads_, [&](uint32_t k) {
      luminance_image(b.pixels + k * n, b.width, b.height, out.full.data() + k * n);
      downsample_image(out.full.data() + k * n, b.width, b.height, out.half.data() + k * n2);
    });
    return out;
  }

  // cpu::gmsd<float> inlined into a clone for AVX2 where the CPU has it: its per-element
  // loops run in wider lanes, the same fp32 operations per element (no contraction, sums
  // in their order), so the same bits as the baseline build.
  __attribute__((target_clones("avx2", "default"), flatten)) static float gmsd_pair(const float* a, const float* b,
                                                                                   uint32_t w, uint32_t h) {
    return cpu::gmsd<float>(a, b, w, h);
  }

  std::vector<float> gmsd(const ImagePairs& p) override {
    constexpr size_t kSmallImage = 64 * 64;  // a view of the triangle stage
    std::vector<float> out(p.count);
    if (p.sizes) {  // pairs of their own sizes: one a thread
      std::vector<size_t> at(p.count + 1, 0);
      for (uint32_t k = 0; k < p.count; ++k) at[k + 1] = at[k] + p.pixels(k);
      parallel_for(p.count, threads_, [&](uint32_t k) {
        out[k] = gmsd_pair(p.first + at[k], p.second + at[k], p.sizes[2 * k], p.sizes[2 * k + 1]);
      }, 1);
      return out;
    }
    const size_t n = size_t(p.width) * p.height;
    parallel_for(
        p.count, threads_, [&](uint32_t k) { out[k] = gmsd_pair(p.first + k * n, p.second + k * n, p.width, p.height); },
        n > kSmallImage ? 1 : 8);
    return out;
  }

  std::unique_ptr<ViewSet> prepare_views(const ViewSetDesc& d) override {
    check_view_set(d);
    auto set = std::make_unique<CpuViewSet>();
    set->desc = d;
    set->desc.texture = nullptr;
    const size_t n = size_t(d.size) * d.size;
    set->coverage.resize(n * d.views.size());
    set->reference.resize(n * d.views.size());
    set->pixels.resize(d.views.size());
    parallel_for(uint32_t(d.views.size()), threads_, [&](uint32_t v) {
      cpu::rasterize_view(d.views[v], d.triangles.data(), d.size, d.texture, d.texture_width, d.texture_height,
                          set->coverage.data() + v * n, set->reference.data() + v * n);
      set->pixels[v] = cpu::view_pixels(d.views[v], d.triangles.data(), d.size, set->coverage.data() + v * n);
    });
    return set;
  }

  void score_views(ViewSet& views, const ViewCandidate* c, size_t count, float* gmsd, ViewImages* images,
                   float* lattice) override {
    auto* set = dynamic_cast<CpuViewSet*>(&views);
    if (!set) throw EngineError("score_views: the view set belongs to another engine");
    const uint32_t S = set->desc.size;
    const size_t n = size_t(S) * S;
    for (size_t k = 0; k < count; ++k)
      if (c[k].view >= set->view_count()) throw EngineError("score_views: candidate names a view that does not exist");
    if (images) {
      images->coverage.resize(n * count), images->reference.resize(n * count), images->candidate.resize(n * count);
    }
    parallel_for(uint32_t(count), threads_, [&](uint32_t k) {
      const uint32_t v = c[k].view;
      const uint8_t* cov = set->coverage.data() + v * n;
      const float* ref = set->reference.data() + v * n;
      float* cand;
      if (images) {
        std::copy(cov, cov + n, images->coverage.begin() + long(k * n));
        std::copy(ref, ref + n, images->reference.begin() + long(k * n));
        cand = images->candidate.data() + k * n;
      } else {
        thread_local std::vector<float> local;
        local.resize(n);
        cand = local.data();
      }
      gmsd[k] = cpu::score_view(set->pixels[v], S, ref, c[k].j, cand, lattice ? lattice + k : nullptr);
    });
  }

  void rebake_texels(const RebakeTexelsDesc& desc, float* texels) override { rebake_texels_cpu(desc, texels, threads_); }

 private:
  unsigned threads_;
};

}  // namespace

std::unique_ptr<Engine> make_cpu_engine(const EngineOptions& options) {
  return std::make_unique<CpuEngine>(options);
}

}  // namespace uvpress::engine
