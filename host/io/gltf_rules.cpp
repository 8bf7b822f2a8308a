// The glTF rules checked on load (gltf_rules.h). Why and what:
//
// uvpress reads an asset's meshes (positions, indices, UVs, normals, tangents) and carries
// everything else through unchanged, so an input's own errors reach the output. The full
// validator is a Node program (tools/validate-gltf.mjs); a user's run cannot depend on it,
// so this is a port of the subset that concerns buffers, accessors and mesh data, with the
// validator's codes and its way of counting (one issue per reference where it counts per
// reference), so that a count here is the count the validator prints for the same codes:
//
//   buffers      BUFFER_VIEW_TOO_LONG                      per bufferView
//   accessors    ACCESSOR_OFFSET_ALIGNMENT, ACCESSOR_TOTAL_OFFSET_ALIGNMENT,
//                ACCESSOR_TOO_LONG                         per accessor
//   byteStride   ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE per sampler input/output,
//                SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE          per skin,
//                MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE per primitive,
//                MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE per further attribute accessor
//                                                           sharing a view without a stride
//   primitives   MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT      per primitive,
//                ACCESSOR_INDEX_OOB, ACCESSOR_INDEX_PRIMITIVE_RESTART
//                                                           per index value and primitive
//   values       ACCESSOR_INVALID_FLOAT                     per non-finite component,
//                ACCESSOR_MIN_MISMATCH, ACCESSOR_MAX_MISMATCH,
//                ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND, ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND
//                                                           per component of an accessor's min/max,
//                ACCESSOR_VECTOR3_NON_UNIT (NORMAL, TANGENT xyz; | |v| - 1 | > 0.00674),
//                ACCESSOR_INVALID_SIGN (TANGENT w not +-1)  per element and primitive
//
// Values are compared as the validator does: float components in single precision
// (declared bounds rounded to float), integer ones as stored (normalized or not), a NaN
// making its component's actual bounds NaN. Value checks skip sparse accessors, matrices
// of 1- or 2-byte components (column padding) and accessors that do not fit their view
// (that is reported once, as ACCESSOR_TOO_LONG).
#include "io/gltf_rules.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace uvpress::io {

namespace {

size_t component_size(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

int components(int type) {
  const int n = tinygltf::GetNumComponentsInType(uint32_t(type));
  return n > 0 ? n : 0;
}

// Bytes one element takes, matrix columns padded to 4 bytes as the spec lays them out.
size_t element_length(const tinygltf::Accessor& a) {
  const size_t size = component_size(a.componentType);
  if (size < 4 && (a.type == TINYGLTF_TYPE_MAT2 || a.type == TINYGLTF_TYPE_MAT3)) {
    const size_t rows = a.type == TINYGLTF_TYPE_MAT2 ? 2 : 3;
    return rows * ((rows * size + 3) / 4 * 4);
  }
  return size * size_t(components(a.type));
}

bool has_padding(const tinygltf::Accessor& a) {
  return component_size(a.componentType) < 4 && (a.type == TINYGLTF_TYPE_MAT2 || a.type == TINYGLTF_TYPE_MAT3);
}

class Checker {
 public:
  explicit Checker(const tinygltf::Model& m) : m_(m) {}

  std::vector<RuleIssue> run() {
    buffer_views();
    accessors();
    animations_and_skins();
    meshes();
    return std::move(issues_);
  }

 private:
  void add(const char* code, const std::string& pointer, const std::string& message) {
    issues_.push_back({code, pointer, message});
  }

  bool view_fits(int v) const {
    if (v < 0 || size_t(v) >= m_.bufferViews.size()) return false;
    const auto& view = m_.bufferViews[size_t(v)];
    if (view.buffer < 0 || size_t(view.buffer) >= m_.buffers.size()) return false;
    const size_t size = m_.buffers[size_t(view.buffer)].data.size();
    return view.byteOffset <= size && view.byteLength <= size - view.byteOffset;
  }

  size_t stride_of(const tinygltf::Accessor& a) const {
    const auto& view = m_.bufferViews[size_t(a.bufferView)];
    return view.byteStride ? view.byteStride : element_length(a);
  }

  // Whether every byte of the accessor's elements lies inside its view (and the view in its
  // buffer): only then are its values read.
  bool accessor_fits(const tinygltf::Accessor& a) const {
    if (!view_fits(a.bufferView) || component_size(a.componentType) == 0 || components(a.type) == 0) return false;
    const auto& view = m_.bufferViews[size_t(a.bufferView)];
    const size_t length = element_length(a), stride = stride_of(a);
    if (a.count == 0) return a.byteOffset <= view.byteLength;
    if (stride < length || a.byteOffset > view.byteLength) return false;
    const size_t room = view.byteLength - a.byteOffset;
    return a.count - 1 <= room / stride && (a.count - 1) * stride + length <= room;
  }

  // Component c of element i as stored (raw integers, not normalized), for readable
  // accessors only.
  double value(const tinygltf::Accessor& a, size_t i, int c) const {
    const auto& view = m_.bufferViews[size_t(a.bufferView)];
    const uint8_t* p = m_.buffers[size_t(view.buffer)].data.data() + view.byteOffset + a.byteOffset +
                       i * stride_of(a) + size_t(c) * component_size(a.componentType);
    switch (a.componentType) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: return double(int8_t(*p));
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return double(*p);
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t s;
        std::memcpy(&s, p, 2);
        return double(s);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t s;
        std::memcpy(&s, p, 2);
        return double(s);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t s;
        std::memcpy(&s, p, 4);
        return double(s);
      }
      default: {
        float f;
        std::memcpy(&f, p, 4);
        return double(f);
      }
    }
  }

