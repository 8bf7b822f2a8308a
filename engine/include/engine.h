// uvpress compute engine: the one interface behind which the Vulkan and the native CPU
// backends live. It knows images, views and triangles; nothing about meshes or glTF.
// This header (and shaders/layout.h, whose structs it uses) is all the host may include:
// the rest of engine/ is the backends' own (a private include path of uvpress_engine).
#pragma once

#include "layout.h"

#include <array>
#include <cstdint>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
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
using shader::kRebakeTile;

// Everything needed to render a set of per-triangle views: the ring triangles in view
// space and the source texture's luminance (GMSD step 1 applied to the stored values).
struct ViewSetDesc {
  uint32_t size = 64;  // S, pixels per side, even, 8 <= S <= 64
  std::vector<ViewDesc> views;
  std::vector<ViewTriangle> triangles;
  const float* texture = nullptr;  // texture_width x texture_height luminance, row 0 on top
  uint32_t texture_width = 0, texture_height = 0;
};

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

// A batch of greyscale image pairs, [0,1] luminance, pair after pair: all width x height,
// or with `sizes` pair k of sizes[2k] x sizes[2k + 1] (eval's views cropped to the asset;
// width and height are then unused).
struct ImagePairs {
  uint32_t width = 0, height = 0, count = 0;
  const float* first = nullptr;  // the pairs' pixels, one image after the other
  const float* second = nullptr;
  const uint32_t* sizes = nullptr;
  // Engine::gmsd_references and gmsd_against only: the images (the references; the second
  // ones) are halved already (MeshRenderDesc::halve), each (w + 1) / 2 x (h + 1) / 2 for a
  // pair of w x h.
  bool halved = false;
  size_t pixels(uint32_t k) const { return sizes ? size_t(sizes[2 * k]) * sizes[2 * k + 1] : size_t(width) * height; }
};

// ---- Whole-mesh renders (eval, seed 001 section 5.1) ----
//
// A batch of perspective views of one textured triangle mesh. Triangle set-up (projection
// in double, snapping to 1/16 pixel, attribute planes) is shared host code, so both
// backends rasterize the same integers: coverage is identical by construction of the
// kernel, pixel values agree to fp32 rounding. Rules: pixel (i, j) has its centre at
// (i + 0.5, j + 0.5), x right, y down; integer edge functions with 4 sub-pixel bits and a
// top-left rule; both faces drawn (no culling); depth = 1/w, larger is nearer, ties keep
// the lower triangle index; perspective-correct UVs; the texture is sampled by hand in
// fp32, clamp-to-edge or repeat: bilinearly from level 0 when it has one level, else
// trilinearly as OpenGL samples a mip-mapped texture (4.6 §8.14: level of detail
// lambda = log2 rho, rho the longer of the two screen-axis derivatives of the texel
// coordinates, taken analytically from the attribute planes; lambda <= 0 magnifies from
// level 0; else the two nearest levels, bilinear each, blended by frac(lambda)); empty
// pixels are 0 in every channel. Triangles reaching past the guard band are clipped to it.
constexpr uint32_t kMeshRenderMaxSide = 1024;  // larger views: render tiles (eval does)
struct MeshRenderDesc {
  uint32_t width = 512, height = 512;  // pixels, 8..kMeshRenderMaxSide each
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
  // Levels in `texture`, level l (max(1, W >> l) x max(1, H >> l) texels) right after level
  // l - 1; 1 .. the full chain down to 1 x 1. The caller filters them (eval: box in linear
  // light), as an engine's mip generation would.
  uint32_t mip_levels = 1;
  bool repeat = false;  // REPEAT wrapping on both axes, else clamp-to-edge
  // Views in tiles: each run of view_tiles_x * view_tiles_y cameras renders the tiles of one
  // view (row-major, each width x height), and MeshRenders holds the view whole
  // (view_tiles_x * width pixels a row), every tile in its place: views wider than
  // kMeshRenderMaxSide (eval's) without a copy of every pixel to stitch them. 1 x 1 (the
  // default): every camera is an image of its own. The cameras must be whole runs.
  uint32_t view_tiles_x = 1, view_tiles_y = 1;
  // false: MeshRenders::coverage is left empty, for callers that read only the pixels (eval's
  // unlit scores). At eval's sizes its 4 bytes a pixel were as many stores as a
  // one-texture render's pixels (reparam's scoring of each candidate).
  bool coverage = true;
  // true: each view's pixels as GMSD's first step leaves them (2 x 2 means, stride 2, zero
  // padding past an odd side: cpu::gmsd_downsample, the same bits), (W + 1) / 2 x
  // (H + 1) / 2 a view of W x H pixels, for callers that only score the renders against
  // references (eval's curves: ImagePairs::halved): a quarter of the image to store and to
  // read back. One channel, no coverage, and even tile sides where views are tiled.
  bool halve = false;
};

