// Engine::gmsd_references and Engine::gmsd_against: GMSD split at the reference's
// gradient magnitudes (cpu/gmsd.h), on the host for both backends, one image a thread.
#include "backend.h"
#include "gmsd.h"
#include "parallel_for.h"

namespace uvpress::engine {

namespace {

// Inlined into a clone for AVX2 where the CPU has it, as CpuEngine's gmsd(): the same fp32
// operations per element in wider lanes, the same bits.
__attribute__((target_clones("avx2", "default"), flatten)) void reference_one(const float* a, uint32_t w, uint32_t h,
                                                                              float* g1, bool halved) {
  if (halved)
    cpu::gmsd_magnitude<float>(a, (w + 1) / 2, (h + 1) / 2, g1);
  else
    cpu::gmsd_reference<float>(a, w, h, g1);
}
__attribute__((target_clones("avx2", "default"), flatten)) float against_one(const float* g1, const float* b,
                                                                             uint32_t w, uint32_t h, bool halved) {
  return halved ? cpu::gmsd_against_halved<float>(g1, b, w, h) : cpu::gmsd_against<float>(g1, b, w, h);
}

uint32_t width_of(const ImagePairs& p, uint32_t k) { return p.sizes ? p.sizes[2 * k] : p.width; }
uint32_t height_of(const ImagePairs& p, uint32_t k) { return p.sizes ? p.sizes[2 * k + 1] : p.height; }

// Where pair k starts: at[k] in the images (halved ones: ImagePairs::halved), half[k] in
// the magnitudes.
struct Offsets {
  std::vector<size_t> at, half;
  explicit Offsets(const ImagePairs& p) : at(p.count + 1, 0), half(p.count + 1, 0) {
    for (uint32_t k = 0; k < p.count; ++k) {
      const size_t h = Engine::gmsd_half_size(width_of(p, k), height_of(p, k));
      at[k + 1] = at[k] + (p.halved ? h : p.pixels(k)), half[k + 1] = half[k] + h;
    }
  }
};

}  // namespace

void Engine::gmsd_references(const ImagePairs& p, float* magnitudes) {
  const Offsets o(p);
  parallel_for(p.count, host_threads(*this), [&](uint32_t k) {
    reference_one(p.first + o.at[k], width_of(p, k), height_of(p, k), magnitudes + o.half[k], p.halved);
  }, 1);
}

std::vector<float> Engine::gmsd_against(const ImagePairs& p) {
  const Offsets o(p);
  std::vector<float> out(p.count);
  parallel_for(p.count, host_threads(*this), [&](uint32_t k) {
    out[k] = against_one(p.first + o.half[k], p.second + o.at[k], width_of(p, k), height_of(p, k), p.halved);
  }, 1);
  return out;
}

}  // namespace uvpress::engine
