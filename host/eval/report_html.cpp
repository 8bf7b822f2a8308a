// The offline HTML report of `uvpress eval` (see eval.h): index.html, plot.svg (gnuplot),
// contact sheets and UV plots as PNG. No scripts, no external resources.
#include "core/error.h"
#include "eval.h"
#include "io/atomic_file.h"
#include "io/image_io.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace uvpress::eval {

namespace fs = std::filesystem;

namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string fmt(double v, const char* f = "%.4g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// A file-name-safe version of a layout name.
std::string slug(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "layout" : out;
}

std::string find_gnuplot() {
  for (const char* p : {"/usr/bin/gnuplot", "/usr/local/bin/gnuplot"})
    if (fs::exists(p)) return p;
  return "";
}

// log q_r against c_r for every layout, by gnuplot's svg terminal. "" when gnuplot is
// missing or fails.
std::string plot_svg(const EvalResult& report, std::string* why) {
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty()) {
    *why = "gnuplot is not installed (apt-get install gnuplot-nox)";
    return "";
  }
  char tmpl[] = "/tmp/uvpress-plot-XXXXXX";
  if (!mkdtemp(tmpl)) {
    *why = "no temporary folder";
    return "";
  }
  const fs::path tmp = tmpl;
  const bool bytes = report.cost_axis == CostAxis::Bytes;
  std::ostringstream script;
  script << "set terminal svg size 760,480 dynamic enhanced font 'sans,12' background rgb 'white'\n"
         << "set output '" << (tmp / "plot.svg").string() << "'\n"
         << "set title 'Perceptual loss against relative " << (bytes ? "bytes" : "pixel cost") << " (" << report.views
         << " views, " << report.resolution.resolution << "^2 px)'\n"
         << (bytes ? "set xlabel 'bytes relative to the input image'\n" : "set xlabel 'relative cost c_r'\n")
         << "set ylabel 'q_r (mean GMSD, log scale)'\n"
         << "set logscale y\nset grid\nset key top right\nset format y '10^{%L}'\n";
  std::string plot = "plot ";
  size_t k = 0;
  for (const auto& L : report.layouts) {
    const std::string data = (tmp / ("l" + std::to_string(k) + ".dat")).string();
    std::ofstream f(data);
    // Along bytes the line joins the points the savings read (the cheapest, by bytes:
    // LayoutResult::cost_q); the others are hollow.
    for (const auto& [c, q] : L.cost_q(report.cost_axis))
      if (q > 0) f << c << " " << q << "\n";
    std::string name = L.name;
    for (char& c : name)
      if (c == '\'' || c == '_') c = ' ';
    const std::string lt = " lt " + std::to_string(k + 1);
    plot += (k ? ", " : "") + std::string("'") + data + "' using 1:2 with linespoints" + lt + " lw 2 pt 7 title '" + name + "'";
    if (bytes) {
      const std::string all = (tmp / ("a" + std::to_string(k) + ".dat")).string();
      std::ofstream fa(all);
      for (const auto& p : L.curve)
        if (p.q > 0) fa << p.bytes_ratio << " " << p.q << "\n";
      plot += ", '" + all + "' using 1:2 with points" + lt + " pt 6 notitle";
    }
    // The file as written (its own texture at its real size): one large square in the
    // layout's colour, so a reader sees where the asset a user gets sits on its own curve.
    if (L.as_written && L.as_written->q > 0) {
      const std::string point = (tmp / ("w" + std::to_string(k) + ".dat")).string();
      std::ofstream w(point);
      w << (bytes ? L.as_written->bytes_ratio : L.as_written->c_r) << " " << L.as_written->q << "\n";
      plot += ", '" + point + "' using 1:2 with points" + lt + " pt 5 ps 2 title '" + name + " as written'";
    }
    ++k;
  }
  script << plot << "\n";
  {
    std::ofstream f(tmp / "plot.gp");
    f << script.str();
  }
  const std::string cmd = gnuplot + " '" + (tmp / "plot.gp").string() + "' 2>'" + (tmp / "err.txt").string() + "'";
  const int rc = std::system(cmd.c_str());
  std::string svg;
  if (rc == 0 && fs::exists(tmp / "plot.svg")) {
    std::ifstream f(tmp / "plot.svg");
    std::stringstream ss;
    ss << f.rdbuf();
    svg = ss.str();
  } else {
    *why = "gnuplot failed";
  }
  std::error_code ec;
  fs::remove_all(tmp, ec);
  return svg;
}