// Texels in the first `levels` levels of a width x height mip chain (sizes as above).
size_t mip_chain_texels(uint32_t width, uint32_t height, uint32_t levels);
// Levels of the full chain of a width x height texture, down to 1 x 1.
uint32_t mip_chain_levels(uint32_t width, uint32_t height);

// std::allocator, except that resize() leaves new elements default-initialized (for
// numbers: unwritten) instead of zeroing them. For buffers whose every element is written
// next, at eval's sizes: zeroing a 20 M-pixel render or a reference's 60 M pixels first
// was a serial pass over memory the render then writes again in parallel.
// Large ones are asked for in huge pages (engine/large_buffer.cpp): a page fault apiece
// for 2 MiB instead of 4 KiB, where each fault is costly (virtual machines).
void* allocate_buffer(size_t bytes);
void free_buffer(void* p);
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() noexcept = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n > size_t(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocate_buffer(n * sizeof(T)));
  }
  void deallocate(T* p, size_t) noexcept { free_buffer(p); }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
    else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
// A vector whose resize() does not zero (UninitializedAllocator).
template <class T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

// Renders, view after view: coverage (triangle index, kNoMeshTriangle where empty; none
// without MeshRenderDesc::coverage) and `channels` floats a pixel; with several textures
// (render_mesh_textures) the pixels hold every view of the first texture, then every view
// of the next, coverage once. Every element is written by the render. width, height and
// count are the cameras' (tiles', with MeshRenderDesc::view_tiles_x/y: the pixels are the
// same in number, laid out as whole views; with MeshRenderDesc::halve, each view halved).
struct MeshRenders {
  uint32_t width = 0, height = 0, count = 0, channels = 0, textures = 1;
  UninitializedVector<uint32_t> coverage;
  UninitializedVector<float> pixels;
};

// One texture of render_mesh_textures: a mip chain laid out as MeshRenderDesc's texture.
struct MeshTexture {
  const float* texels = nullptr;
  uint32_t width = 0, height = 0, mip_levels = 1;
};
constexpr uint32_t kNoMeshTriangle = 0xffffffffu;

// ---- Texture re-bake sampling (host/atlas/rebake.cpp; engine/cpu/rebake_texels.cpp) ----
//
// The per-texel sampling loop of a re-bake. The host sets up the triangles (texel units,
// double), bins them in kRebakeTile x kRebakeTile tiles of the new image and picks the
// owner triangle of every covered texel; the engine filters each owned texel's footprint
// in the source: n_x by n_y samples (the owner's `ns`) on a regular grid inside the new
// texel, each mapped to the source by the affine map of the triangle that contains it (the
// owner; else the first other triangle of the tile's list that contains it; else the
// owner's closest point), sampled bilinearly (texel centres at integers + 0.5, glTF wrap
// modes) and averaged with equal weights.
struct RebakeTriangle {
  double n[3][2];       // vertices in new texel coordinates
  double o0[2];         // vertex 0 in old (source) texel coordinates
  double J[2][2];       // d old / d new, texel units
  double lo[2], hi[2];  // bounding box in new texels
  double sign;          // +1 or -1: orientation of the new triangle
  int ns[2];            // samples per axis, >= 1
};

