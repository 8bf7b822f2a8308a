// The isometric layout of one UV layout's charts (`flatten --assign`): every chart that can
// be flattened takes its low-distortion, foldover-free parameterization (Liu et al. 2018,
// host/flatten, holes filled for the solve) at one texel density over the whole layout.
//
// The density: the flattened charts together keep the source texels their input shapes
// had (sum of |triangle areas| in texels), spread evenly over their surface, so an
// artist's uneven density becomes even and the texture's size can stay what it was.
// Each flattened chart is turned to match its input UVs (orthogonal Procrustes): the
// solver's frame is arbitrary, and the author's orientation packs well (the demo's square
// sheet: 93 % of its box under the chart, 51 % as the solver left it). A chart keeps its
// input shape, with a reason, when it is no disk even with its holes filled, when the
// solve fails, or when its flattened boundary runs over itself (new overlapping triangle
// pairs): a layout is never written with UVs that overlap where the input's did not. A chart folded in the input is flattened like any
// other: the solve does not start from its UVs, and unfolds it.
#pragma once

#include "flatten/flatten.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::pipeline {

// One chart as reparam holds it: positions (3 per local vertex), triangles (3 local
// indices each, positive orientation in `uv`) and the input UVs in source texels.
struct ChartGeometry {
  const std::vector<double>* positions = nullptr;  // 3 per local vertex
  const std::vector<uint32_t>* triangles = nullptr;
  const std::vector<double>* uv = nullptr;
};

struct IsometricCharts {
  std::vector<std::vector<double>> uv;  // per chart, source texel units (2 per local vertex)
  std::vector<char> flattened;          // per chart: 1 when `uv` is the flattened shape
  size_t filled_holes = 0;              // boundary loops closed for the solves
  double texels_per_area = 0;           // the common density: texels per unit of 3-D area
  std::vector<std::string> kept;        // "chart C: reason", per chart that kept its shape
};

IsometricCharts isometric_charts(const std::vector<ChartGeometry>& charts, const flatten::Options& options);

}  // namespace uvpress::pipeline
