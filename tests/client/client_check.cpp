#include "client/client_check.h"

#include "support.h"

#include "core/quantile.h"
#include "eval/resize.h"
#include "io/gltf_io.h"
#include "io/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace uvpress::test::client {

namespace {

// Debian's chromium, or UVPRESS_CHROMIUM (another build; a missing path shows the skip).
fs::path chromium_path() {
  const char* env = std::getenv("UVPRESS_CHROMIUM");
  return env && *env ? fs::path(env) : fs::path("/usr/bin/chromium");
}

fs::path source_dir() { return fs::path(UVPRESS_SOURCE_DIR); }

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

// file:// URL of an absolute path (percent-encoding what a URL cannot hold as is).
std::string file_url(const fs::path& p) {
  static const char* hex = "0123456789ABCDEF";
  std::string out = "file://";
  for (unsigned char c : fs::absolute(p).lexically_normal().string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

// One headless Chromium run on `url` with SwiftShader WebGL, bounded by `timeout_s`: its
// --dump-dom in `dom`, its stderr in `log`. Returns the exit status.
int run_chromium(const std::string& url, const fs::path& work, const fs::path& dom, const fs::path& log, int timeout_s,
                 int virtual_ms) {
  const fs::path profile = work / "chromium-profile";
  fs::create_directories(profile);
  const std::string cmd = "timeout -k 5 " + std::to_string(timeout_s) + " " + quote(chromium_path().string()) +
                          " --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader"
                          " --allow-file-access-from-files --no-first-run --disable-background-networking"
                          " --disable-component-update --disable-sync --disable-quic --disable-extensions"
                          " --user-data-dir=" + quote(profile.string()) +
                          " --virtual-time-budget=" + std::to_string(virtual_ms) + " --dump-dom " + quote(url) + " >" +
                          quote(dom.string()) + " 2>" + quote(log.string()) + " </dev/null";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string element_text(const std::string& dom, const std::string& id) {
  const std::string open = "id=\"" + id + "\">";
  const size_t a = dom.find(open);
  if (a == std::string::npos) return {};
  const size_t b = dom.find('<', a + open.size());
  return dom.substr(a + open.size(), b == std::string::npos ? std::string::npos : b - a - open.size());
}

std::vector<uint8_t> base64_decode(const std::string& s) {
  std::vector<int> value(256, -1);
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < alphabet.size(); ++i) value[static_cast<unsigned char>(alphabet[i])] = int(i);
  std::vector<uint8_t> out;
  out.reserve(s.size() * 3 / 4);
  uint32_t acc = 0;
  int bits = 0;
  for (unsigned char c : s) {
    if (value[c] < 0) continue;  // '=' padding and whitespace
    acc = (acc << 6) | uint32_t(value[c]);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t((acc >> bits) & 0xFF));
    }
  }
  return out;
}

std::string tail(const std::string& s, size_t n) { return s.size() <= n ? s : "…" + s.substr(s.size() - n); }

// Lines of Chromium's stderr worth showing (its D-Bus and GPU-blocklist chatter is not).
std::string relevant_log(const std::string& log) {
  std::istringstream in(log);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (line.find("dbus") != std::string::npos || line.find("DBus") != std::string::npos) continue;
    out += line + "\n";
  }
  return tail(out, 2000);
}

}  // namespace

bool three_installed() {
  return fs::exists(source_dir() / "tools/node_modules/three/build/three.module.js") &&
         fs::exists(source_dir() / "tools/node_modules/three/examples/jsm/loaders/GLTFLoader.js");
}

