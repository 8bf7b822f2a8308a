// OBJ and OFF readers (read_mesh); the first byte picks the format.
#include "core/error.h"
#include "fuzz_common.h"
#include "io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  std::string path = uvpress::fuzz::write_input((data[0] & 1) ? "in.off" : "in.obj", data + 1, size - 1);
  try {
    uvpress::io::read_mesh(path);
  } catch (const uvpress::InputError&) {
  }
  return 0;
}
