#include "pipeline/injective_fit.h"

#include "atlas/uv_overlap.h"

namespace uvpress::pipeline {

InjectiveFit fit_chart_injective(const std::vector<double>& uv, const std::vector<uint32_t>& triangles,
                                 const std::vector<perceptual::TriangleTarget>& targets,
                                 const perceptual::MeshStageOptions& options) {
  InjectiveFit out;
  out.fit = perceptual::fit_chart(uv, triangles, targets, options);
  out.overlap_pairs = atlas::find_new_overlaps(uv.data(), out.fit.uv.data(), triangles.data(), triangles.size() / 3).size();
  if (out.fell_back()) out.fit.uv = uv;
  return out;
}

}  // namespace uvpress::pipeline