  bool readable(int index) const {
    if (index < 0 || size_t(index) >= m_.accessors.size()) return false;
    const auto& a = m_.accessors[size_t(index)];
    return !a.sparse.isSparse && !has_padding(a) && accessor_fits(a);
  }

  void buffer_views() {
    for (size_t v = 0; v < m_.bufferViews.size(); ++v) {
      const auto& view = m_.bufferViews[v];
      if (view.buffer < 0 || size_t(view.buffer) >= m_.buffers.size()) continue;
      if (!view_fits(int(v)))
        add("BUFFER_VIEW_TOO_LONG", "/bufferViews/" + std::to_string(v),
            "bufferView does not fit buffer " + std::to_string(view.buffer));
    }
  }

  void accessors() {
    for (size_t i = 0; i < m_.accessors.size(); ++i) {
      const auto& a = m_.accessors[i];
      const std::string ptr = "/accessors/" + std::to_string(i);
      const size_t size = component_size(a.componentType);
      if (size == 0 || components(a.type) == 0 || a.bufferView < 0 || size_t(a.bufferView) >= m_.bufferViews.size())
        continue;
      const auto& view = m_.bufferViews[size_t(a.bufferView)];
      if (a.byteOffset % size) add("ACCESSOR_OFFSET_ALIGNMENT", ptr + "/byteOffset", "offset is not a multiple of the component size");
      if ((view.byteOffset + a.byteOffset) % size)
        add("ACCESSOR_TOTAL_OFFSET_ALIGNMENT", ptr + "/byteOffset", "total offset is not a multiple of the component size");
      if (view_fits(a.bufferView) && !accessor_fits(a) && stride_of(a) >= element_length(a))
        add("ACCESSOR_TOO_LONG", ptr, "accessor does not fit bufferView " + std::to_string(a.bufferView));
      if (readable(int(i))) values(a, ptr);
    }
  }

