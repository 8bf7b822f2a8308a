// uvpress bench flatten: every method side by side on the same meshes, one JSON line per
// mesh and method: N_c, eta (eq. 12, eps = 0.01), t_c, E_c (normalized by area), seconds
// per iteration and per numeric factorization, numeric factorizations and PCG iterations
// (sparse_system.h: most steps reuse an earlier factor), flips, peak memory. Meshes: every .obj/.off
// in --meshes (default ../shared/meshes), plus camelhead subdivided 1:4 at the edge
// midpoints (flat subdivision: the same surface, 4^k as many faces) - level 2 is 363,264
// faces ("camelhead-s2", about 360K), level 3 is 1,453,056 ("camelhead-s3", about 1.4M).
#include "bench.h"

#include "core/error.h"
#include "flatten/flatten.h"
#include "flatten/report.h"
#include "io/mesh_io.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

namespace uvpress::cli {

namespace {

namespace fs = std::filesystem;

// 1:4 midpoint subdivision; new vertices are shared across each edge.
Mesh subdivide(const Mesh& m) {
  Mesh out;
  out.positions = m.positions;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
  auto midpoint = [&](uint32_t a, uint32_t b) {
    auto key = std::make_pair(std::min(a, b), std::max(a, b));
    auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const uint32_t id = uint32_t(out.positions.size() / 3);
    for (int k = 0; k < 3; ++k)
      out.positions.push_back(0.5 * (m.positions[3 * size_t(a) + size_t(k)] + m.positions[3 * size_t(b) + size_t(k)]));
    mid.emplace(key, id);
    return id;
  };
  out.triangles.reserve(4 * m.triangles.size());
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t a = m.triangles[3 * t], b = m.triangles[3 * t + 1], c = m.triangles[3 * t + 2];
    const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.triangles.insert(out.triangles.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  return out;
}

struct Args {
  std::string meshes = "../shared/meshes";
  std::vector<std::string> only;     // mesh names (file stems, camelhead-s2, camelhead-s3)
  std::vector<std::string> methods;  // default: all
  std::vector<int> levels{2, 3};     // camelhead subdivision levels to add
  int max_iterations = 5000;
};

void run(const Args& a) {
  std::vector<std::pair<std::string, fs::path>> files;
  if (!fs::is_directory(a.meshes)) throw InputError(a.meshes, "not a folder (use --meshes)");
  for (auto& e : fs::directory_iterator(a.meshes)) {
    const auto ext = e.path().extension();
    if (ext == ".obj" || ext == ".off") files.emplace_back(e.path().stem().string(), e.path());
  }
  std::sort(files.begin(), files.end());
  auto wanted = [&](const std::string& name) {
    return a.only.empty() || std::find(a.only.begin(), a.only.end(), name) != a.only.end();
  };
  std::vector<flatten::Method> methods;
  for (const auto& m : a.methods) methods.push_back(*flatten::parse_method(m));
  if (methods.empty()) methods = flatten::all_methods();

  auto bench_mesh = [&](const std::string& name, const Mesh& mesh) {
    for (flatten::Method method : methods) {
      flatten::Options o;
      o.method = method;
      o.max_iterations = a.max_iterations;
      flatten::reset_peak_rss();
      flatten::Result r;
      try {
        r = flatten::flatten(mesh, o);
      } catch (const flatten::FlattenError& e) {
        std::fprintf(stderr, "bench flatten: %s: %s\n", name.c_str(), e.what());
        return;
      }
      nlohmann::ordered_json line = {{"bench", "flatten"}, {"mesh", name}};
      line.update(flatten::summary_json(r, method, mesh.triangle_count(), mesh.vertex_count()));
      double factorization = 0;
      for (const auto& rec : r.log) factorization += rec.t_factorization;
      line["s_per_factorization"] = r.factorizations ? factorization / r.factorizations : 0.0;
      line["iter_over_factorization"] = factorization > 0 ? r.seconds / factorization : 0.0;
      line["threads"] = flatten::thread_count();
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  };

  Mesh camelhead;
  for (const auto& [name, path] : files) {
    if (name == "camelhead") camelhead = io::read_mesh(path.string());
    if (!wanted(name)) continue;
    bench_mesh(name, name == "camelhead" ? camelhead : io::read_mesh(path.string()));
  }
  if (camelhead.triangles.empty()) return;
  Mesh m = camelhead;
  int level = 0;
  const int deepest = a.levels.empty() ? 0 : *std::max_element(a.levels.begin(), a.levels.end());
  while (level < deepest) {
    const std::string next = "camelhead-s" + std::to_string(level + 1);
    bool needed = false;  // anything at this level or deeper wanted?
    for (int l : a.levels) needed = needed || (l > level && wanted("camelhead-s" + std::to_string(l)));
    if (!needed) break;
    m = subdivide(m);
    ++level;
    if (std::find(a.levels.begin(), a.levels.end(), level) != a.levels.end() && wanted(next)) bench_mesh(next, m);
  }
}

}  // namespace

void add_bench_flatten(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("flatten", "Progressive parameterization vs SLIM, CM, P-CM, HYBRID on the test meshes");
  auto a = std::make_shared<Args>();
  cmd->add_option("--meshes", a->meshes, "Folder of .obj/.off disk meshes")->capture_default_str();
  cmd->add_option("--mesh", a->only, "Only these meshes (file stem, camelhead-s2, camelhead-s3; several allowed)");
  cmd->add_option("--method", a->methods, "Only these methods (several allowed)")
      ->check(CLI::IsMember({"progressive", "slim", "cm", "p-cm", "hybrid"}));
  cmd->add_option("--subdivide", a->levels, "camelhead subdivision levels to add (0 for none)")->capture_default_str();
  cmd->add_option("--max-iter", a->max_iterations, "Iteration limit per run")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->callback([&g, a] {
    g.action = [a] {
      run(*a);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
