#include "rebaker.h"

#include "backend.h"
#include "rebake.spv.h"

#include <algorithm>
#include <cstring>

namespace uvpress::engine {

Rebaker::Rebaker(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer)
    : context_(context), sequence_(sequence), max_buffer_(max_buffer),
      kernel_(context, rebake_spv, sizeof(rebake_spv), 8, sizeof(shader::RebakePush), kRebakeTile, kRebakeTile) {}

void Rebaker::run(const RebakeTexelsDesc& d, float* texels) {
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
      src[b] = &vk::reuse(context_, dummy_, 16);
      continue;
    }
    vk::Buffer& s = vk::reuse(context_, source_[b], 4ull * C * count);
    std::memcpy(s.data<float>(), d.source + first * C, 4ull * C * count);
    src[b] = &s;
  }
  const uint64_t tiles = uint64_t(tx) * ty;
  if (4 * (tiles + 1) > max_buffer_) throw EngineError("Vulkan rebake_texels: too many tiles for one buffer");
  vk::Buffer& starts = vk::reuse(context_, starts_, 4 * (tiles + 1));
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
    vk::Buffer& entries =
        vk::reuse(context_, entries_, std::max<uint64_t>(16, sizeof(shader::RebakeEntry) * n_entries));
    vk::Buffer& owner = vk::reuse(context_, owner_, 4 * n_texels);
    vk::Buffer& out = vk::reuse(context_, texels_, 4ull * C * n_texels, vk::HostAccess::Read);
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

shader::RebakeEntry Rebaker::make_entry(const RebakeTriangle& t, double ox, double oy) {
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

}  // namespace uvpress::engine
