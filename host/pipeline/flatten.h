// `uvpress flatten` on whole files: foldover-free, low-distortion UVs (flatten/flatten.h)
// for an OBJ/OFF disk mesh, or for a glTF asset chart by chart (charts from TEXCOORD_0
// seams; a primitive without UVs is one chart per connected component), and their report.
// UVs are scaled uniformly into [0,1]: a glTF's charts are laid out side by side on shelves
// at one common scale and written as a new TEXCOORD set on every primitive (existing sets
// untouched). Flips are counted on the values as written, and for a glTF the pairs of
// triangles that overlap in the new UVs but did not in TEXCOORD_0 (a flattened chart whose
// free boundary runs over itself keeps its input UVs). Reading and writing files is the
// caller's.
//
// flatten_assign (--assign): the materials use the flattened UVs. Each textured layout's
// charts are flattened at one texel density (pipeline/isometric_charts.h), packed into
// `cost` of the input's texels, every texture of the layout re-baked into them (never
// repointed without a re-bake) and the UV set the materials sample replaced: reparam's
// packing, re-bake and checks (no new overlaps, no flips), scored on screen against the
// input.
#pragma once

#include "core/mesh.h"
#include "engine.h"
#include "flatten/flatten.h"
#include "io/gltf_io.h"
#include "pipeline/reparam.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace uvpress::pipeline {

struct FlattenedChart {
  std::string label;       // "mesh M primitive P chart C" in a glTF, "" for an OBJ/OFF mesh
  Mesh mesh;               // positions + triangles of the chart
  flatten::Result result;  // result.uv: the chart's own UVs, before the layout
  size_t filled_holes = 0;  // boundary loops closed virtually for the solve
  std::string skipped;      // why the chart kept its input UVs ("" when flattened)
};

struct FlattenResult {
  flatten::Method method = flatten::Method::Progressive;
  std::vector<FlattenedChart> charts;
  bool gltf = false;                 // a glTF asset (else one OBJ/OFF mesh)
  std::vector<std::string> uv_sets;  // glTF: the TEXCOORD sets written
  size_t overlaps_new = 0;           // glTF: the caller writes nothing unless 0
};

// The charts together: faces, vertices, flips, iterations and time summed (the time and
// iterations over flattened charts), E_c area-weighted, eta and N_c the largest.
struct FlattenTotals {
  size_t faces = 0, vertices = 0, flips = 0;
  size_t skipped = 0, filled_holes = 0;  // charts that kept their input UVs, holes closed for the solve
  double seconds = 0;
  double energy = 0, area = 0;  // sums of 3-D area x E and of 3-D area: E_c = energy / area
  int iterations = 0, most_iterations = 0, eta = 0;
  bool converged = true;
};
FlattenTotals totals(const FlattenResult& result);

// Called with the name of each stage once it is done: "load" (the glTF's primitives read),
// "flatten" (every chart solved).
using FlattenProgress = std::function<void(const char* stage)>;
// A chart that keeps its input UVs, one line: "mesh M primitive P chart C: skipped: <reason>
// (input UVs kept)".
using FlattenWarning = std::function<void(const std::string& line)>;

// One OBJ/OFF disk mesh, read from `input` (named in errors). `written` receives the mesh
// with its new UVs (per corner as the triangles, as an OBJ's "%.9g" reads back). Throws
// InputError(input, reason) for a non-disk mesh or a failed solve (flatten::invalid_reason).
FlattenResult flatten_mesh(const Mesh& mesh, const flatten::Options& options, const std::string& input, Mesh& written,
                           const FlattenProgress& progress = {});

// A glTF asset: a new TEXCOORD_n (the first unused n) as float32 on every primitive of
// `file.model`. Throws InputError(file.path, reason) for an asset without triangle
// primitives or a chart whose solve failed (a chart that cannot be flattened keeps its
// input UVs, with a warning).
FlattenResult flatten_gltf(io::GltfFile& file, const flatten::Options& options, const FlattenProgress& progress = {},
                           const FlattenWarning& warn = {});

// What the report says about the files, from the caller's I/O.
struct FlattenFiles {
  std::string input, output;
  nlohmann::ordered_json input_validation;  // glTF: the input's rules checked on load
  uint64_t input_bytes = 0, output_bytes = 0;  // the whole asset before and after
};

// The --report: flatten/report.h's summary for a single chart flattened whole, else the
// totals with one summary per chart (`chart`, `filled_holes`, `skipped`); then input,
// output, for a glTF uv_sets_written, charts_skipped, holes_filled, overlaps_new,
// input_validation; then input_bytes, output_bytes.
nlohmann::ordered_json to_json(const FlattenResult& result, const FlattenFiles& files);

// flatten --assign on `file` (changed in place): reparam's report of the isometric layout,
// with what the summary line says.
struct AssignResult {
  ReparamResult reparam;  // what reparam did with the isometric layout
  size_t flattened = 0, kept = 0, holes = 0;  // charts flattened, charts that kept their UVs, holes filled
  std::string uv_sets;                         // the sets replaced, "TEXCOORD_0, TEXCOORD_1"
  bool at_density = false;  // a layout was packed no denser than the source (its cost ratio below `cost`)
};
// Throws InputError(file.path, "--assign: no textured layout to flatten...") when there is
// none, before any warning.
AssignResult flatten_assign(io::GltfFile& file, engine::Engine& engine, double cost, const flatten::Options& options,
                            const Progress& progress = {});
// The --report: input, output, assign, seconds, input_bytes, output_bytes,
// input_validation, then the rest of reparam's report.
nlohmann::ordered_json to_json(const AssignResult& result, const FlattenFiles& files, double seconds);

}  // namespace uvpress::pipeline
