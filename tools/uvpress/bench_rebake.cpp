// uvpress bench rebake: seconds to re-bake a 2048 x 2048 RGBA colour texture (sRGB, alpha:
// linear light, premultiplied) into a packed layout at half the texels, on every backend,
// one JSON line per backend. The layout: 8 x 8 charts of 128 triangles each, moved to
// shuffled cells, turned by multiples of 90 degrees and shrunk to leave gutters, as the
// packer leaves them. "seconds" is the whole atlas::rebake (host set-up, owners, sampling,
// conversions, gutter fill); "sampling_s" the engine's rebake_texels alone. A second line
// per backend, "rebake-lanczos": the same layout through the Lanczos-3 bake of reparam's
// candidates (atlas/rebake_lanczos.h).
#include "bench.h"

#include "atlas/rebake.h"
#include "atlas/rebake_lanczos.h"
#include "atlas/rebake_lsq.h"
#include "io/asset.h"
#include "io/gltf_io.h"
#include "io/image_io.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

namespace uvpress::cli {

namespace {

struct BenchLayout {
  std::vector<uint32_t> idx;
  std::vector<float> old_uv, new_uv;
};

BenchLayout bench_layout(int charts, int grid) {
  BenchLayout L;
  std::mt19937 rng(1);
  std::vector<int> cell(size_t(charts) * charts);
  std::iota(cell.begin(), cell.end(), 0);
  std::shuffle(cell.begin(), cell.end(), rng);
  for (int c = 0; c < charts * charts; ++c) {
    const int oi = c % charts, oj = c / charts, ni = cell[size_t(c)] % charts, nj = cell[size_t(c)] / charts;
    const int turn = int(rng() % 4);
    const uint32_t base = uint32_t(L.old_uv.size() / 2);
    for (int j = 0; j <= grid; ++j)
      for (int i = 0; i <= grid; ++i) {
        const double s = double(i) / grid, t = double(j) / grid;
        L.old_uv.push_back(float((oi + s) / charts));
        L.old_uv.push_back(float((oj + t) / charts));
        double a = s - 0.5, b = t - 0.5;
        for (int k = 0; k < turn; ++k) std::swap(a, b), a = -a;
        L.new_uv.push_back(float((ni + 0.5 + 0.92 * a) / charts));
        L.new_uv.push_back(float((nj + 0.5 + 0.92 * b) / charts));
      }
    for (int j = 0; j < grid; ++j)
      for (int i = 0; i < grid; ++i) {
        const uint32_t v = base + uint32_t(j * (grid + 1) + i), w = uint32_t(grid + 1);
        L.idx.insert(L.idx.end(), {v, v + 1, v + w + 1, v, v + w + 1, v + w});
      }
  }
  return L;
}

void bench_rebake(const Globals& g, uint32_t size, uint32_t out_size, int repeats) {
  Image src;
  src.width = src.height = size, src.channels = 4, src.bits = 8;
  src.pixels.resize(size_t(size) * size * 4);
  uint32_t h = 12345;
  for (size_t i = 0; i < src.pixels.size(); ++i) {
    h = h * 1664525u + 1013904223u;
    src.pixels[i] = float((h >> 24) & 0xffu) / 255.0f;
  }
  const BenchLayout L = bench_layout(8, 8);
  const atlas::RebakeMesh mesh{L.idx.data(), L.idx.size(), L.old_uv.data(), L.new_uv.data(), L.old_uv.size() / 2};
  atlas::RebakeOptions o;
  o.width = o.height = out_size;
  o.role = atlas::RebakeRole::Color;
  for (auto& b : available_backends(g, "rebake")) {
    atlas::RebakeStats stats;
    atlas::rebake(src, {mesh}, o, *b.engine, &stats);  // warm-up: pipelines, buffers, page faults
    double best = 1e300, best_sampling = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      atlas::rebake(src, {mesh}, o, *b.engine, &stats);
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      best_sampling = std::min(best_sampling, stats.sample_seconds);
    }
    const auto d = b.engine->device();
    nlohmann::ordered_json line = {{"bench", "rebake"},       {"backend", d.backend},
                                   {"device", d.name},        {"device_type", d.type},
                                   {"threads", d.threads},    {"size", size},
                                   {"out_size", out_size},    {"channels", 4},
                                   {"triangles", stats.triangles}, {"covered", stats.covered},
                                   {"seconds", best},         {"sampling_s", best_sampling}};
    std::printf("%s\n", line.dump().c_str());
    std::fflush(stdout);
    // The Lanczos-3 bake reparam's candidates use (atlas/rebake_lanczos.h): the same
    // layout, every covered texel filtered on the host, the area bake only where it stays.
    double best_lanczos = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      atlas::rebake_lanczos(src, {mesh}, o, *b.engine, &stats);
      best_lanczos = std::min(best_lanczos, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    line["bench"] = "rebake-lanczos", line["seconds"] = best_lanczos, line.erase("sampling_s");
    std::printf("%s\n", line.dump().c_str());
    std::fflush(stdout);
  }
}

constexpr double kPi = 3.14159265358979323846;

// Bilinear sample in linear light (colour decoded per texel), texel centres at + 0.5, clamped.
double sample_linear(const Image& im, double u, double v, uint32_t c, bool srgb) {
  const double x = u * im.width - 0.5, y = v * im.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y), ax = x - fx, ay = y - fy;
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, int(im.width) - 1), j = std::clamp(j, 0, int(im.height) - 1);
    const float s = im.at(uint32_t(i), uint32_t(j), c);
    return srgb ? double(atlas::srgb_to_linear(s)) : double(s);
  };
  const int i = int(fx), j = int(fy);
  return (1 - ay) * ((1 - ax) * at(i, j) + ax * at(i + 1, j)) + ay * ((1 - ax) * at(i, j + 1) + ax * at(i + 1, j + 1));
}

