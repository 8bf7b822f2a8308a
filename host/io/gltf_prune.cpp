#include "io/gltf_prune.h"

#include "io/image_io.h"

#include <algorithm>
#include <set>
#include <utility>
#include <vector>
#include <type_traits>

namespace uvpress::io {

namespace {

// Extensions whose references to accessors and bufferViews this pass knows (the instancing
// attributes), or that hold none. Any other extension used may point at an accessor or a
// bufferView by index (EXT_meshopt_compression, vendor extensions): then nothing is pruned.
bool known_extension(const std::string& name) {
  if (name.rfind("KHR_materials_", 0) == 0) return true;
  static const std::set<std::string> known = {
      "KHR_texture_transform", "KHR_mesh_quantization", "KHR_lights_punctual", "KHR_texture_basisu",
      "EXT_texture_webp",      "EXT_mesh_gpu_instancing", "KHR_xmp_json_ld", "EXT_lights_image_based"};
  return known.count(name) > 0;
}

// f on an index: by reference when it may edit it, on a copy when the model is const.
template <typename F>
void call(F& f, int& index) { f(index); }
template <typename F>
void call(F& f, const int& index) {
  int copy = index;
  f(copy);
}

// Calls `f(int& accessor)` on every accessor reference of the model (on a copy of each
// index when the model is const).
template <typename M, typename F>
void for_each_accessor_ref(M& m, F&& f) {
  constexpr bool edit = !std::is_const_v<M>;
  for (auto& mesh : m.meshes)
    for (auto& p : mesh.primitives) {
      for (auto& [name, a] : p.attributes) call(f, a);
      if (p.indices >= 0) call(f, p.indices);
      for (auto& target : p.targets)
        for (auto& [name, a] : target) call(f, a);
    }
  for (auto& skin : m.skins)
    if (skin.inverseBindMatrices >= 0) call(f, skin.inverseBindMatrices);
  for (auto& anim : m.animations)
    for (auto& s : anim.samplers) {
      if (s.input >= 0) call(f, s.input);
      if (s.output >= 0) call(f, s.output);
    }
  for (auto& node : m.nodes) {
    auto it = node.extensions.find("EXT_mesh_gpu_instancing");
    if (it == node.extensions.end() || !it->second.IsObject()) continue;
    auto& object = it->second.template Get<tinygltf::Value::Object>();
    auto attributes = object.find("attributes");
    if (attributes == object.end() || !attributes->second.IsObject()) continue;
    for (auto& [name, v] : attributes->second.template Get<tinygltf::Value::Object>()) {
      if (!v.IsInt()) continue;
      int a = v.template Get<int>();
      f(a);
      if constexpr (edit) v = tinygltf::Value(a);
    }
  }
}

// Calls `f(int& view)` on every bufferView reference of the accessors in `keep` and of the images.
template <typename M, typename F>
void for_each_view_ref(M& m, const std::vector<bool>& keep_accessor, F&& f) {
  for (size_t i = 0; i < m.accessors.size(); ++i) {
    if (!keep_accessor[i]) continue;
    auto& a = m.accessors[i];
    if (a.bufferView >= 0) call(f, a.bufferView);
    if (a.sparse.isSparse) {
      call(f, a.sparse.indices.bufferView);
      call(f, a.sparse.values.bufferView);
    }
  }
  for (auto& image : m.images)
    if (image.bufferView >= 0) call(f, image.bufferView);
}

std::vector<bool> referenced_accessors(const tinygltf::Model& m) {
  std::vector<bool> used(m.accessors.size(), false);
  for_each_accessor_ref(m, [&](int& a) {
    if (a >= 0 && size_t(a) < used.size()) used[size_t(a)] = true;
  });
  return used;
}

std::vector<bool> referenced_views(const tinygltf::Model& m, const std::vector<bool>& keep_accessor) {
  std::vector<bool> used(m.bufferViews.size(), false);
  for_each_view_ref(m, keep_accessor, [&](int& v) {
    if (v >= 0 && size_t(v) < used.size()) used[size_t(v)] = true;
  });
  return used;
}

// The bytes of its bufferView that accessor `a` reads, relative to the view: [first,
// second); empty when it has no view or no elements. Matrix columns of 1- and 2-byte
// components are padded to 4 bytes (glTF 2.0, 3.6.2.4).
std::pair<size_t, size_t> accessor_span(const tinygltf::Model& m, const tinygltf::Accessor& a) {
  if (a.bufferView < 0 || size_t(a.bufferView) >= m.bufferViews.size() || a.count == 0) return {0, 0};
  const int component = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
  const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
  if (component <= 0 || components <= 0) return {0, 0};
  size_t element = size_t(component) * size_t(components);
  const int columns = a.type == TINYGLTF_TYPE_MAT2 ? 2 : a.type == TINYGLTF_TYPE_MAT3 ? 3 : a.type == TINYGLTF_TYPE_MAT4 ? 4 : 0;
  if (columns > 0) element = size_t(columns) * ((size_t(columns) * size_t(component) + 3) / 4 * 4);
  const size_t stride = m.bufferViews[size_t(a.bufferView)].byteStride > 0 ? m.bufferViews[size_t(a.bufferView)].byteStride : element;
  return {a.byteOffset, a.byteOffset + stride * (a.count - 1) + element};
}

// Per buffer, the bytes to drop: those only removed views covered, and inside a kept view
// the ranges that only removed accessors read (a replaced TEXCOORD_0 in a view it shares
// with other attributes, as Fox's does with JOINTS_0: 13.8 KB). Only views that nothing but
// accessors use are cut (not an image's, nor a sparse accessor's index or value view), and
// bytes no accessor read in the input stay: not ours to drop. `cut[v]`: view v loses bytes.
std::vector<std::vector<uint8_t>> dropped_bytes(const tinygltf::Model& m, const std::vector<bool>& keep_view,
                                                const std::vector<bool>& keep_accessor, std::vector<bool>& cut) {
  std::vector<std::vector<uint8_t>> drop(m.buffers.size());
  for (size_t b = 0; b < m.buffers.size(); ++b) drop[b].assign(m.buffers[b].data.size(), 0);
  auto view_range = [&](const tinygltf::BufferView& view, std::vector<uint8_t>*& mask) -> std::pair<size_t, size_t> {
    mask = view.buffer >= 0 && size_t(view.buffer) < drop.size() ? &drop[size_t(view.buffer)] : nullptr;
    if (!mask || view.byteOffset > mask->size()) return {0, 0};
    return {view.byteOffset, std::min(mask->size(), view.byteOffset + view.byteLength)};
  };
  for (const bool kept : {false, true})
    for (size_t v = 0; v < m.bufferViews.size(); ++v) {
      if (keep_view[v] != kept) continue;
      std::vector<uint8_t>* mask;
      const auto [a, e] = view_range(m.bufferViews[v], mask);
      if (mask && a < e) std::fill(mask->begin() + long(a), mask->begin() + long(e), uint8_t(kept ? 0 : 1));
    }
  // Views used otherwise than as an accessor's elements are kept whole.
  std::vector<bool> whole(m.bufferViews.size(), false);
  auto mark_whole = [&](int v) {
    if (v >= 0 && size_t(v) < whole.size()) whole[size_t(v)] = true;
  };
  for (const auto& image : m.images) mark_whole(image.bufferView);
  for (const auto& a : m.accessors)
    if (a.sparse.isSparse) mark_whole(a.sparse.indices.bufferView), mark_whole(a.sparse.values.bufferView);
  cut.assign(m.bufferViews.size(), false);
  std::vector<std::vector<std::pair<size_t, size_t>>> removed(m.bufferViews.size()), live(m.bufferViews.size());
  for (size_t i = 0; i < m.accessors.size(); ++i) {
    const int v = m.accessors[i].bufferView;
    if (v < 0 || size_t(v) >= m.bufferViews.size()) continue;
    const auto span = accessor_span(m, m.accessors[i]);
    if (span.first < span.second) (keep_accessor[i] ? live : removed)[size_t(v)].push_back(span);
  }
  for (size_t v = 0; v < m.bufferViews.size(); ++v) {
    if (!keep_view[v] || whole[v] || removed[v].empty() || live[v].empty()) continue;
    std::vector<uint8_t>* mask;
    const auto [a, e] = view_range(m.bufferViews[v], mask);
    if (!mask || a >= e) continue;
    std::vector<uint8_t> state(e - a, 0);  // 1: a removed accessor's, 2: a kept one's
    for (const auto& [f, t] : removed[v])
      for (size_t k = f; k < std::min(t, e - a); ++k) state[k] = std::max<uint8_t>(state[k], 1);
    for (const auto& [f, t] : live[v])
      for (size_t k = f; k < std::min(t, e - a); ++k) state[k] = 2;
    for (size_t k = 0; k < state.size(); ++k)
      if (state[k] == 1) (*mask)[a + k] = 1, cut[v] = true;
  }
  return drop;
}

// Drops the bytes `drop` marks from each buffer; kept bytes move in runs, each run starting
// at its old offset modulo 4 (accessors stay aligned as they were). Views move with their
// bytes; a view that lost bytes inside (cut) shrinks to its kept ones, and its accessors'
// offsets follow them.
size_t compact_buffers(tinygltf::Model& m, const std::vector<bool>& keep_view, const std::vector<bool>& keep_accessor) {
  std::vector<bool> cut;
  const std::vector<std::vector<uint8_t>> drops = dropped_bytes(m, keep_view, keep_accessor, cut);
  size_t removed = 0;
  for (size_t b = 0; b < m.buffers.size(); ++b) {
    auto& data = m.buffers[b].data;
    const std::vector<uint8_t>& drop = drops[b];
    if (std::find(drop.begin(), drop.end(), 1) == drop.end()) continue;
    struct Run {
      size_t from, to, at;  // old [from, to) now at `at`
    };
    std::vector<Run> runs;
    std::vector<uint8_t> out;
    out.reserve(data.size());
    for (size_t i = 0; i < data.size();) {
      if (drop[i]) {
        ++i;
        continue;
      }
      size_t j = i;
      while (j < data.size() && !drop[j]) ++j;
      size_t at = out.size();
      while (at % 4 != i % 4) ++at;
      out.resize(at, 0);
      out.insert(out.end(), data.begin() + long(i), data.begin() + long(j));
      runs.push_back({i, j, at});
      i = j;
    }
    // Where a kept byte went (`end`: also the position just past a run's last byte).
    auto moved = [&](size_t old, bool end) -> size_t {
      for (const Run& r : runs)
        if (old >= r.from && (old < r.to || (end && old == r.to))) return old - r.from + r.at;
      return old;
    };
    for (size_t v = 0; v < m.bufferViews.size(); ++v) {
      auto& view = m.bufferViews[v];
      if (!keep_view[v] || view.buffer != int(b)) continue;
      if (!cut[v]) {
        view.byteOffset = moved(view.byteOffset, true);
        continue;
      }
      // The view's first and last kept bytes (a kept accessor reads some: dropped_bytes).
      const size_t from = view.byteOffset, to = std::min(data.size(), view.byteOffset + view.byteLength);
      size_t first = from, last = to;
      while (first < to && drop[first]) ++first;
      while (last > first && drop[last - 1]) --last;
      const size_t start = moved(first, false), end = moved(last - 1, false) + 1;
      for (size_t i = 0; i < m.accessors.size(); ++i)
        if (keep_accessor[i] && m.accessors[i].bufferView == int(v))
          m.accessors[i].byteOffset = moved(from + m.accessors[i].byteOffset, true) - start;
      view.byteOffset = start;
      view.byteLength = end - start;
    }
    removed += data.size() > out.size() ? data.size() - out.size() : 0;
    data = std::move(out);
  }
  return removed;
}

// Old index -> new index (-1: removed).
std::vector<int> renumbering(const std::vector<bool>& keep) {
  std::vector<int> to(keep.size(), -1);
  int next = 0;
  for (size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) to[i] = next++;
  return to;
}

template <typename T>
void erase_unkept(std::vector<T>& objects, const std::vector<bool>& keep) {
  size_t out = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    if (!keep[i]) continue;
    if (out != i) objects[out] = std::move(objects[i]);  // never onto itself: that empties its vectors
    ++out;
  }
  objects.resize(out);
}

}  // namespace

