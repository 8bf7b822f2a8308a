// eval's report: EvalResult as JSON, keys in the order the README documents.
#include "result.h"

#include <algorithm>

namespace uvpress::eval {

namespace {

using json = nlohmann::ordered_json;

json point_json(const CurvePoint& p, bool lit) {
  json j = {{"c_r", p.c_r},     {"c_r_actual", p.c_r_actual}, {"c_r_chart", p.c_r_chart}, {"r", p.width},
            {"width", p.width}, {"height", p.height},         {"q", p.q}};
  if (lit) j["q_unlit"] = p.q_unlit, j["q_lit"] = p.q_lit;
  j["q_views"] = p.q_views;
  if (p.codec_bytes) j["codec_bytes"] = *p.codec_bytes;
  if (p.bytes) j["bytes"] = *p.bytes, j["bytes_ratio"] = p.bytes_ratio;
  return j;
}

json as_written_json(const CurvePoint& p, bool lit) {
  json j = {{"c_r", p.c_r}, {"c_r_chart", p.c_r_chart}, {"q", p.q}};
  if (lit) j["q_unlit"] = p.q_unlit, j["q_lit"] = p.q_lit;
  j["width"] = p.width, j["height"] = p.height;
  if (p.bytes) j["bytes"] = *p.bytes, j["bytes_ratio"] = p.bytes_ratio;
  j["q_views"] = p.q_views;
  return j;
}

json layout_json(const LayoutResult& l, bool lit) {
  json j;
  j["name"] = l.name;
  j["file"] = l.file;
  j["texture"] = l.texture;
  j["full_size"] = {l.full_size[0], l.full_size[1]};
  j["uv_area"] = l.uv_area;
  j["texel_density_spread_log2"] = l.texel_density_spread_log2;
  if (!l.isometric.is_null()) j["flatten"] = l.isometric;
  if (l.rebake) j["rebake"] = *l.rebake;
  j["resize"] = l.resize;
  if (l.resize_mean_log_q)
    j["resize_mean_log_q"] = {{"lanczos3-srgb", l.resize_mean_log_q->first},
                              {"lanczos3-linear", l.resize_mean_log_q->second}};
  if (l.as_written) j["as_written"] = as_written_json(*l.as_written, lit);
  j["curve"] = json::array();
  for (const auto& p : l.curve) j["curve"].push_back(point_json(p, lit));
  return j;
}

json savings_json(const SavingsRow& row, CostAxis axis) {
  json j = {{"layout", row.layout}, {"vs", row.vs}};
  const Savings& s = row.savings;
  const std::string unit = axis == CostAxis::Bytes ? "bytes" : "pixel";
  if (s.points) {
    j[unit + "_ratio_at_equal_q"] = s.ratio;
    j[unit + "_savings"] = 1 - s.ratio;
    j["q_range"] = {s.q_lo, s.q_hi};
  } else {
    j[unit + "_ratio_at_equal_q"] = nullptr;
    j[unit + "_savings"] = nullptr;
    j["q_range"] = nullptr;
  }
  j["points"] = s.points;
  j["ties"] = s.ties;  // q levels where the two are within the noise floor (counted as ratio 1)
  return j;
}

}  // namespace

const char* to_string(CostAxis axis) { return axis == CostAxis::Bytes ? "bytes" : "texels"; }

std::vector<std::pair<double, double>> LayoutResult::cost_q(CostAxis axis) const {
  std::vector<std::pair<double, double>> cq;
  for (const auto& p : curve) cq.push_back({axis == CostAxis::Bytes ? p.bytes_ratio : p.c_r_actual, p.q});
  std::sort(cq.begin(), cq.end());
  if (axis == CostAxis::Texels) return cq;
  // Bytes need not grow with texels (a flat-art PNG halved gains blended colours: Fox's
  // costs 1.87x its own bytes, the full size re-encoded 0.74x), so a point that costs more
  // than a cheaper one of the same layout and looks no better is dropped: nobody pays
  // more for worse. What remains is the fewest bytes that reach each q.
  std::vector<std::pair<double, double>> front;
  for (const auto& [c, q] : cq)
    if (front.empty() || q < front.back().second) front.push_back({c, q});
  return front;
}

std::vector<std::pair<double, double>> LayoutResult::grid_q() const {
  std::vector<std::pair<double, double>> cq;
  for (const auto& p : curve) cq.push_back({p.c_r, p.q});
  return cq;
}

const LayoutResult* EvalResult::layout(const std::string& name) const {
  for (const auto& l : layouts)
    if (l.name == name) return &l;
  return nullptr;
}

json EvalResult::to_json() const {
  json report;
  report["asset"] = asset;
  report["device"] = {{"backend", device.backend}, {"name", device.name}, {"type", device.type}, {"threads", device.threads}};
  report["views"] = views;
  report["resolution"] = resolution.resolution;
  report["resolution_mode"] = resolution.automatic ? "auto" : "fixed";
  report["resolution_cap"] = resolution_cap;
  report["resolution_capped"] = resolution.capped;
  report["resolution_cropped"] = resolution.cropped;
  report["view_pixels"] = resolution.view_pixels;
  report["texels_per_pixel"] = {{"percentile", resolution.percentile},
                                {"value", resolution.texels_per_pixel},
                                {"median", resolution.texels_per_pixel_median}};
  report["resolved_fraction"] = resolution.resolved_fraction;
  report["noise_floor"] = noise_floor_measured ? json(resolution.noise_floor) : json(nullptr);
  report["fov_degrees"] = fov_degrees;
  report["texture_filter"] = to_string(filter);
  report["shading"] = lit ? "lit" : "unlit";
  report["shading_requested"] = to_string(shading_requested);
  if (!shading_warning.empty()) report["shading_warning"] = shading_warning;
  if (lit && noise_floor_measured) report["noise_floor_unlit"] = noise_floor_unlit, report["noise_floor_lit"] = noise_floor_lit;
  report["triangles"] = triangles;
  report["reference"] = {{"file", reference.file},       {"image", reference.image},
                         {"width", reference.width},     {"height", reference.height},
                         {"uv_area", reference.uv_area}, {"image_texels", reference.image_texels},
                         {"chart_texels", reference.chart_texels}, {"image_bytes", reference.image_bytes}};
  if (!reference.encoding.empty()) report["reference"]["encoding"] = reference.encoding;
  report["cost_measure"] = "image_texels";
  report["cost_axis"] = to_string(cost_axis);
  if (codec)
    report["codec"] = {{"name", "astc-" + io::block_name(*codec)},
                       {"quality", io::to_string(codec->quality)},
                       {"bits_per_texel", 128.0 / (codec->block_x * codec->block_y)}};
  else
    report["codec"] = nullptr;
  report["cost_grid"] = cost_grid;
  report["contact_c_r"] = contact_c_r;
  if (!input_resize.empty()) report["input_resize"] = input_resize;
  report["layouts"] = json::array();
  for (const auto& l : layouts) report["layouts"].push_back(layout_json(l, lit));
  report["savings"] = json::array();
  for (const auto& row : savings) report["savings"].push_back(savings_json(row, cost_axis));
  report["seconds"] = {{"textures", seconds.textures},
                       {"render", seconds.render},
                       {"gmsd", seconds.gmsd},
                       {"shading", seconds.shading},
                       {"total", seconds.total}};
  return report;
}

}  // namespace uvpress::eval