// RMS over `count` area-uniform random points of the new-UV triangles (colour channels).
double surface_rms(const Image& source, const Image& baked, const BenchLayout& L, bool srgb, int count) {
  std::vector<double> cum;
  double total = 0;
  for (size_t t = 0; t + 2 < L.idx.size(); t += 3) {
    const float* a = &L.new_uv[2 * L.idx[t]];
    const float* b = &L.new_uv[2 * L.idx[t + 1]];
    const float* c = &L.new_uv[2 * L.idx[t + 2]];
    total += std::abs(double(b[0] - a[0]) * (c[1] - a[1]) - double(c[0] - a[0]) * (b[1] - a[1]));
    cum.push_back(total);
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  const uint32_t channels = std::min<uint32_t>(source.channels, 3);
  double sum = 0;
  for (int s = 0; s < count; ++s) {
    const size_t t = std::min(size_t(std::lower_bound(cum.begin(), cum.end(), U(rng) * total) - cum.begin()), cum.size() - 1) * 3;
    double r1 = U(rng), r2 = U(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const double w[3] = {1 - r1 - r2, r1, r2};
    double nu = 0, nv = 0, ou = 0, ov = 0;
    for (int k = 0; k < 3; ++k) {
      const uint32_t id = L.idx[t + size_t(k)];
      nu += w[k] * L.new_uv[2 * id], nv += w[k] * L.new_uv[2 * id + 1];
      ou += w[k] * L.old_uv[2 * id], ov += w[k] * L.old_uv[2 * id + 1];
    }
    for (uint32_t c = 0; c < channels; ++c) {
      const double d = sample_linear(baked, nu, nv, c, srgb) - sample_linear(source, ou, ov, c, srgb);
      sum += d * d;
    }
  }
  return std::sqrt(sum / (double(count) * channels));
}

// Sinusoids up to ~0.4 cycles per texel in several directions plus noise, 8-bit RGB.
Image detailed_texture(uint32_t size) {
  Image im;
  im.width = im.height = size, im.channels = 3, im.bits = 8;
  im.pixels.resize(size_t(size) * size * 3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1, 1);
  for (uint32_t y = 0; y < size; ++y)
    for (uint32_t x = 0; x < size; ++x)
      for (uint32_t c = 0; c < 3; ++c) {
        const double v = 0.5 + 0.18 * std::sin(2 * kPi * (0.31 * x + 0.07 * y) + c) +
                         0.12 * std::sin(2 * kPi * (0.05 * x - 0.23 * y) + 2 * c) +
                         0.08 * std::sin(2 * kPi * (0.11 * x + 0.13 * y)) + 0.07 * noise(rng);
        im.at(x, y, c) = float(std::round(std::clamp(v, 0.0, 1.0) * 255.0) / 255.0);
      }
  return im;
}

// The old UVs turned by `degrees` about the centre at `scale` times the source density; the
// new image is as large as the turned, scaled [0,1]^2 needs (one texel of margin a side).
uint32_t transform_layout(BenchLayout& L, uint32_t source_size, double degrees, double scale) {
  const double c = std::cos(degrees * kPi / 180), s = std::sin(degrees * kPi / 180);
  const uint32_t size = uint32_t(std::ceil(source_size * scale * (std::abs(c) + std::abs(s)))) + 2;
  const double k = double(source_size) * scale / size;
  L.new_uv.resize(L.old_uv.size());
  for (size_t i = 0; i + 1 < L.old_uv.size(); i += 2) {
    const double u = L.old_uv[i] - 0.5, v = L.old_uv[i + 1] - 0.5;
    L.new_uv[i] = float(0.5 + k * (c * u - s * v));
    L.new_uv[i + 1] = float(0.5 + k * (s * u + c * v));
  }
  return size;
}

void bench_rebake_lsq(const std::vector<std::string>& assets, int points) {
  struct Case {
    std::string name;
    Image source;
    BenchLayout layout;  // old_uv and idx
  };
  std::vector<Case> cases;
  {
    Case g{"generated", detailed_texture(256), {}};
    const int n = 16;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        g.layout.old_uv.push_back(float(0.0625 + 0.875 * i / n)), g.layout.old_uv.push_back(float(0.0625 + 0.875 * j / n));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t v = uint32_t(j * (n + 1) + i), w = uint32_t(n + 1);
        g.layout.idx.insert(g.layout.idx.end(), {v, v + 1, v + w + 1, v, v + w + 1, v + w});
      }
    cases.push_back(std::move(g));
  }
  for (const std::string& path : assets) {
    const io::GltfFile file = io::load_gltf(path);
    const io::Asset asset = io::build_asset(file);
    for (const io::AssetImage& im : asset.images) {
      const io::ImageUse* use = nullptr;
      for (const io::ImageUse& u : im.uses)
        if (u.role == io::TextureRole::BaseColor && !u.tiled) use = &u;
      if (!use) continue;
      Case a{path, io::decode_image(file.image_bytes.at(size_t(im.index)), path), {}};
      const io::Primitive& p = asset.primitives.at(size_t(use->primitive));
      const auto& uv = p.uv_sets.at(size_t(use->tex_coord)).uv;
      for (size_t i = 0; i + 1 < uv.size(); i += 2) {
        const auto t = use->transform.present ? use->transform.apply(uv[i], uv[i + 1]) : std::array<float, 2>{uv[i], uv[i + 1]};
        a.layout.old_uv.push_back(t[0]), a.layout.old_uv.push_back(t[1]);
      }
      a.layout.idx = p.indices;
      if (a.source.width != a.source.height) continue;  // the layouts below assume a square source
      cases.push_back(std::move(a));
      break;
    }
  }
  const auto cpu = engine::make_cpu_engine({});  // the area bake on the oracle, as the solve's own filter
  for (Case& cs : cases) {
    for (auto [degrees, scale] : {std::pair{30.0, 1.0}, std::pair{0.0, 0.7}, std::pair{30.0, 0.7}}) {
      BenchLayout L = cs.layout;
      const uint32_t size = transform_layout(L, cs.source.width, degrees, scale);
      const atlas::RebakeMesh mesh{L.idx.data(), L.idx.size(), L.old_uv.data(), L.new_uv.data(), L.old_uv.size() / 2};
      atlas::RebakeOptions o;
      o.width = o.height = size, o.role = atlas::RebakeRole::Color;
      const auto t0 = std::chrono::steady_clock::now();
      const Image area = atlas::rebake(cs.source, {mesh}, o, *cpu);
      const double area_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      atlas::LsqBakeStats st;
      const Image lsq = atlas::rebake_least_squares(cs.source, {mesh}, o, area, &st);
      const double e_area = surface_rms(cs.source, area, L, true, points);
      const double e_lsq = surface_rms(cs.source, lsq, L, true, points);
      nlohmann::ordered_json line = {{"bench", "rebake-lsq"},
                                     {"asset", cs.name},
                                     {"source", cs.source.width},
                                     {"size", size},
                                     {"degrees", degrees},
                                     {"scale", scale},
                                     {"rms_area", e_area},
                                     {"rms_lsq", e_lsq},
                                     {"ratio", e_area > 0 ? e_lsq / e_area : 1.0},
                                     {"area_s", area_s},
                                     {"lsq_s", st.seconds},
                                     {"iterations", st.iterations},
                                     {"residual", {st.initial_residual, st.final_residual}},
                                     {"samples", st.samples},
                                     {"unknowns", st.unknowns}};
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  }
}

}  // namespace

void add_bench_rebake(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("rebake", "Seconds to re-bake a 2048^2 RGBA texture per backend");
  auto size = std::make_shared<uint32_t>(2048);
  auto out_size = std::make_shared<uint32_t>(1448);
  auto repeats = std::make_shared<int>(3);
  cmd->add_option("--size", *size, "Source texture, texels a side")->capture_default_str()->check(CLI::Range(16u, 8192u));
  cmd->add_option("--out-size", *out_size, "New texture, texels a side (1448: half the texels)")
      ->capture_default_str()
      ->check(CLI::Range(16u, 8192u));
  cmd->add_option("--repeat", *repeats, "Timed repetitions (the best is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->callback([&g, size, out_size, repeats] {
    g.action = [&g, size, out_size, repeats] {
      bench_rebake(g, *size, *out_size, *repeats);
      return 0;
    };
  });
}

void add_bench_rebake_lsq(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("rebake-lsq", "Least-squares vs area-filtered re-bake: error ratio and seconds");
  auto assets = std::make_shared<std::vector<std::string>>();
  auto points = std::make_shared<int>(400000);
  cmd->add_option("--asset", *assets, "Also bench the base colour of these glTF files (repeatable)");
  cmd->add_option("--points", *points, "Random surface points of the error measure")
      ->capture_default_str()
      ->check(CLI::Range(1000, 100000000));
  cmd->callback([&g, assets, points] {
    g.action = [assets, points] {
      bench_rebake_lsq(*assets, *points);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