std::optional<std::string> chromium_unavailable() {
  static std::optional<std::optional<std::string>> cached;
  if (cached) return *cached;
  auto decide = [&]() -> std::optional<std::string> {
    if (!fs::exists(chromium_path())) return chromium_path().string() + " is absent (tools/install-deps.sh installs chromium)";
    const fs::path work = fs::temp_directory_path() / ("uvpress-client-probe-" + std::to_string(::getpid()));
    fs::create_directories(work);
    // A page that says whether WebGL 2 gets a context.
    const fs::path page = work / "probe.html";
    std::ofstream(page) << "<!doctype html><html><body><pre id=\"status\">no script</pre><script>"
                           "const gl = document.createElement('canvas').getContext('webgl2');"
                           "document.getElementById('status').textContent = gl ? 'webgl2 ' + gl.getParameter(gl.VERSION)"
                           " : 'no webgl2 context';</script></body></html>";
    std::optional<std::string> why;
    for (int attempt = 0; attempt < 2; ++attempt) {
      const int rc = run_chromium(file_url(page), work, work / "dom.html", work / "log.txt", 60, 1000);
      const std::string status = element_text(read_file(work / "dom.html"), "status");
      if (rc == 0 && status.rfind("webgl2 ", 0) == 0) {
        why.reset();
        break;
      }
      why = rc != 0 ? "Chromium cannot start (exit " + std::to_string(rc) + "): " + relevant_log(read_file(work / "log.txt"))
                    : "Chromium starts but WebGL 2 does not (SwiftShader): " + status;
    }
    std::error_code ec;
    fs::remove_all(work, ec);
    return why;
  };
  cached = decide();
  return *cached;
}

Render render(const std::vector<fs::path>& glbs, const fs::path& work, int tile) {
  if (!three_installed())
    throw std::runtime_error("three.js is not in tools/node_modules (run tools/install-deps.sh)");
  fs::create_directories(work);
  std::string models;
  for (const auto& g : glbs) {
    if (g.extension() != ".glb") throw std::runtime_error("render: .glb only: " + g.string());
    models += (models.empty() ? "" : ",") + file_url(g);
  }
  const std::string url = file_url(source_dir() / "tests/client/render.html") + "?tile=" + std::to_string(tile) +
                          "&models=" + models;
  std::string why;
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const fs::path dom = work / "dom.html", log = work / "chromium.log";
    const int rc = run_chromium(url, work, dom, log, 180, 120000);
    const std::string text = read_file(dom);
    const std::string status = element_text(text, "status");
    if (rc != 0 || status.rfind("done ", 0) != 0) {
      why = "attempt " + std::to_string(attempt) + ": Chromium exit " + std::to_string(rc) + ", page status '" +
            tail(status, 2000) + "'\n" + relevant_log(read_file(log));
      continue;
    }
    const std::string data = element_text(text, "result");
    const std::string prefix = "data:image/png;base64,";
    if (data.rfind(prefix, 0) != 0) {
      why = "attempt " + std::to_string(attempt) + ": no PNG in the page";
      continue;
    }
    Render r;
    r.image = io::decode_image(base64_decode(data.substr(prefix.size())), "three.js render");
    r.status = status;
    r.attempts = attempt;
    std::istringstream s(status.substr(5));
    int w = 0, h = 0;
    s >> w >> h >> r.tile >> r.rows >> r.columns;
    const auto views = nlohmann::json::parse(element_text(text, "views"), nullptr, false);
    if (views.is_array())
      for (const auto& v : views) r.views.push_back({v.value("name", ""), v.value("kind", "")});
    if (int(r.image.width) != w || int(r.image.height) != h || r.rows != int(glbs.size()) + 1 ||
        r.columns != int(r.views.size()) || r.image.channels < 3) {
      why = "attempt " + std::to_string(attempt) + ": unexpected render " + status;
      continue;
    }
    // A black mask row (nothing drawn) is a failed frame: the page retries, and so do we.
    bool lit = false;
    for (uint32_t y = uint32_t(r.tile) * uint32_t(r.rows - 1); y < r.image.height && !lit; ++y)
      for (uint32_t x = 0; x < r.image.width && !lit; ++x) lit = r.image.at(x, y, 0) > 0.5f;
    if (!lit) {
      why = "attempt " + std::to_string(attempt) + ": black frame";
      continue;
    }
    return r;
  }
  throw std::runtime_error("three.js render failed three times: " + why);
}

std::vector<ViewDiff> compare(const Render& r, int a, int b) {
  std::vector<ViewDiff> out;
  const uint32_t T = uint32_t(r.tile);
  const uint32_t mask_row = uint32_t(r.rows - 1);
  for (int v = 0; v < r.columns; ++v) {
    ViewDiff d;
    d.view = r.views[size_t(v)].name;
    d.kind = r.views[size_t(v)].kind;
    std::vector<double> diffs;
    diffs.reserve(size_t(T) * T);
    for (uint32_t y = 0; y < T; ++y)
      for (uint32_t x = 0; x < T; ++x) {
        const uint32_t px = uint32_t(v) * T + x;
        if (r.image.at(px, mask_row * T + y, 0) < 0.5f) continue;
        double m = 0;
        for (uint32_t c = 0; c < 3; ++c)
          m = std::max(m, std::abs(double(r.image.at(px, uint32_t(a) * T + y, c)) -
                                   double(r.image.at(px, uint32_t(b) * T + y, c))));
        diffs.push_back(std::round(m * 255.0));
      }
    d.covered = diffs.size();
    double sum = 0;
    for (double x : diffs) sum += x;
    d.mean = diffs.empty() ? 0 : sum / double(diffs.size());
    d.p99 = quantile(diffs, 0.99);
    out.push_back(d);
  }
  return out;
}

