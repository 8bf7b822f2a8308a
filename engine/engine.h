// uvpress compute engine: the one interface behind which the Vulkan and the native CPU
// backends live. It knows images, views and triangles; nothing about meshes or glTF.
#pragma once

#include "layout.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace uvpress::engine {

// What the user asked for (--device / UVPRESS_DEVICE).
enum class DeviceRequest { Auto, Gpu, Lavapipe, Cpu };

std::optional<DeviceRequest> parse_device_request(std::string_view text);
const char* to_string(DeviceRequest request);
// UVPRESS_DEVICE when set and valid, else `fallback`. Throws EngineError on a bad value.
DeviceRequest device_request_from_env(DeviceRequest fallback);

struct DeviceInfo {
  std::string backend;  // "vulkan" or "cpu"
  std::string name;     // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)", or the CPU backend's name
  std::string type;     // "discrete-gpu", "integrated-gpu", "virtual-gpu", "cpu"
  unsigned threads = 1; // host threads the CPU backend uses (1 for Vulkan)
};

struct EngineOptions {
  bool validation = false;  // Vulkan: enable the Khronos validation layer and count its errors
  // Largest buffer the backend may allocate. 0: the device's own limit (lavapipe: 128 MiB).
  // Tests lower it to exercise chunking.
  uint64_t max_buffer_bytes = 0;
  unsigned threads = 0;     // CPU backend: 0 = hardware concurrency
};

class EngineError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A batch of `count` RGBA8 images of one size, packed pixel after pixel, image after image;
// each pixel is one uint32 with R in the low byte.
struct Rgba8Batch {
  uint32_t width = 0, height = 0, count = 0;
  const uint32_t* pixels = nullptr;
};

// Greyscale planes of a batch: `full` is count x height x width luminance,
// `half` is count x ceil(height/2) x ceil(width/2).
struct LuminanceBatch {
  std::vector<float> full;
  std::vector<float> half;
};

using shader::ViewCandidate;
using shader::ViewDesc;
using shader::ViewTriangle;

// Everything needed to render a set of per-triangle views: the ring triangles in view
// space and the source texture's luminance (GMSD step 1 applied to the stored values).
struct ViewSetDesc {
  uint32_t size = 64;  // S, pixels per side, even, 8 <= S <= 64
  std::vector<ViewDesc> views;
  std::vector<ViewTriangle> triangles;
  const float* texture = nullptr;  // texture_width x texture_height luminance, row 0 on top
  uint32_t texture_width = 0, texture_height = 0;
};

// Throws EngineError when a view set breaks the kernels' limits (size, ranges, guard band).
void check_view_set(const ViewSetDesc& desc);

// Views prepared on an engine: coverage and reference renders, made once and reused by
// every round of candidates. Opaque; only the engine that made it can use it.
class ViewSet {
 public:
  virtual ~ViewSet() = default;
  virtual uint32_t size() const = 0;        // S
  virtual uint32_t view_count() const = 0;
};

// Per-pixel results, S*S per view or candidate, for tests and debugging.
struct ViewImages {
  std::vector<uint8_t> coverage;  // ring triangle index per pixel, shader::kNoTriangle where empty
  std::vector<float> reference;   // reference render (luminance), 0 where empty
  std::vector<float> candidate;   // candidate render after the least-squares bake, 0 where empty
};

// A batch of equal-sized greyscale image pairs, [0,1] luminance, pair after pair.
struct ImagePairs {
  uint32_t width = 0, height = 0, count = 0;
  const float* first = nullptr;   // count * width * height
  const float* second = nullptr;
};

