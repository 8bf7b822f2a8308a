// A test fixture shared by the re-bake tests: a dark chart (the square [16, 48)^2 of a
// 64^2 source, value 0.1) on a white background, moved 3 texels right at the same density,
// so that in a 64^2 atlas it covers x in [19, 51) and the source's white lies around it.
#pragma once

#include "atlas/rebake.h"
#include "core/image.h"

#include <cstdint>
#include <vector>

namespace uvpress::test {

struct DarkChartOnWhite {
  Image source;
  std::vector<uint32_t> indices{0, 1, 2, 0, 2, 3};
  std::vector<float> old_uv{0.25f, 0.25f, 0.75f, 0.25f, 0.75f, 0.75f, 0.25f, 0.75f};
  std::vector<float> new_uv{0.25f + 3 / 64.f, 0.25f, 0.75f + 3 / 64.f, 0.25f, 0.75f + 3 / 64.f, 0.75f, 0.25f + 3 / 64.f, 0.75f};

  DarkChartOnWhite() {
    source.width = source.height = 64, source.channels = 3;
    source.pixels.assign(64 * 64 * 3, 1.0f);
    for (uint32_t y = 16; y < 48; ++y)
      for (uint32_t x = 16; x < 48; ++x)
        for (uint32_t c = 0; c < 3; ++c) source.at(x, y, c) = 0.1f;
  }
  atlas::RebakeMesh mesh() const { return {indices.data(), indices.size(), old_uv.data(), new_uv.data(), 4}; }
};

}  // namespace uvpress::test
