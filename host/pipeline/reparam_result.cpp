// reparam's report: ReparamResult as JSON, keys in the order the README documents.
#include "reparam.h"
#include "texture_costs.h"

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

namespace {

json triangle_stage_json(const TriangleStageReport& t) {
  json eps = t.epsilon;
  if (t.rate_control)
    eps = {{"rule", "rate control: max(margin * loss under the resize to the requested cost, floor)"},
           {"quartiles", t.rate_control->quartiles},
           {"max", t.rate_control->max}};
  json j = {{"epsilon", eps},
            {"evaluations", t.evaluations},
            {"evaluations_mean", t.evaluations_mean},
            {"early_stop", t.early_stop},
            {"view_size", t.view_size},
            {"triangles", t.triangles},
            {"feasible", t.feasible},
            {"infeasible", t.infeasible},
            {"views_resolve_texels", t.views_resolve_texels},
            {"sampled_by_patches", t.sampled_by_patches},
            {"tiles_coarsened", t.tiles_coarsened},
            {"lambda_area_quartiles", t.lambda_area_quartiles}};
  if (t.infeasible_identity_gmsd)
    j["infeasible_identity_gmsd"] = {{"median", t.infeasible_identity_gmsd->median},
                                     {"max", t.infeasible_identity_gmsd->max}};
  return j;
}

json layout_json(const LayoutReport& l) {
  json j = {{"images", l.images}, {"driver", l.driver}};
  json sets = json::array();
  for (const auto& s : l.uv_sets)
    sets.push_back({{"mesh", s.mesh}, {"primitive", s.primitive}, {"tex_coord", s.tex_coord}});
  j["uv_sets"] = sets;
  if (l.untouched) {
    j["untouched"] = *l.untouched;
    return j;
  }
  if (l.equal_slope)
    j["equal_slope"] = {{"cost", l.equal_slope->cost},
                        {"spent", l.equal_slope->spent},
                        {"multiplier", l.equal_slope->multiplier},
                        {"scale_quartiles", l.equal_slope->scale_quartiles}};
  if (l.unit_scale)
    j["unit_scale"] = {{"cost", l.unit_scale->cost},
                       {"units", l.unit_scale->units},
                       {"scale_quartiles", l.unit_scale->scale_quartiles},
                       {"scale_min", l.unit_scale->scale_min}};
  if (l.isometric)
    j["isometric"] = {{"charts_flattened", l.isometric->charts_flattened},
                      {"charts_kept", l.isometric->charts_kept},
                      {"holes_filled", l.isometric->holes_filled},
                      {"texels_per_area", l.isometric->texels_per_area}};
  j["pack_seconds"] = l.pack_seconds;
  j["charts"] = l.charts;
  j["rigid_charts"] = l.rigid_charts;
  j["shared_texel_charts"] = l.shared_texel_charts;
  j["packing_units"] = l.packing_units;
  j["exact_units"] = l.exact_units;
  j["pinned_units"] = l.pinned_units;
  j["exact_texels"] = l.exact_texels;
  j["atlas"] = l.atlas;
  j["scale"] = l.scale;
  j["scale_cap"] = l.scale_cap;
  j["capped_at_source_density"] = l.capped_at_source_density;
  j["packing_efficiency"] = l.packing_efficiency;
  j["gutter"] = l.gutter;
  if (l.mip_align > 1) j["mip_align"] = l.mip_align;
  if (l.side_multiple > 1) j["side_multiple"] = l.side_multiple;
  j["edge_gutter"] = l.edge_gutter;
  j["gutter_texels"] = l.gutter_texels;
  j["footprint_texels"] = l.footprint_texels;
  j["chart_cost_ratio"] = l.chart_cost_ratio;
  j["flips"] = l.flips;
  j["overlaps_new"] = l.overlaps_new;
  j["overlap_fallback_charts"] = l.overlap_fallback_charts;
  j["overlap_fallback_pairs"] = l.overlap_fallback_pairs;
  if (l.outline)
    j["outline"] = {{"kept", l.outline->kept}, {"failed", l.outline->failed}, {"mean_blend", l.outline->mean_blend}};
  if (l.mesh_stage_failed_charts) j["mesh_stage_failed_charts"] = *l.mesh_stage_failed_charts;
  if (l.triangle_stage) j["triangle_stage"] = triangle_stage_json(*l.triangle_stage);
  return j;
}

json texture_json(const TextureReport& t) {
  return {{"image", t.image},
          {"name", t.name},
          {"role", t.role},
          {"old_size", t.old_size},
          {"new_size", t.new_size},
          {"old_bytes", t.old_bytes},
          {"new_bytes", t.new_bytes},
          {"encoding", t.encoding},
          {"written", t.written},
          {"old", cost_json(t.old_cost, t.old_bytes)},
          {"new", cost_json(t.new_cost, t.new_bytes)},
          {"resize_bytes", t.resize_bytes},
          {"bytes_ratio", t.bytes_ratio},
          {"bytes_vs_resize", t.bytes_vs_resize}};
}

}  // namespace

