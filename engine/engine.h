// uvpress compute engine: the one interface behind which the Vulkan and the native CPU
// backends live. It knows images, views and triangles; nothing about meshes or glTF.
#pragma once

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

class Engine {
 public:
  virtual ~Engine() = default;
  virtual DeviceInfo device() const = 0;

  // GMSD steps 1 and 2 (reference/gmsd.md) for every image of the batch.
  virtual LuminanceBatch luminance(const Rgba8Batch& batch) = 0;

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
