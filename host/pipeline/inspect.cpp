#include "pipeline/inspect.h"

#include "atlas/charts.h"
#include "io/asset.h"
#include "io/image_io.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

json inspect(const io::GltfFile& file) {
  const io::Asset asset = io::build_asset(file);
  const auto& m = file.model;
  json out;
  out["file"] = file.path;
  out["generator"] = m.asset.generator;
  out["counts"] = {{"nodes", m.nodes.size()},         {"meshes", m.meshes.size()},
                   {"primitives", asset.primitives.size()}, {"materials", m.materials.size()},
                   {"textures", m.textures.size()},   {"images", m.images.size()},
                   {"animations", m.animations.size()}, {"skins", m.skins.size()}};
  out["extensions_used"] = m.extensionsUsed;
  out["extensions_required"] = m.extensionsRequired;

  size_t triangles = 0;
  json prims = json::array();
  for (const auto& p : asset.primitives) {
    triangles += p.triangle_count();
    json jp = {{"mesh", p.mesh},           {"primitive", p.primitive}, {"mesh_name", p.mesh_name},
               {"material", p.material},   {"triangles", p.triangle_count()}, {"vertices", p.vertex_count()}};
    json sets = json::array();
    for (size_t s = 0; s < p.uv_sets.size(); ++s) {
      const auto& uv = p.uv_sets[s];
      if (uv.uv.empty()) continue;
      Mesh welded = atlas::weld_uv_mesh(p.positions.data(), uv.uv.data(), p.vertex_count(), p.indices.data(),
                                        p.indices.size());
      sets.push_back({{"set", s},
                      {"min", {uv.min[0], uv.min[1]}},
                      {"max", {uv.max[0], uv.max[1]}},
                      {"charts", atlas::find_charts(welded).count},
                      {"normalized", uv.normalized},
                      {"component_type", uv.component_type}});
    }
    jp["uv_sets"] = sets;
    prims.push_back(jp);
  }
  out["triangles"] = triangles;
  out["skipped_primitives"] = asset.skipped_primitives;
  out["primitives"] = prims;

  bool any_tiled = false;
  json images = json::array();
  for (const auto& img : asset.images) {
    const std::string label = file.path + ": " + img.name;
    io::ImageHeader h = io::read_image_header(file.image_bytes[size_t(img.index)], label);
    json ji = {{"index", img.index},
               {"name", img.name},
               {"width", h.width},
               {"height", h.height},
               {"channels", h.channels},
               {"bits", h.bits},
               {"format", h.format},
               {"bytes", file.image_bytes[size_t(img.index)].size()},
               {"color_space", img.color_space == ColorSpace::Srgb ? "sRGB" : "linear"},
               {"mixed_color_spaces", img.mixed_color_spaces}};
    json uses = json::array();
    for (const auto& u : img.uses) {
      any_tiled |= u.tiled;
      json ju = {{"material", u.material},
                 {"material_name", u.material >= 0 ? m.materials[size_t(u.material)].name : ""},
                 {"role", io::to_string(u.role)},
                 {"slot", u.slot},
                 {"texture", u.texture},
                 // glTF's numbering, as in `primitives` (mesh m, its primitive p: "m.p").
                 {"mesh", asset.primitives[size_t(u.primitive)].mesh},
                 {"primitive", asset.primitives[size_t(u.primitive)].primitive},
                 {"tex_coord", u.tex_coord},
                 {"wrap", {u.wrap_s, u.wrap_t}},
                 {"tiled", u.tiled}};
      if (u.transform.present)
        ju["transform"] = {{"offset", {u.transform.offset[0], u.transform.offset[1]}},
                           {"rotation", u.transform.rotation},
                           {"scale", {u.transform.scale[0], u.transform.scale[1]}}};
      uses.push_back(ju);
    }
    ji["uses"] = uses;
    json materials = json::array();
    for (const auto& u : img.uses)
      if (std::find(materials.begin(), materials.end(), u.material) == materials.end()) materials.push_back(u.material);
    ji["materials"] = materials;
    images.push_back(ji);
  }
  out["images"] = images;
  out["tiled"] = any_tiled;
  return out;
}

std::string format_inspection(const json& info) {
  std::string s;
  char buf[512];
  const auto& c = info["counts"];
  std::snprintf(buf, sizeof buf, "%s: %zu triangles in %zu primitives, %zu materials, %zu images, %zu animations, %zu skins\n",
                std::filesystem::path(info["file"].get<std::string>()).filename().c_str(), info["triangles"].get<size_t>(),
                c["primitives"].get<size_t>(), c["materials"].get<size_t>(), c["images"].get<size_t>(),
                c["animations"].get<size_t>(), c["skins"].get<size_t>());
  s += buf;
  for (const auto& p : info["primitives"]) {
    std::snprintf(buf, sizeof buf, "primitive %d.%d \"%s\" material %d: %zu triangles, %zu vertices\n",
                  p["mesh"].get<int>(), p["primitive"].get<int>(), p["mesh_name"].get<std::string>().c_str(),
                  p["material"].get<int>(), p["triangles"].get<size_t>(), p["vertices"].get<size_t>());
    s += buf;
    if (p["uv_sets"].empty()) s += "  no UV sets\n";
    for (const auto& uv : p["uv_sets"]) {
      std::snprintf(buf, sizeof buf, "  TEXCOORD_%d: u [%.4g, %.4g] v [%.4g, %.4g], %u charts%s\n", uv["set"].get<int>(),
                    uv["min"][0].get<double>(), uv["max"][0].get<double>(), uv["min"][1].get<double>(),
                    uv["max"][1].get<double>(), uv["charts"].get<unsigned>(),
                    uv["normalized"].get<bool>() ? " (normalized integers)" : "");
      s += buf;
    }
  }
  for (const auto& img : info["images"]) {
    std::snprintf(buf, sizeof buf, "image %d \"%s\": %ux%u, %u channels, %u-bit %s, %s%s, %zu bytes\n",
                  img["index"].get<int>(), img["name"].get<std::string>().c_str(), img["width"].get<unsigned>(),
                  img["height"].get<unsigned>(), img["channels"].get<unsigned>(), img["bits"].get<unsigned>(),
                  img["format"].get<std::string>().c_str(), img["color_space"].get<std::string>().c_str(),
                  img["mixed_color_spaces"].get<bool>() ? " (also sampled as data)" : "", img["bytes"].get<size_t>());
    s += buf;
    if (img["uses"].empty()) s += "  unused\n";
    for (const auto& u : img["uses"]) {
      std::snprintf(buf, sizeof buf, "  %s of material %d \"%s\" on primitive %d.%d via TEXCOORD_%d%s%s\n",
                    u["role"].get<std::string>().c_str(), u["material"].get<int>(),
                    u["material_name"].get<std::string>().c_str(), u["mesh"].get<int>(), u["primitive"].get<int>(),
                    u["tex_coord"].get<int>(),
                    u.contains("transform") ? " with KHR_texture_transform" : "",
                    u["tiled"].get<bool>() ? " - tiled (UVs leave [0,1] under REPEAT): its layout is left as it is" : "");
      s += buf;
    }
  }
  return s;
}

}  // namespace uvpress::pipeline
