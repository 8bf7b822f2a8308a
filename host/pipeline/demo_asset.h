// The embedded default asset: a curved sheet whose texture mixes flat colour, smooth
// gradients and fine detail, so that re-parameterization has pixels to move around.
// Generated, not shipped: the same bytes on every machine.
#pragma once

#include "io/gltf_io.h"

namespace uvpress::pipeline {

struct DemoOptions {
  int grid = 48;          // quads per side: 2 * grid^2 triangles
  int texture_size = 512;
};

io::GltfFile make_demo_asset(const DemoOptions& options = {});

}  // namespace uvpress::pipeline
