// reparam's report: ReparamResult as JSON, keys in the order the README documents.
#include "reparam.h"
#include "texture_costs.h"

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

bool ReparamResult::capped_at_source_density() const {
  bool capped = false;
  for (const auto& l : layouts) capped |= l.value("capped_at_source_density", false);
  return capped;
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
    for (const auto& [c_r, q] : *curve) report["curve"].push_back({{"c_r", c_r}, {"q", q}});
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
                                    {"overlaps_new", c.overlaps_new}});
  if (guard.ran)
    report["guard"] = {{"q_reparam", guard.q_reparam}, {"q_resize", guard.q_resize}, {"resize", "lanczos3-srgb"},
                       {"chosen", guard.chosen}};
  else if (!guard.skipped.empty())
    report["guard"] = {{"skipped", guard.skipped}};
  else
    report["guard"] = nullptr;
  report["q"] = q ? json(*q) : json(nullptr);
  report["layouts"] = layouts;
  report["textures"] = textures;
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
  report["warnings"] = warnings;
  report["seconds"] = seconds;
  return report;
}

}  // namespace uvpress::pipeline
