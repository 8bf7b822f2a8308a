#include "io/mesh_io.h"

#include "core/error.h"
#include "io/atomic_file.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace uvpress::io {

namespace {

struct Lines {
  std::string text;
  size_t pos = 0, number = 0;
  bool next(std::string_view& line) {
    if (pos >= text.size()) return false;
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    line = std::string_view(text).substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end + 1, ++number;
    return true;
  }
};

std::string load_text(const std::string& path) {
  auto bytes = read_file(path);
  return std::string(bytes.begin(), bytes.end());
}

// Splits on blanks.
std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

double to_double(std::string_view t, const std::string& path, size_t line) {
  // strtod accepts what from_chars does not (leading '+'), and OBJ writers emit it.
  std::string s(t);
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0')
    throw InputError(path, "line " + std::to_string(line) + ": '" + s + "' is not a number");
  if (!std::isfinite(v)) throw InputError(path, "line " + std::to_string(line) + ": non-finite coordinate");
  return v;
}

long to_long(std::string_view t, const std::string& path, size_t line) {
  long v = 0;
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || p != t.data() + t.size())
    throw InputError(path, "line " + std::to_string(line) + ": '" + std::string(t) + "' is not an integer");
  return v;
}

// OBJ indices are 1-based, negative ones count back from the end.
uint32_t obj_index(long i, size_t count, const std::string& path, size_t line) {
  long r = i > 0 ? i - 1 : long(count) + i;
  if (i == 0 || r < 0 || size_t(r) >= count)
    throw InputError(path, "line " + std::to_string(line) + ": index " + std::to_string(i) + " out of range");
  return uint32_t(r);
}

}  // namespace

Mesh read_obj(const std::string& path, ObjExtras* extras) {
  Lines in{load_text(path)};
  Mesh m;
  ObjExtras x;
  std::string_view line;
  bool any_without_uv = false, any_without_normal = false;
  while (in.next(line)) {
    auto t = tokens(line);
    if (t.empty() || t[0][0] == '#') continue;
    if (t[0] == "v") {
      if (t.size() < 4) throw InputError(path, "line " + std::to_string(in.number) + ": vertex needs 3 coordinates");
      for (int k = 1; k <= 3; ++k) m.positions.push_back(to_double(t[size_t(k)], path, in.number));
    } else if (t[0] == "vt") {
      if (t.size() < 3) throw InputError(path, "line " + std::to_string(in.number) + ": vt needs 2 coordinates");
      m.uvs.push_back(to_double(t[1], path, in.number));
      m.uvs.push_back(to_double(t[2], path, in.number));
    } else if (t[0] == "vn") {
      if (t.size() < 4) throw InputError(path, "line " + std::to_string(in.number) + ": vn needs 3 coordinates");
      for (int k = 1; k <= 3; ++k) x.normals.push_back(to_double(t[size_t(k)], path, in.number));
    } else if (t[0] == "f") {
      if (t.size() < 4) throw InputError(path, "line " + std::to_string(in.number) + ": face needs 3 vertices");
      std::vector<uint32_t> v, vt, vn;
      for (size_t k = 1; k < t.size(); ++k) {
        std::string_view c = t[k];
        size_t s1 = c.find('/');
        v.push_back(obj_index(to_long(c.substr(0, s1), path, in.number), m.vertex_count(), path, in.number));
        if (s1 != std::string_view::npos) {
          std::string_view rest = c.substr(s1 + 1);
          size_t s2 = rest.find('/');
          std::string_view uv = rest.substr(0, s2);
          if (!uv.empty()) vt.push_back(obj_index(to_long(uv, path, in.number), m.uv_count(), path, in.number));
          if (s2 != std::string_view::npos && s2 + 1 < rest.size())
            vn.push_back(obj_index(to_long(rest.substr(s2 + 1), path, in.number), x.normals.size() / 3, path, in.number));
        }
      }
      if (!vt.empty() && vt.size() != v.size())
        throw InputError(path, "line " + std::to_string(in.number) + ": face mixes corners with and without vt");
      if (!vn.empty() && vn.size() != v.size())
        throw InputError(path, "line " + std::to_string(in.number) + ": face mixes corners with and without vn");
      if (vt.empty()) any_without_uv = true;
      if (vn.empty()) any_without_normal = true;
      for (size_t k = 1; k + 1 < v.size(); ++k) {
        m.triangles.insert(m.triangles.end(), {v[0], v[k], v[k + 1]});
        if (!vt.empty()) m.uv_triangles.insert(m.uv_triangles.end(), {vt[0], vt[k], vt[k + 1]});
        if (!vn.empty()) x.normal_triangles.insert(x.normal_triangles.end(), {vn[0], vn[k], vn[k + 1]});
      }
    } else if (t[0] == "mtllib" || t[0] == "usemtl") {
      // The rest of the line, as written (names may hold spaces).
      std::string_view rest = line.substr(line.find(t[0]) + t[0].size());
      while (!rest.empty() && (rest.front() == ' ' || rest.front() == '\t')) rest.remove_prefix(1);
      while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\t' || rest.back() == '\r')) rest.remove_suffix(1);
      if (t[0] == "mtllib") x.mtllib.emplace_back(rest);
      else x.usemtl.emplace_back(m.triangle_count(), std::string(rest));
    } else if (t[0] == "o" || t[0] == "g" || t[0] == "s") {
      ++x.dropped;
    }
  }
  if (m.triangles.empty()) throw InputError(path, "no faces");
  if (any_without_uv) m.uv_triangles.clear();  // UVs only when every face has them
  if (m.uv_triangles.empty()) m.uvs.clear();
  if (any_without_normal) x.normal_triangles.clear();  // normals likewise
  if (x.normal_triangles.empty()) x.normals.clear();
  if (extras) *extras = std::move(x);
  return m;
}

