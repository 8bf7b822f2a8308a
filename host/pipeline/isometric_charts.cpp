#include "pipeline/isometric_charts.h"

#include "atlas/uv_overlap.h"
#include "core/mat2.h"

#include <cmath>

namespace uvpress::pipeline {

namespace {

double uv_area(const std::vector<double>& uv, const std::vector<uint32_t>& t) {
  double sum = 0;
  for (size_t k = 0; k + 2 < t.size(); k += 3) {
    const double* a = &uv[2 * size_t(t[k])];
    const double* b = &uv[2 * size_t(t[k + 1])];
    const double* c = &uv[2 * size_t(t[k + 2])];
    sum += std::abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) / 2;
  }
  return sum;
}

// Turns `uv` (in place, about its centroid) by the rotation that best matches `target`
// (orthogonal Procrustes: R = polar(sum q p^T)). The solver's frame is arbitrary; turned
// back to the input's, a chart keeps the orientation its author packed it in (a square
// sheet stays axis-aligned and fills its box) and the re-bake resamples at a small angle.
void align_rotation(std::vector<double>& uv, const std::vector<double>& target) {
  const size_t n = uv.size() / 2;
  if (n == 0) return;
  double cp[2] = {0, 0}, cq[2] = {0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 2; ++d) cp[d] += uv[2 * i + size_t(d)] / double(n), cq[d] += target[2 * i + size_t(d)] / double(n);
  double M[4] = {0, 0, 0, 0}, R[4];
  for (size_t i = 0; i < n; ++i) {
    const double p[2] = {uv[2 * i] - cp[0], uv[2 * i + 1] - cp[1]}, q[2] = {target[2 * i] - cq[0], target[2 * i + 1] - cq[1]};
    M[0] += q[0] * p[0], M[1] += q[0] * p[1], M[2] += q[1] * p[0], M[3] += q[1] * p[1];
  }
  polar(M, R);
  for (size_t i = 0; i < n; ++i) {
    const double p[2] = {uv[2 * i] - cp[0], uv[2 * i + 1] - cp[1]};
    uv[2 * i] = R[0] * p[0] + R[1] * p[1], uv[2 * i + 1] = R[2] * p[0] + R[3] * p[1];
  }
}

}  // namespace

IsometricCharts isometric_charts(const std::vector<ChartGeometry>& charts, const flatten::Options& options) {
  IsometricCharts out;
  out.uv.resize(charts.size());
  out.flattened.assign(charts.size(), 0);
  auto keep = [&](size_t c, const std::string& why) {
    out.uv[c] = *charts[c].uv;
    out.flattened[c] = 0;
    out.kept.push_back("chart " + std::to_string(c) + ": " + why);
  };
  // Flattened at the 3-D area scale (flatten::Result: UV area = surface area).
  double texels = 0, area = 0;
  for (size_t c = 0; c < charts.size(); ++c) {
    const ChartGeometry& g = charts[c];
    Mesh mesh;
    mesh.positions = *g.positions;
    mesh.triangles = *g.triangles;
    flatten::ChartResult flat;
    try {
      flat = flatten::flatten_chart(mesh, options);
    } catch (const flatten::FlattenError& e) {
      keep(c, e.what());
      continue;
    }
    if (const std::string why = flatten::invalid_reason(flat.result); !why.empty()) {
      keep(c, why);
      continue;
    }
    // Flip-free is not injective: a free boundary can run over itself.
    const auto overlaps = atlas::find_new_overlaps(g.uv->data(), flat.result.uv.data(), g.triangles->data(), g.triangles->size() / 3);
    if (!overlaps.empty()) {
      keep(c, "the flattened chart runs over itself (" + std::to_string(overlaps.size()) + " pairs of triangles overlap)");
      continue;
    }
    out.uv[c] = std::move(flat.result.uv);
    align_rotation(out.uv[c], *g.uv);
    out.flattened[c] = 1;
    out.filled_holes += flat.filled_holes;
    texels += uv_area(*g.uv, *g.triangles);
    area += uv_area(out.uv[c], *g.triangles);
  }
  // One density for every flattened chart: their input texels spread over their surface.
  out.texels_per_area = area > 0 ? texels / area : 0;
  const double s = std::sqrt(out.texels_per_area);
  for (size_t c = 0; c < charts.size(); ++c)
    if (out.flattened[c])
      for (double& x : out.uv[c]) x *= s;
  return out;
}

}  // namespace uvpress::pipeline
