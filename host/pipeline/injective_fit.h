// The mesh stage for one chart with injectivity kept: perceptual::fit_chart is flip-free,
// but nothing in it stops a chart's boundary from running over itself (a nearly closed
// chart whose targets curl it, arms pushed into each other). A fit that overlaps where the
// input did not is dropped for the input shape, rigid: the packer only moves it.
#pragma once

#include "perceptual/mesh_stage.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::pipeline {

struct InjectiveFit {
  perceptual::MeshStageResult fit;  // fit.uv: the fitted chart, or the input when it overlapped
  size_t overlap_pairs = 0;         // triangle pairs the fit overlapped that the input did not (> 0: fell back)
  bool fell_back() const { return overlap_pairs > 0; }
};

// fit_chart(uv, triangles, targets, options), checked with atlas::find_new_overlaps
// against `uv` (the chart's input, texel units, 3 local indices per triangle).
InjectiveFit fit_chart_injective(const std::vector<double>& uv, const std::vector<uint32_t>& triangles,
                                 const std::vector<perceptual::TriangleTarget>& targets,
                                 const perceptual::MeshStageOptions& options = {});

}  // namespace uvpress::pipeline