Mesh read_off(const std::string& path) {
  Lines in{load_text(path)};
  std::vector<std::string_view> values;
  std::string_view line;
  bool header = false;
  while (in.next(line)) {
    size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    auto t = tokens(line);
    size_t k = 0;
    if (!header && !t.empty()) {
      if (t[0] != "OFF") throw InputError(path, "not an OFF file (first keyword is not OFF)");
      header = true, k = 1;
    }
    for (; k < t.size(); ++k) values.push_back(t[k]);
  }
  if (!header) throw InputError(path, "empty file");
  size_t at = 0;
  auto next_long = [&]() {
    if (at >= values.size()) throw InputError(path, "file ends early");
    return to_long(values[at++], path, 0);
  };
  long nv = next_long(), nf = next_long();
  next_long();  // edge count, unused
  if (nv <= 0 || nf <= 0 || size_t(nv) * 3 > values.size() || size_t(nf) * 4 > values.size())
    throw InputError(path, "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                               " faces, more than the file holds");
  Mesh m;
  m.positions.reserve(size_t(nv) * 3);
  for (long i = 0; i < 3 * nv; ++i) {
    if (at >= values.size()) throw InputError(path, "file ends early");
    m.positions.push_back(to_double(values[at++], path, 0));
  }
  for (long f = 0; f < nf; ++f) {
    long n = next_long();
    if (n < 3) throw InputError(path, "face " + std::to_string(f) + " has fewer than 3 vertices");
    std::vector<uint32_t> v;
    for (long k = 0; k < n; ++k) {
      long i = next_long();
      if (i < 0 || i >= nv) throw InputError(path, "face " + std::to_string(f) + ": vertex index out of range");
      v.push_back(uint32_t(i));
    }
    for (size_t k = 1; k + 1 < v.size(); ++k) m.triangles.insert(m.triangles.end(), {v[0], v[k], v[k + 1]});
  }
  return m;
}

Mesh read_mesh(const std::string& path, ObjExtras* extras) {
  std::string ext = extension_of(path);
  if (extras) *extras = {};
  if (ext == ".obj") return read_obj(path, extras);
  if (ext == ".off") return read_off(path);
  read_file(path);  // a missing file says so before the extension does
  throw InputError(path, "unsupported mesh format '" + ext + "' (expected .obj or .off)");
}

void write_obj(const Mesh& m, const std::string& path, const ObjExtras* extras) {
  AtomicWriter writer;
  write_obj(m, path, extras, writer);
  writer.commit();
}

void write_obj(const Mesh& m, const std::string& path, const ObjExtras* extras, AtomicWriter& writer) {
  std::string out = "# written by uvpress\n";
  char buf[128];
  const bool normals = extras && extras->normal_triangles.size() == m.triangles.size() && !m.triangles.empty();
  if (extras)
    for (const std::string& lib : extras->mtllib) out += "mtllib " + lib + "\n";
  for (size_t i = 0; i < m.vertex_count(); ++i) {
    std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", m.positions[3 * i], m.positions[3 * i + 1],
                  m.positions[3 * i + 2]);
    out += buf;
  }
  for (size_t i = 0; i < m.uv_count(); ++i) {
    std::snprintf(buf, sizeof buf, "vt %.9g %.9g\n", m.uvs[2 * i], m.uvs[2 * i + 1]);
    out += buf;
  }
  if (normals)
    for (size_t i = 0; i < extras->normals.size() / 3; ++i) {
      std::snprintf(buf, sizeof buf, "vn %.9g %.9g %.9g\n", extras->normals[3 * i], extras->normals[3 * i + 1],
                    extras->normals[3 * i + 2]);
      out += buf;
    }
  size_t next_material = 0;
  for (size_t f = 0; f < m.triangle_count(); ++f) {
    while (extras && next_material < extras->usemtl.size() && extras->usemtl[next_material].first <= f)
      out += "usemtl " + extras->usemtl[next_material++].second + "\n";
    const uint32_t* v = &m.triangles[3 * f];
    if (normals) {
      const uint32_t* n = &extras->normal_triangles[3 * f];
      if (m.has_uvs()) {
        const uint32_t* t = &m.uv_triangles[3 * f];
        std::snprintf(buf, sizeof buf, "f %u/%u/%u %u/%u/%u %u/%u/%u\n", v[0] + 1, t[0] + 1, n[0] + 1, v[1] + 1, t[1] + 1,
                      n[1] + 1, v[2] + 1, t[2] + 1, n[2] + 1);
      } else {
        std::snprintf(buf, sizeof buf, "f %u//%u %u//%u %u//%u\n", v[0] + 1, n[0] + 1, v[1] + 1, n[1] + 1, v[2] + 1, n[2] + 1);
      }
    } else if (m.has_uvs()) {
      const uint32_t* t = &m.uv_triangles[3 * f];
      std::snprintf(buf, sizeof buf, "f %u/%u %u/%u %u/%u\n", v[0] + 1, t[0] + 1, v[1] + 1, t[1] + 1, v[2] + 1,
                    t[2] + 1);
    } else {
      std::snprintf(buf, sizeof buf, "f %u %u %u\n", v[0] + 1, v[1] + 1, v[2] + 1);
    }
    out += buf;
  }
  writer.add(path, out);
}

}  // namespace uvpress::io