constexpr uint32_t kRebakeNoOwner = 0xffffffffu;
// glTF sampler wrap codes; anything else wraps as REPEAT.
constexpr int kRebakeWrapRepeat = 10497, kRebakeWrapClampToEdge = 33071, kRebakeWrapMirroredRepeat = 33648;

struct RebakeTexelsDesc {
  uint32_t width = 0, height = 0;  // the new image
  // The working source: source_height rows of source_width texels, `channels` floats each
  // (1..4), row 0 on top; colour already linearized and premultiplied by the host.
  const float* source = nullptr;
  uint32_t source_width = 0, source_height = 0, channels = 0;
  int wrap_s = kRebakeWrapRepeat, wrap_t = kRebakeWrapRepeat;
  // The source is premultiplied by its last channel (channels 2 or 4): the result is
  // un-premultiplied, and a footprint whose mean alpha is <= 1e-7 gets the mean of the
  // straight colours instead of 0/0.
  bool premultiplied = false;
  const RebakeTriangle* triangles = nullptr;
  size_t triangle_count = 0;
  // Tiles of kRebakeTile texels, row-major, tiles_x = ceil(width / kRebakeTile): the
  // triangles meeting tile k are tile_list[tile_start[k] .. tile_start[k + 1]), in order.
  const uint32_t* tile_start = nullptr;  // tiles_x * tiles_y + 1
  const uint32_t* tile_list = nullptr;
  // Per texel (width * height, row 0 on top): the position in tile_list, within the
  // texel's own tile, of the owner triangle; kRebakeNoOwner where uncovered.
  const uint32_t* owner = nullptr;
};

// The rule above, as functions: part of the engine's contract, not of a backend. The host
// needs it itself: it picks owners by the kernel's own geometry, and its least-squares
// bake (host/atlas/rebake_lsq.cpp) filters squares centred on its sample points, one call
// per point inside its own loops, where an Engine method would add only a virtual call
// (on every backend it would run this same double-precision code on the host).

// Squared distance from p to triangle t (0 inside or on an edge) and the closest point:
// the geometry both the host's owner search and the CPU kernel use.
double rebake_closest_point(const RebakeTriangle& t, double px, double py, double& qx, double& qy);

// Texel index i wrapped into [0, n) by a glTF wrap mode (anything unknown as REPEAT).
int rebake_wrap(int i, int n, int mode);

// The kernel's filter for one footprint: the square [bx, bx + size] x [by, by + size] of new
// texel space (size 1: one texel), n_x by n_y samples (t.ns) mapped through t (the owner) or the first
// triangle of [first, last) that contains them, as described above; writes desc.channels
// doubles to out (straight colour when premultiplied). The CPU backend calls it with each
// owned texel's corner; host/atlas/rebake_lsq.cpp with a square centred on any sample point
// (its band-limited target), so both bakes see one filter.
void rebake_filter_box(const RebakeTexelsDesc& desc, const RebakeTriangle& t, const uint32_t* first,
                       const uint32_t* last, double bx, double by, double* out, double size = 1.0);

class Engine {
 public:
  virtual ~Engine() = default;
  virtual DeviceInfo device() const = 0;

  // GMSD steps 1 and 2 (reference/gmsd.md) for every image of the batch.
  virtual LuminanceBatch luminance(const Rgba8Batch& batch) = 0;

  // GMSD (reference/gmsd.md) of every pair, images of any size (on Vulkan, those above
  // 64 x 64 are scored on the host).
  virtual std::vector<float> gmsd(const ImagePairs& pairs) = 0;

