// The Vulkan backend's whole-mesh renderer (render_mesh.comp; the CPU twin is
// cpu/render_mesh.cpp).
#pragma once

#include "compute.h"
#include "engine.h"

#include <cstdint>
#include <memory>

namespace uvpress::engine {

// Its own kernel and buffers, made on first use (eval is the only user). Views go in
// chunks whose set-up triangles, bins and outputs each fit one device buffer.
class MeshRenderer {
 public:
  MeshRenderer(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer);

  // Every view of d (engine.h, MeshRenderDesc) into out, in chunks.
  void render(const MeshRenderDesc& d, MeshRenders& out);

 private:

  vk::Context& context_;
  vk::Sequence& sequence_;
  uint64_t max_buffer_;
  vk::Kernel kernel_;
  std::unique_ptr<vk::Buffer> texture_, triangles_, offsets_, items_, coverage_, pixels_;
};

}  // namespace uvpress::engine