nlohmann::json write_resize(const fs::path& input_glb, const fs::path& output_glb, const fs::path& resize_glb) {
  io::GltfFile in = io::load_gltf(input_glb.string());
  const io::GltfFile out = io::load_gltf(output_glb.string());
  if (in.image_bytes.size() != out.image_bytes.size())
    throw std::runtime_error("input and output have different image counts");
  nlohmann::json resized = nlohmann::json::array();
  for (size_t i = 0; i < in.image_bytes.size(); ++i) {
    const auto hin = io::read_image_header(in.image_bytes[i], "input image " + std::to_string(i));
    const auto hout = io::read_image_header(out.image_bytes[i], "output image " + std::to_string(i));
    if (hin.width == hout.width && hin.height == hout.height) continue;
    // The output's texels at the input's aspect ratio, as reparam's guard sizes its resize.
    const double texels = double(hout.width) * hout.height;
    const uint32_t w = std::max(1u, uint32_t(std::lround(std::sqrt(texels * hin.width / hin.height))));
    const uint32_t h = std::max(1u, uint32_t(std::lround(texels / w)));
    const Image img = io::decode_image(in.image_bytes[i], "input image " + std::to_string(i));
    // Encoded as reparam writes its textures: the input's codec and settings (a palette for
    // a paletted PNG), so that both sides carry the same encoder's loss.
    in.image_bytes[i] = io::encode_image(eval::resize_lanczos3(img, w, h, false), io::encode_settings_of(in.image_bytes[i]));
    resized.push_back({{"image", i}, {"from", {hin.width, hin.height}}, {"to", {w, h}}, {"output", {hout.width, hout.height}}});
  }
  io::save_gltf(in, resize_glb.string());
  return resized;
}

Verdict judge(const std::vector<ViewDiff>& output, const std::vector<ViewDiff>& resize) {
  Verdict v;
  v.json["views"] = nlohmann::json::array();
  v.json["margins"] = {{"mean", kMeanMargin}, {"p99", kP99Margin}, {"min_covered", kMinCovered}};
  for (size_t i = 0; i < output.size(); ++i) {
    const ViewDiff& o = output[i];
    const ViewDiff& r = resize[i];
    const bool judged = o.covered >= kMinCovered;
    const bool pass = !judged || (o.mean <= r.mean + kMeanMargin && o.p99 <= r.p99 + kP99Margin);
    v.json["views"].push_back({{"view", o.view},
                               {"kind", o.kind},
                               {"covered", o.covered},
                               {"output", {{"mean", o.mean}, {"p99", o.p99}}},
                               {"resize", {{"mean", r.mean}, {"p99", r.p99}}},
                               {"judged", judged},
                               {"pass", pass}});
    if (!pass) {
      v.pass = false;
      std::ostringstream s;
      s.precision(3);
      s << o.view << ": output mean " << o.mean << " p99 " << o.p99 << " vs resize mean " << r.mean << " p99 " << r.p99
        << " (margins " << kMeanMargin << ", " << kP99Margin << ")";
      v.failures.push_back(s.str());
    }
  }
  v.json["pass"] = v.pass;
  return v;
}

void edit_image(const fs::path& glb, const fs::path& out_glb, int image, const std::function<void(Image&)>& edit) {
  io::GltfFile f = io::load_gltf(glb.string());
  auto& bytes = f.image_bytes.at(size_t(image));
  Image img = io::decode_image(bytes, "image " + std::to_string(image));
  edit(img);
  const std::string format = io::sniff_image_format(bytes.data(), bytes.size()) == "jpeg" ? "jpeg" : "png";
  bytes = io::encode_image(img, format);
  io::save_gltf(f, out_glb.string());
}

}  // namespace uvpress::test::client