  // Non-finite floats, and the declared min/max against the values (per component).
  void values(const tinygltf::Accessor& a, const std::string& ptr) {
    const int n = components(a.type);
    const bool is_float = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    if (is_float)
      for (size_t i = 0; i < a.count; ++i)
        for (int c = 0; c < n; ++c)
          if (!std::isfinite(value(a, i, c)))
            add("ACCESSOR_INVALID_FLOAT", ptr, "element " + std::to_string(i * size_t(n) + size_t(c)) + " is not finite");
    const bool has_min = a.minValues.size() == size_t(n), has_max = a.maxValues.size() == size_t(n);
    if ((!has_min && !has_max) || a.count == 0) return;
    // The declared bound as the values are stored: floats rounded to single precision.
    auto as_stored = [&](double d) { return is_float ? double(float(d)) : d; };
    for (int c = 0; c < n; ++c) {
      double lo = value(a, 0, c), hi = lo;
      size_t below = 0, above = 0;
      const double dmin = has_min ? as_stored(a.minValues[size_t(c)]) : 0, dmax = has_max ? as_stored(a.maxValues[size_t(c)]) : 0;
      for (size_t i = 0; i < a.count; ++i) {
        const double v = value(a, i, c);
        // NaN wins, as in the validator (Dart's min and max): the bound no longer matches.
        lo = std::isnan(lo) || std::isnan(v) ? std::numeric_limits<double>::quiet_NaN() : std::min(lo, v);
        hi = std::isnan(hi) || std::isnan(v) ? std::numeric_limits<double>::quiet_NaN() : std::max(hi, v);
        below += has_min && v < dmin, above += has_max && v > dmax;
      }
      const std::string comp = " of component " + std::to_string(c);
      if (has_min && !(lo == dmin)) add("ACCESSOR_MIN_MISMATCH", ptr + "/min", "declared minimum" + comp + " is not the actual one");
      if (has_max && !(hi == dmax)) add("ACCESSOR_MAX_MISMATCH", ptr + "/max", "declared maximum" + comp + " is not the actual one");
      if (below) add("ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND", ptr + "/min", std::to_string(below) + " elements below the declared minimum" + comp);
      if (above) add("ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND", ptr + "/max", std::to_string(above) + " elements above the declared maximum" + comp);
    }
  }

  bool strided(int accessor) const {
    if (accessor < 0 || size_t(accessor) >= m_.accessors.size()) return false;
    const int v = m_.accessors[size_t(accessor)].bufferView;
    return v >= 0 && size_t(v) < m_.bufferViews.size() && m_.bufferViews[size_t(v)].byteStride != 0;
  }

  void animations_and_skins() {
    for (size_t a = 0; a < m_.animations.size(); ++a)
      for (size_t s = 0; s < m_.animations[a].samplers.size(); ++s) {
        const auto& sampler = m_.animations[a].samplers[s];
        const std::string ptr = "/animations/" + std::to_string(a) + "/samplers/" + std::to_string(s);
        if (strided(sampler.input)) add("ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE", ptr + "/input", "input accessor's bufferView has a byteStride");
        if (strided(sampler.output)) add("ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE", ptr + "/output", "output accessor's bufferView has a byteStride");
      }
    for (size_t s = 0; s < m_.skins.size(); ++s)
      if (strided(m_.skins[s].inverseBindMatrices))
        add("SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE", "/skins/" + std::to_string(s) + "/inverseBindMatrices",
            "inverse bind matrices' bufferView has a byteStride");
  }

  void meshes() {
    std::vector<int> first_accessor_of_view(m_.bufferViews.size(), -1);
    for (size_t mi = 0; mi < m_.meshes.size(); ++mi)
      for (size_t pi = 0; pi < m_.meshes[mi].primitives.size(); ++pi) {
        const auto& prim = m_.meshes[mi].primitives[pi];
        const std::string ptr = "/meshes/" + std::to_string(mi) + "/primitives/" + std::to_string(pi);
        size_t vertices = std::numeric_limits<size_t>::max();
        std::set<size_t> counts;
        for (const auto& [name, index] : prim.attributes) {
          if (index < 0 || size_t(index) >= m_.accessors.size()) continue;
          const auto& a = m_.accessors[size_t(index)];
          counts.insert(a.count);
          // Indices are checked against POSITION's count, as the validator does (else the fewest).
          if (name == "POSITION") vertices = a.count;
          else if (!prim.attributes.count("POSITION")) vertices = std::min(vertices, a.count);
          // Two accessors interleaved in one view need its byteStride to say how.
          if (a.bufferView >= 0 && size_t(a.bufferView) < m_.bufferViews.size() && !m_.bufferViews[size_t(a.bufferView)].byteStride) {
            int& first = first_accessor_of_view[size_t(a.bufferView)];
            if (first < 0) first = index;
            else if (first != index)
              add("MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE", ptr + "/attributes/" + name,
                  "bufferView " + std::to_string(a.bufferView) + " holds several accessors but has no byteStride");
          }
          if (name == "NORMAL" || name == "TANGENT") unit_vectors(index, name == "TANGENT", ptr + "/attributes/" + name);
        }
        if (counts.size() > 1) add("MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT", ptr + "/attributes", "attributes differ in count");
        if (prim.indices >= 0) {
          if (strided(prim.indices))
            add("MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE", ptr + "/indices", "indices' bufferView has a byteStride");
          if (!counts.empty()) indices(prim.indices, vertices, ptr + "/indices");
        }
      }
  }

