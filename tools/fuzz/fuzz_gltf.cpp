// glTF reader: load_gltf (tinygltf plus uvpress's checks), the validator rules checked on
// load (check_rules: reads every accessor it may), then build_asset (accessors,
// indices, UV sets, image uses) and every image's header. The first byte picks .glb or
// .gltf. Any InputError is a correct answer; a crash or sanitizer report is a bug.
#include "core/error.h"
#include "fuzz_common.h"
#include "io/asset.h"
#include "io/gltf_io.h"
#include "io/gltf_rules.h"
#include "io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const bool binary = data[0] & 1;
  std::string path = uvpress::fuzz::write_input(binary ? "in.glb" : "in.gltf", data + 1, size - 1);
  try {
    uvpress::io::GltfFile file = uvpress::io::load_gltf(path);
    uvpress::io::describe_issues(uvpress::io::check_rules(file));
    uvpress::io::Asset asset = uvpress::io::build_asset(file);
    for (const auto& bytes : file.image_bytes) {
      try {
        uvpress::io::read_image_header(bytes, path);
      } catch (const uvpress::InputError&) {
      }
    }
  } catch (const uvpress::InputError&) {
  }
  return 0;
}