std::vector<uint8_t> png(const Image& img) {
  Image out = img;
  out.bits = 8;
  return io::encode_image(out, "png");
}

}  // namespace

void write_html_report(const EvalResult& report, const EvalArtifacts& art, const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw InputError(dir, "cannot create the report folder");
  io::AtomicWriter writer;
  std::string why;
  const std::string svg = plot_svg(report, &why);
  if (!svg.empty()) writer.add((fs::path(dir) / "plot.svg").string(), svg);

  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>uvpress eval: "
    << escape(fs::path(report.asset).filename().string()) << "</title>\n"
    << "<style>body{font-family:sans-serif;margin:2em;max-width:1400px;color:#222}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}"
       "th{background:#f3f3f3}td.l,th.l{text-align:left}.headline{font-size:1.3em;background:#eef6ee;padding:.6em 1em;"
       "border-left:5px solid #3a3}figure{display:inline-block;margin:.5em;vertical-align:top}"
       "figcaption{font-size:.9em;color:#555}img{max-width:100%;border:1px solid #ddd}</style>\n</head><body>\n";
  h << "<h1>uvpress eval</h1>\n<p>Asset <code>" << escape(report.asset) << "</code>, "
    << report.triangles << " textured triangles; " << report.views
    << " views from the vertices of a regular dodecahedron, " << report.resolution.resolution << "&times;"
    << report.resolution.resolution << " pixels"
    << (report.resolution.cropped ? " cropped to the asset (" + std::to_string(std::lround(report.resolution.view_pixels)) +
                                        " pixels a view on average)"
                                  : std::string())
    << ", " << escape(to_string(report.filter))
    << "; device " << escape(report.device.backend) << " ("
    << escape(report.device.name) << "). Quality q = mean GMSD against the input layout with its "
    << "full texture (lower is better); cost c<sub>r</sub> = image texels (W&times;H, what a user pays for) relative to the "
    << "input's image; the paper's c<sub>r</sub> (texels under the charts, eq. 20&ndash;21) is in each cell's tooltip. "
    << "The input layout's texture is resized as users' tools do (" << escape(report.input_resize.empty() ? std::string("?") : report.input_resize)
    << ", the stronger of Lanczos-3 in sRGB values and in linear light); other layouts are re-baked and area-filtered. "
    << "&ldquo;As written&rdquo;: a file's own texture at its real size. Shading: "
    << (report.lit
            ? std::string("lit (q from views lit by a fixed rig through the normal, occlusion, metallic-roughness and "
                          "emissive maps; each point's unlit q in its tooltip)")
            : std::string("unlit (q from the base colour's luminance)"))
    << (!report.shading_warning.empty() ? " &mdash; " + escape(report.shading_warning) : "")
    << "; the contact sheets show the base colour.</p>\n";

  const bool bytes = report.cost_axis == CostAxis::Bytes;
  if (bytes)
    h << "<p>Cost axis: <b>bytes</b> &mdash; every texture encoded as the input's image is (" << escape(report.reference.encoding)
      << "), relative to that image's " << report.reference.image_bytes << " bytes; each cell's tooltip has its bytes.</p>\n";
  h << "<h2>" << (bytes ? "Byte" : "Pixel") << " savings at equal quality</h2>\n";
  bool any = false;
  for (const auto& row : report.savings) {
    const Savings& s = row.savings;
    if (!s.points) continue;
    const double r = s.ratio;
    h << "<p class=\"headline\"><b>" << escape(row.layout) << "</b> reaches the quality of <b>"
      << escape(row.vs) << "</b> with <b>" << fmt(100 * r, "%.1f") << "%</b> of its " << (bytes ? "bytes" : "pixels") << " ("
      << (r <= 1 ? fmt(100 * (1 - r), "%.1f") + "% fewer" : fmt(100 * (r - 1), "%.1f") + "% more")
      << "), over q &isin; [" << fmt(s.q_lo) << ", " << fmt(s.q_hi)
      << "], " << s.points << " levels.</p>\n";
    any = true;
  }
  if (!any)
    h << "<p>No pair of layouts reaches a common q on this grid (or only one layout)"
      << (bytes ? "; along bytes a curve keeps only its cheapest points, and where the input at full size is its "
                  "cheapest (q 0), no downscale of it is left to compare with"
                : "")
      << ".</p>\n";

  h << "<h2>log q<sub>r</sub> against " << (bytes ? "bytes" : "c<sub>r</sub>") << "</h2>\n";
  if (!svg.empty())
    h << "<img src=\"plot.svg\" alt=\"q_r against " << (bytes ? "bytes" : "c_r") << "\" width=\"760\" height=\"480\">\n";
  else h << "<p><i>Plot unavailable: " << escape(why) << ".</i></p>\n";

  h << "<table><tr><th class=\"l\">layout</th><th class=\"l\">texture</th>";
  for (double c : report.cost_grid) h << "<th>c<sub>r</sub>=" << fmt(c, "%.2f") << "</th>";
  h << "<th>as written</th></tr>\n";
  for (const auto& L : report.layouts) {
    h << "<tr><td class=\"l\">" << escape(L.name) << "</td><td class=\"l\">" << escape(L.texture) << " "
      << L.full_size[0] << "&times;" << L.full_size[1] << "</td>";
    for (const auto& p : L.curve)
      h << "<td title=\"" << p.width << "x" << p.height << ", c_r " << fmt(p.c_r_actual) << ", chart c_r "
        << fmt(p.c_r_chart) << (p.bytes ? ", " + std::to_string(*p.bytes) + " bytes" : std::string())
        << (report.lit ? ", unlit q " + fmt(p.q_unlit) : std::string()) << "\">" << fmt(p.q)
        << "</td>";
    if (L.as_written)
      h << "<td>q " << fmt(L.as_written->q) << " at c<sub>r</sub> " << fmt(L.as_written->c_r, "%.3f")
        << (L.as_written->bytes ? ", " + fmt(L.as_written->bytes_ratio, "%.3f") + " of the bytes" : std::string()) << "</td>";
    else
      h << "<td></td>";
    h << "</tr>\n";
  }
  h << "</table>\n";

  std::vector<std::pair<std::string, std::vector<uint8_t>>> images;
  if (!art.layouts.empty() || !art.reference_contact.pixels.empty()) {
    h << "<h2>The " << report.views << " views at c<sub>r</sub> = " << fmt(report.contact_c_r) << "</h2>\n";
    if (!art.reference_contact.pixels.empty()) {
      images.push_back({"contact-reference.png", png(art.reference_contact)});
      h << "<figure><img src=\"contact-reference.png\" alt=\"reference views\"><figcaption>reference: input layout, "
           "full texture</figcaption></figure>\n";
    }
    for (const auto& a : art.layouts) {
      const std::string f = "contact-" + slug(a.name) + ".png";
      images.push_back({f, png(a.contact)});
      h << "<figure><img src=\"" << f << "\" alt=\"" << escape(a.name) << " views\"><figcaption>" << escape(a.name)
        << "</figcaption></figure>\n";
    }
    h << "<h2>Layouts in UV space</h2>\n<p>Each triangle coloured by its texel density relative to the layout's mean "
         "(log<sub>2</sub> of texels per unit length, &minus;2 blue &hellip; 0 white &hellip; +2 red). The spread is the "
         "area-weighted RMS of that log; an isometric layout has 0.</p>\n";
    for (const auto& a : art.layouts) {
      const std::string f = "uv-" + slug(a.name) + ".png";
      images.push_back({f, png(a.uv_plot)});
      const LayoutResult* L = report.layout(a.name);
      const double spread = L ? L->texel_density_spread_log2 : 0.0;
      h << "<figure><img src=\"" << f << "\" alt=\"" << escape(a.name) << " UV layout\" style=\"max-width:420px\">"
        << "<figcaption>" << escape(a.name) << ": spread " << fmt(spread, "%.3f") << "</figcaption></figure>\n";
    }
  }
  h << "<p style=\"color:#777\">seconds: textures " << fmt(report.seconds.textures, "%.2f") << ", render "
    << fmt(report.seconds.render, "%.2f") << ", GMSD " << fmt(report.seconds.gmsd, "%.2f") << ", total "
    << fmt(report.seconds.total, "%.2f") << ".</p>\n</body></html>\n";
  for (const auto& [name, bytes] : images) writer.add((fs::path(dir) / name).string(), bytes);
  writer.add((fs::path(dir) / "index.html").string(), h.str());
  writer.commit();
}

}  // namespace uvpress::eval