// ---- Whole-mesh renders (eval, seed 001 section 5.1) ----
//
// A batch of perspective views of one textured triangle mesh. Triangle set-up (projection
// in double, snapping to 1/16 pixel, attribute planes) is shared host code, so both
// backends rasterize the same integers: coverage is identical by construction of the
// kernel, pixel values agree to fp32 rounding. Rules: pixel (i, j) has its centre at
// (i + 0.5, j + 0.5), x right, y down; integer edge functions with 4 sub-pixel bits and a
// top-left rule; both faces drawn (no culling); depth = 1/w, larger is nearer, ties keep
// the lower triangle index; perspective-correct UVs; the texture is sampled bilinearly by
// hand in fp32 (no mip-maps: see host/eval/eval.h for why that is the right filter here),
// clamp-to-edge or repeat; empty pixels are 0 in every channel.
struct MeshRenderDesc {
  uint32_t width = 512, height = 512;  // pixels, 8..1024 each
  // One camera per view: clip = M (x, y, z, 1), row-major 4x4 (OpenGL conventions: NDC x
  // right, y up; w > 0 in front of the camera).
  std::vector<std::array<float, 16>> cameras;
  const float* positions = nullptr;  // x y z per vertex
  size_t vertex_count = 0;
  const uint32_t* indices = nullptr;  // 3 per triangle
  size_t triangle_count = 0;
  const float* uvs = nullptr;  // u v per vertex, glTF convention (v down the image)
  const float* texture = nullptr;  // texture_height rows of texture_width texels, `channels` floats each, row 0 on top
  uint32_t texture_width = 0, texture_height = 0, channels = 1;  // channels 1..4
  bool repeat = false;  // REPEAT wrapping on both axes, else clamp-to-edge
};

// Renders, view after view: coverage (triangle index, kNoMeshTriangle where empty) and
// `channels` floats a pixel.
struct MeshRenders {
  uint32_t width = 0, height = 0, count = 0, channels = 0;
  std::vector<uint32_t> coverage;
  std::vector<float> pixels;
};
constexpr uint32_t kNoMeshTriangle = 0xffffffffu;

// Throws EngineError for a description that breaks the limits above.
void check_mesh_render(const MeshRenderDesc& desc);

class Engine {
 public:
  virtual ~Engine() = default;
  virtual DeviceInfo device() const = 0;

  // GMSD steps 1 and 2 (reference/gmsd.md) for every image of the batch.
  virtual LuminanceBatch luminance(const Rgba8Batch& batch) = 0;

  // GMSD (reference/gmsd.md) of every pair; images up to 64 x 64 on Vulkan.
  virtual std::vector<float> gmsd(const ImagePairs& pairs) = 0;

  // Rasterizes every view (coverage, reference render). Throws EngineError for a view that
  // breaks the limits in shader/layout.h.
  virtual std::unique_ptr<ViewSet> prepare_views(const ViewSetDesc& desc) = 0;
  // GMSD of each candidate's least-squares bake against its view's reference. With
  // `images`, also returns coverage, reference and candidate renders per candidate.
  virtual void score_views(ViewSet& views, const ViewCandidate* candidates, size_t count, float* gmsd,
                           ViewImages* images = nullptr) = 0;

  // Whole-mesh renders (see MeshRenderDesc). The default is the CPU reference
  // (engine/cpu/render_mesh.cpp); the Vulkan backend runs render_mesh.comp.
  virtual MeshRenders render_mesh(const MeshRenderDesc& desc);

  // Validation-layer errors seen so far (always 0 on the CPU backend).
  virtual uint64_t validation_errors() const { return 0; }
};

// The native C++ backend: the reference for every kernel, and the fallback.
std::unique_ptr<Engine> make_cpu_engine(const EngineOptions& options);
// A Vulkan backend on the device `request` selects (Gpu: discrete, then integrated, then
// virtual; Lavapipe: a CPU Vulkan device). Throws EngineError when there is none.
std::unique_ptr<Engine> make_vulkan_engine(DeviceRequest request, const EngineOptions& options);

// The backend a request resolves to: Cpu -> native; Gpu/Lavapipe -> Vulkan on that kind of
// device; Auto -> a real GPU when Vulkan has one, else the native CPU backend (lavapipe
// runs these kernels many times slower than plain C++: see `uvpress bench`).
std::unique_ptr<Engine> make_engine(DeviceRequest request, const EngineOptions& options);

}  // namespace uvpress::engine