  // GMSD against references scored many times (eval's reference views): gmsd_references
  // works out each reference's gradient magnitudes once (steps 1 and 2, half its size a
  // side: gmsd_half_size elements, one reference's after another into `magnitudes`), and
  // gmsd_against scores images against them (pairs.first: those magnitudes, laid out so;
  // pairs.second: the images), equal bit for bit to gmsd() of the images with the
  // references, which are then neither read again nor kept (a quarter of their memory).
  // On the host for both backends (engine/cpu/gmsd_against.cpp), as gmsd() is for eval's
  // sizes.
  void gmsd_references(const ImagePairs& references, float* magnitudes);
  std::vector<float> gmsd_against(const ImagePairs& pairs);
  static size_t gmsd_half_size(uint32_t width, uint32_t height) {
    return size_t((width + 1) / 2) * ((height + 1) / 2);
  }

  // Rasterizes every view (coverage, reference render). Throws EngineError for a view that
  // breaks the limits in shader/layout.h.
  virtual std::unique_ptr<ViewSet> prepare_views(const ViewSetDesc& desc) = 0;
  // GMSD of each candidate's least-squares bake against its view's reference. With
  // `images`, also returns coverage, reference and candidate renders per candidate; with
  // `lattice`, the candidate tile's texel spacing in J-mapped source texels (1: the loss of
  // eq. 5-7 exactly; a power of two > 1: the tile had to be coarsened to fit kTileMax).
  virtual void score_views(ViewSet& views, const ViewCandidate* candidates, size_t count, float* gmsd,
                           ViewImages* images = nullptr, float* lattice = nullptr) = 0;

  // Whole-mesh renders (see MeshRenderDesc) into `out`, every pixel written, its storage
  // reused when it is large enough: eval renders the same views at every cost, and a fresh
  // result (a quarter of a gigabyte for Duck's 20 views) cost more in page faults and zeroing
  // than the rasterization did. The default is the CPU reference
  // (engine/cpu/render_mesh.cpp); the Vulkan backend runs render_mesh.comp. Throws
  // EngineError for a description that breaks the limits there.
  virtual void render_mesh(const MeshRenderDesc& desc, MeshRenders& out);
  MeshRenders render_mesh(const MeshRenderDesc& desc) {
    MeshRenders out;
    render_mesh(desc, out);
    return out;
  }

  // The views of `desc` rendered once per texture of `textures` (desc's own texture is
  // ignored; its channels and wrap apply to all): what render_mesh gives for each, into
  // `out` as MeshRenders says. eval scores one layout at ten costs and two resizes, and the
  // views' rasterization does not depend on the texture. The default is the CPU reference
  // (engine/cpu/render_mesh.cpp): each view is rasterized once, in the texel space of the
  // largest texture (whose pixels are render_mesh's, bit for bit), and every texture is
  // sampled from the kept texel coordinates scaled to its size and level of detail
  // lambda + log2 sqrt(kx ky) (kx, ky its sides over the largest's); the other textures
  // agree with render_mesh to fp32 rounding of those coordinates, and to that of the
  // level of detail where their aspect is not the largest's (eval rounds each side on its
  // own: kx and ky differ by under one texel, a level-of-detail error below 2^-9 at
  // 512 texels, finer than GPUs' 8-bit LOD fractions). The Vulkan backend runs
  // render_mesh.comp once per texture. Throws as render_mesh does, and for no texture.
  virtual void render_mesh_textures(const MeshRenderDesc& desc, const std::vector<MeshTexture>& textures,
                                    MeshRenders& out);

  // Re-bake sampling (see RebakeTexelsDesc): writes `channels` floats for every owned texel
  // of `texels` (width * height * channels), leaves the others untouched. The CPU backend
  // is the oracle (rebake_filter_box per texel, double precision, on its threads; the bits
  // do not depend on their count); the Vulkan backend runs rebake.comp (fp32, local
  // frames). Throws EngineError for a description that breaks the rules there.
  virtual void rebake_texels(const RebakeTexelsDesc& desc, float* texels) = 0;

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
