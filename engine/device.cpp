// Which backend a run gets: --device / UVPRESS_DEVICE, resolved once per process.
#include "engine.h"

#include <cstdlib>

namespace uvpress::engine {

std::optional<DeviceRequest> parse_device_request(std::string_view t) {
  if (t == "auto") return DeviceRequest::Auto;
  if (t == "gpu") return DeviceRequest::Gpu;
  if (t == "lavapipe") return DeviceRequest::Lavapipe;
  if (t == "cpu") return DeviceRequest::Cpu;
  return std::nullopt;
}

const char* to_string(DeviceRequest r) {
  switch (r) {
    case DeviceRequest::Auto: return "auto";
    case DeviceRequest::Gpu: return "gpu";
    case DeviceRequest::Lavapipe: return "lavapipe";
    case DeviceRequest::Cpu: return "cpu";
  }
  return "?";
}

DeviceRequest device_request_from_env(DeviceRequest fallback) {
  const char* env = std::getenv("UVPRESS_DEVICE");
  if (!env || !*env) return fallback;
  auto r = parse_device_request(env);
  if (!r) throw EngineError(std::string("UVPRESS_DEVICE='") + env + "' is not one of auto, gpu, lavapipe, cpu");
  return *r;
}

std::unique_ptr<Engine> make_engine(DeviceRequest request, const EngineOptions& options) {
  switch (request) {
    case DeviceRequest::Cpu: return make_cpu_engine(options);
    case DeviceRequest::Gpu:
    case DeviceRequest::Lavapipe: return make_vulkan_engine(request, options);
    case DeviceRequest::Auto:
      try {
        return make_vulkan_engine(DeviceRequest::Gpu, options);
      } catch (const EngineError&) {
        return make_cpu_engine(options);  // no GPU (or no Vulkan at all): the native backend
      }
  }
  return make_cpu_engine(options);
}

}  // namespace uvpress::engine