PruneResult prune_replaced(GltfFile& file, const tinygltf::Model& input) {
  PruneResult result;
  tinygltf::Model& m = file.model;
  for (const std::string& ext : m.extensionsUsed)
    if (!known_extension(ext)) {
      result.skipped = "the file uses " + ext + ", whose references to accessors and bufferViews are not known";
      return result;
    }
  // Images with new bytes leave their bufferView: save_gltf stores the new bytes itself.
  for (size_t i = 0; i < m.images.size() && i < file.image_bytes.size(); ++i) {
    auto& image = m.images[i];
    if (image.bufferView < 0 || size_t(image.bufferView) >= m.bufferViews.size()) continue;
    const auto& view = m.bufferViews[size_t(image.bufferView)];
    if (view.buffer < 0 || size_t(view.buffer) >= m.buffers.size()) continue;
    const auto& data = m.buffers[size_t(view.buffer)].data;
    const auto& bytes = file.image_bytes[i];
    const bool same = view.byteLength == bytes.size() && view.byteOffset + view.byteLength <= data.size() &&
                      std::equal(bytes.begin(), bytes.end(), data.begin() + long(view.byteOffset));
    if (same) continue;
    image.bufferView = -1;
    image.mimeType = mime_of_format(sniff_image_format(bytes.data(), bytes.size()));
  }

  // Unreferenced now, and referenced in the input or new since.
  const std::vector<bool> used_before = referenced_accessors(input);
  const std::vector<bool> used_now = referenced_accessors(m);
  std::vector<bool> keep_accessor(m.accessors.size(), true);
  for (size_t i = 0; i < m.accessors.size(); ++i)
    if (!used_now[i] && (i >= used_before.size() || used_before[i])) keep_accessor[i] = false;
  const std::vector<bool> views_before = referenced_views(input, std::vector<bool>(input.accessors.size(), true));
  const std::vector<bool> views_now = referenced_views(m, keep_accessor);
  std::vector<bool> keep_view(m.bufferViews.size(), true);
  for (size_t v = 0; v < m.bufferViews.size(); ++v)
    if (!views_now[v] && (v >= views_before.size() || views_before[v])) keep_view[v] = false;

  result.accessors = size_t(std::count(keep_accessor.begin(), keep_accessor.end(), false));
  result.buffer_views = size_t(std::count(keep_view.begin(), keep_view.end(), false));
  if (result.accessors == 0 && result.buffer_views == 0) return result;

  result.buffer_bytes = compact_buffers(m, keep_view, keep_accessor);
  const std::vector<int> accessor_to = renumbering(keep_accessor), view_to = renumbering(keep_view);
  for_each_view_ref(m, keep_accessor, [&](int& v) {
    if (v >= 0 && size_t(v) < view_to.size()) v = view_to[size_t(v)];
  });
  for_each_accessor_ref(m, [&](int& a) {
    if (a >= 0 && size_t(a) < accessor_to.size()) a = accessor_to[size_t(a)];
  });
  erase_unkept(m.accessors, keep_accessor);
  erase_unkept(m.bufferViews, keep_view);
  return result;
}

}  // namespace uvpress::io