  void indices(int index, size_t vertices, const std::string& ptr) {
    if (!readable(index)) return;
    const auto& a = m_.accessors[size_t(index)];
    const size_t size = component_size(a.componentType);
    if (a.type != TINYGLTF_TYPE_SCALAR || a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
        a.componentType == TINYGLTF_COMPONENT_TYPE_BYTE || a.componentType == TINYGLTF_COMPONENT_TYPE_SHORT)
      return;
    const double restart = std::ldexp(1.0, int(8 * size)) - 1;
    for (size_t i = 0; i < a.count; ++i) {
      const double v = value(a, i, 0);
      if (v == restart) add("ACCESSOR_INDEX_PRIMITIVE_RESTART", ptr, "index " + std::to_string(i) + " is the primitive restart value");
      if (v >= double(vertices))
        add("ACCESSOR_INDEX_OOB", ptr, "index " + std::to_string(i) + " is past the last vertex (" + std::to_string(vertices) + " vertices)");
    }
  }

  // NORMAL and TANGENT xyz of unit length, TANGENT w = +-1 (float data only: normalized
  // integers are never exactly unit).
  void unit_vectors(int index, bool tangent, const std::string& ptr) {
    if (!readable(index)) return;
    const auto& a = m_.accessors[size_t(index)];
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || components(a.type) != (tangent ? 4 : 3)) return;
    for (size_t i = 0; i < a.count; ++i) {
      const double x = value(a, i, 0), y = value(a, i, 1), z = value(a, i, 2);
      if (std::abs(std::sqrt(x * x + y * y + z * z) - 1) > 0.00674)
        add("ACCESSOR_VECTOR3_NON_UNIT", ptr, "element " + std::to_string(i) + " is not of unit length");
      if (tangent) {
        const double w = value(a, i, 3);
        if (w != 1 && w != -1) add("ACCESSOR_INVALID_SIGN", ptr, "element " + std::to_string(i) + " has w other than 1 or -1");
      }
    }
  }

  const tinygltf::Model& m_;
  std::vector<RuleIssue> issues_;
};

}  // namespace

std::vector<RuleIssue> check_rules(const GltfFile& file) { return Checker(file.model).run(); }

const std::vector<std::string>& rule_codes() {
  static const std::vector<std::string> codes = {
      "BUFFER_VIEW_TOO_LONG", "ACCESSOR_OFFSET_ALIGNMENT", "ACCESSOR_TOTAL_OFFSET_ALIGNMENT", "ACCESSOR_TOO_LONG",
      "ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE", "SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE",
      "MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE", "MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE",
      "MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT", "ACCESSOR_INDEX_OOB", "ACCESSOR_INDEX_PRIMITIVE_RESTART",
      "ACCESSOR_INVALID_FLOAT", "ACCESSOR_MIN_MISMATCH", "ACCESSOR_MAX_MISMATCH", "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND",
      "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND", "ACCESSOR_VECTOR3_NON_UNIT", "ACCESSOR_INVALID_SIGN"};
  return codes;
}

std::map<std::string, size_t> count_by_code(const std::vector<RuleIssue>& issues) {
  std::map<std::string, size_t> out;
  for (const auto& i : issues) ++out[i.code];
  return out;
}

nlohmann::ordered_json validation_json(const std::vector<RuleIssue>& issues) {
  nlohmann::ordered_json j = {{"errors", issues.size()}, {"codes", nlohmann::ordered_json::object()}};
  for (const auto& [code, n] : count_by_code(issues)) j["codes"][code] = n;
  return j;
}

std::string describe_issues(const std::vector<RuleIssue>& issues, size_t codes) {
  const auto by_code = count_by_code(issues);
  std::vector<std::pair<std::string, size_t>> sorted(by_code.begin(), by_code.end());
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string s = std::to_string(issues.size()) + " glTF validation error" + (issues.size() == 1 ? "" : "s") + " (";
  for (size_t k = 0; k < sorted.size() && k < codes; ++k)
    s += (k ? ", " : "") + std::to_string(sorted[k].second) + " " + sorted[k].first;
  if (sorted.size() > codes) s += ", ...";
  return s + ")";
}

}  // namespace uvpress::io
