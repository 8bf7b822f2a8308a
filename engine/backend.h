// What the backends share behind engine.h, and the host never sees: the checks of each
// kernel's description (so both backends refuse the same descriptions with the same
// message) and the CPU backend's re-bake kernel.
#pragma once

#include "engine.h"

#include <array>

namespace uvpress::engine {

// Throws EngineError when a view set breaks the kernels' limits (size, ranges, guard band).
void check_view_set(const ViewSetDesc& desc);

// Throws EngineError for a MeshRenderDesc that breaks its limits.
void check_mesh_render(const MeshRenderDesc& desc);
// Checks `desc` and sizes `out` for every camera and `textures` textures (its storage kept
// when large enough, and never shrunk then regrown within a call: a regrown vector is
// zeroed; the renderers write every pixel).
void size_mesh_renders(const MeshRenderDesc& desc, MeshRenders& out, uint32_t textures = 1);
// Pixels a side of one view of `desc` as MeshRenders holds it (its tiles together, halved
// with MeshRenderDesc::halve).
std::array<uint32_t, 2> view_size(const MeshRenderDesc& desc);
// MeshRenderDesc::halve after the fact: `full`, the renders of `desc` without it, into
// `out`, every view by cpu::gmsd_downsample (the backends without a halving kernel).
void halve_renders(const MeshRenderDesc& desc, const MeshRenders& full, MeshRenders& out);

// Threads for the host code both backends run (render_mesh on the CPU, GMSD against
// references): the CPU engine's own count, else the machine's.
unsigned host_threads(const Engine& engine);

// Throws EngineError for a RebakeTexelsDesc that breaks its rules.
void check_rebake_texels(const RebakeTexelsDesc& desc);

// Engine::rebake_texels on the CPU (the oracle, double precision): checks `desc`, then
// rebake_filter_box for every owned texel, tiles handed out to `threads` (>= 1) threads;
// every texel depends on its own footprint only, so the bits do not depend on `threads`.
void rebake_texels_cpu(const RebakeTexelsDesc& desc, float* texels, unsigned threads);

}  // namespace uvpress::engine
