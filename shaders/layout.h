// Structs shared verbatim by GLSL and C++ (std430 / push-constant rules: only 32-bit
// scalars, members in declaration order, no implicit padding), so the two sides of a
// kernel's interface cannot drift. Include from GLSL with GL_GOOGLE_include_directive.
#ifndef UVPRESS_SHADER_LAYOUT_H
#define UVPRESS_SHADER_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
namespace uvpress::shader {
typedef uint32_t uint;
#endif

// One dispatch over `count` equal-sized images of a batch, starting at image `first`
// (relative to the bound buffers). Grid: (ceil(width/lx), ceil(height/ly), count).
struct ImageBatchPush {
  uint width;   // of the input image, pixels
  uint height;
  uint first;   // first image of this dispatch within the bound buffers
  uint count;   // images in this dispatch
};

#ifdef __cplusplus
static_assert(sizeof(ImageBatchPush) == 16, "push constant layout");
}  // namespace uvpress::shader
#endif

#endif