bool ReparamResult::capped_at_source_density() const {
  bool capped = false;
  for (const auto& l : layouts) capped |= l.capped_at_source_density;
  return capped;
}

std::vector<std::pair<double, double>> ReparamResult::curve_cost_q() const {
  std::vector<std::pair<double, double>> points;
  if (curve)
    for (const CurvePoint& p : *curve) points.push_back({p.c_r, p.q});
  return points;
}

json ReparamResult::to_json() const {
  json report;
  report["device"] = device.name;
  report["backend"] = device.backend;
  if (scoring)
    report["scoring"] = {{"resolution", scoring->resolution.resolution},
                         {"filter", eval::to_string(scoring->filter)},
                         {"resolution_capped", scoring->resolution.capped},
                         {"resolution_cropped", scoring->resolution.cropped},
                         {"resolved_fraction", scoring->resolution.resolved_fraction},
                         {"shading", eval::to_string(scoring->shading)}};
  if (curve) {
    report["curve"] = json::array();
    for (const CurvePoint& p : *curve) report["curve"].push_back({{"c_r", p.c_r}, {"q", p.q}, {"layout", p.layout}});
  }
  if (max_gmsd)
    report["max_gmsd"] = {{"bound", max_gmsd->bound},
                          {"met", max_gmsd->met},
                          {"c_r", max_gmsd->c_r},
                          {"q", max_gmsd->q},
                          {"scale", max_gmsd->scale}};
  report["texture_totals"] = {{"old", cost_json(texture_totals.old_cost, texture_totals.old_bytes)},
                              {"new", cost_json(texture_totals.new_cost, texture_totals.new_bytes)},
                              {"resize_bytes", texture_totals.resize_bytes}};
  report["pruned"] = {{"accessors", pruned.accessors}, {"buffer_views", pruned.buffer_views}, {"buffer_bytes", pruned.buffer_bytes}};
  if (!pruned.skipped.empty()) report["pruned"]["skipped"] = pruned.skipped;
  report["chosen"] = chosen;
  report["layout"] = layout;
  report["candidates"] = json::array();
  for (const auto& c : candidates)
    report["candidates"].push_back({{"name", c.name},
                                    {"cost_ratio", c.cost_ratio},
                                    {"q", c.q >= 0 ? json(c.q) : json(nullptr)},
                                    {"overlaps_new", c.overlaps_new},
                                    {"seconds", {{"mesh_stage", c.seconds_mesh},
                                                 {"pack", c.seconds_pack},
                                                 {"rebake", c.seconds_bake},
                                                 {"score", c.seconds_score}}}});
  if (guard.ran) {
    report["guard"] = {{"q_reparam", guard.q_reparam}, {"q_resize", guard.q_resize}, {"resize", "lanczos3-srgb"},
                       {"resize_sides", guard.resize_aligned ? "aligned" : "nearest"}, {"chosen", guard.chosen}};
    if (!guard.unseen.empty()) report["guard"]["unseen"] = guard.unseen;
    if (guard.far)
      report["guard"]["far"] = {{"resolution", guard.far->resolution}, {"q_reparam", guard.far->q_reparam}, {"q_resize", guard.far->q_resize},
                                {"noise_floor", guard.far->noise_floor}};
  }
  else if (!guard.skipped.empty())
    report["guard"] = {{"skipped", guard.skipped}};
  else
    report["guard"] = nullptr;
  report["q"] = q ? json(*q) : json(nullptr);
  report["layouts"] = json::array();
  for (const auto& l : layouts) report["layouts"].push_back(layout_json(l));
  report["textures"] = json::array();
  for (const auto& t : textures) report["textures"].push_back(texture_json(t));
  report["cost_ratio"] = cost_ratio;
  report["flips"] = flips;
  report["overlaps_new"] = overlaps_new;  // always 0 in a written file
  report["overlap_fallback_charts"] = overlap_fallback_charts;
  report["charts"] = charts;
  report["triangles_optimized"] = triangles_optimized;
  report["triangles_infeasible"] = triangles_infeasible;
  json& s = report["stages"] = json::object();
  if (stages.max_gmsd_eval) s["max_gmsd_eval"] = *stages.max_gmsd_eval;
  s["texture_costs"] = stages.texture_costs;
  s["triangle_stage"] = stages.triangle_stage;
  s["mesh_stage"] = stages.mesh_stage;
  s["pack"] = stages.pack;
  s["rebake"] = stages.rebake;
  s["candidates_and_guard"] = stages.candidates_and_guard;
  s["score_far"] = stages.score_far;
  s["candidates_built"] = stages.candidates_built;
  report["warnings"] = warnings;
  report["seconds"] = seconds;
  return report;
}

}  // namespace uvpress::pipeline
