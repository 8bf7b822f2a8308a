#include "mesh_renderer.h"

#include "backend.h"
#include "layout.h"
#include "mesh_render.h"
#include "render_mesh.spv.h"
#include "cpu/parallel_for.h"

#include <algorithm>
#include <cstring>
#include <thread>
#include <vector>

namespace uvpress::engine {

MeshRenderer::MeshRenderer(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer)
    : context_(context), sequence_(sequence), max_buffer_(max_buffer),
      kernel_(context, render_mesh_spv, sizeof(render_mesh_spv), 6, sizeof(shader::MeshPush), shader::kMeshTile,
              shader::kMeshTile) {}

void MeshRenderer::render(const MeshRenderDesc& d, MeshRenders& out) {
  size_mesh_renders(d, out);
  const uint64_t n = uint64_t(d.width) * d.height;
  if (out.count == 0) return;
  const uint64_t tex_bytes = 4ull * mip_chain_texels(d.texture_width, d.texture_height, d.mip_levels) * d.channels;
  if (tex_bytes > max_buffer_)
    throw EngineError("Vulkan render_mesh: the texture exceeds the device's largest buffer");
  vk::Buffer& texture = vk::reuse(context_, texture_, tex_bytes);
  std::memcpy(texture.data<float>(), d.texture, tex_bytes);
  const uint32_t tx = mesh::tiles_x(d), ty = mesh::tiles_y(d);
  const uint64_t bins = uint64_t(tx) * ty;
  // Set-up and binning stay on the host, one view a thread: done serially they were most of
  // a GPU render (eval's 1248-px views of Duck as 2 x 2 tiles: 80 set-ups a render).
  std::vector<mesh::ViewSetup> setups(out.count);
  parallel_for(out.count, std::max(1u, std::thread::hardware_concurrency()),
               [&](uint32_t v) { setups[v] = mesh::setup_view(d, v); }, 1);
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
    vk::Buffer& triangles = vk::reuse(context_, triangles_, std::max<uint64_t>(tri, 4));
    vk::Buffer& offsets = vk::reuse(context_, offsets_, 4 * (bins * count + 1));
    vk::Buffer& bin_items = vk::reuse(context_, items_, std::max<uint64_t>(items, 4));
    vk::Buffer& coverage = vk::reuse(context_, coverage_, 4 * n * count, vk::HostAccess::Read);
    vk::Buffer& pixels = vk::reuse(context_, pixels_, 4 * n * d.channels * count, vk::HostAccess::Read);
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
    if (d.view_tiles_x * d.view_tiles_y == 1) {
      if (d.coverage) std::memcpy(out.coverage.data() + first * n, coverage.data<uint32_t>(), 4 * n * count);
      std::memcpy(out.pixels.data() + first * n * d.channels, pixels.data<float>(), 4 * n * d.channels * count);
    } else {  // each tile's rows into their place in its view (MeshRenderDesc::view_tiles_x)
      const size_t C = d.channels;
      parallel_for(count, std::max(1u, std::thread::hardware_concurrency()), [&](uint32_t v) {
        const mesh::ImagePlace at = mesh::image_place(d, first + v);
        for (uint32_t j = 0; j < d.height; ++j) {
          if (d.coverage)
            std::memcpy(out.coverage.data() + at.origin + j * at.row_stride,
                        coverage.data<uint32_t>() + v * n + j * d.width, 4 * size_t(d.width));
          std::memcpy(out.pixels.data() + (at.origin + j * at.row_stride) * C,
                      pixels.data<float>() + (v * n + j * size_t(d.width)) * C, 4 * size_t(d.width) * C);
        }
      }, 1);
    }
    first += count;
  }
}

}  // namespace uvpress::engine
