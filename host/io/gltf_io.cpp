#include "io/gltf_io.h"

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/ktx2.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace uvpress::io {

namespace fs = std::filesystem;

bool is_supported_required_extension(const std::string& name) {
  // Texture transforms and quantized attributes are read (asset.cpp); the material and
  // lighting extensions change shading only, which uvpress carries through untouched.
  static const std::set<std::string> supported = {
      "KHR_texture_transform", "KHR_mesh_quantization", "KHR_materials_unlit", "KHR_materials_emissive_strength",
      "KHR_materials_ior", "KHR_materials_specular", "KHR_materials_transmission", "KHR_materials_volume",
      "KHR_materials_clearcoat", "KHR_materials_sheen", "KHR_materials_iridescence", "KHR_materials_variants",
      "KHR_lights_punctual"};
  return supported.count(name) > 0;
}

uint64_t image_fingerprint(const std::vector<uint8_t>& bytes) {
  uint64_t h = 1469598103934665603ull;
  for (uint8_t b : bytes) h = (h ^ b) * 1099511628211ull;
  return h;
}

bool is_gltf_output_path(const std::string& path) {
  std::string ext = extension_of(path);
  return ext == ".gltf" || ext == ".glb";
}

namespace {

// tinygltf errors come as several lines; the user gets one.
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  std::replace(s.begin(), s.end(), '\n', ';');
  return s.empty() ? "unreadable glTF" : s;
}

// Keeps each image's encoded bytes instead of decoding them: uvpress decodes on demand
// (io/image_decode.h), and untouched images are written back byte for byte.
bool keep_image_bytes(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void* user) {
  auto& store = *static_cast<std::vector<std::vector<uint8_t>>*>(user);
  if (index < 0) return false;
  // tinygltf 2.7 hands over a bufferView's bytes without checking the view against its
  // buffer (found by fuzzing: a heap over-read). Those are copied after loading, checked.
  if (image && image->bufferView >= 0) return true;
  if (size_t(index) >= store.size()) store.resize(size_t(index) + 1);
  store[size_t(index)].assign(bytes, bytes + std::max(size, 0));
  return true;
}

// Images are written by save_gltf itself; tinygltf only serializes their URI.
bool skip_image_write(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
  return false;
}

// The asset's external files, checked (references.h) and read before tinygltf runs. Its
// file callbacks serve these bytes and nothing else: whatever path tinygltf builds from a
// URI (it also tries the current folder), it cannot reach a file that was not checked.
struct CheckedFiles {
  std::map<std::string, std::vector<uint8_t>> by_path;  // canonical path -> bytes
};

CheckedFiles read_references(const std::string& path, const std::vector<uint8_t>& bytes, const RefPolicy& policy) {
  CheckedFiles files;
  for (const ExternalRef& ref : external_refs(bytes)) {
    OpenRef open = open_ref(path, ref, policy);
    auto& slot = files.by_path[open.path.string()];
    if (slot.empty()) slot = open.file.read_all();  // one read for a file named twice
  }
  return files;
}

const std::vector<uint8_t>* checked(const std::string& path, void* user) {
  std::error_code ec;
  const std::string key = fs::weakly_canonical(path, ec).string();
  auto& files = static_cast<CheckedFiles*>(user)->by_path;
  auto it = ec ? files.end() : files.find(key);
  return it == files.end() ? nullptr : &it->second;
}

bool checked_exists(const std::string& path, void* user) { return checked(path, user) != nullptr; }

bool read_checked(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const auto* bytes = checked(path, user);
  if (!bytes) {
    if (err) *err = "not a checked reference";
    return false;
  }
  *out = *bytes;
  return true;
}

// No '~' or variable expansion: a URI is a path relative to the asset, nothing more.
std::string no_expansion(const std::string& path, void*) { return path; }

bool no_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "uvpress writes its outputs itself";
  return false;
}

std::string image_label(const tinygltf::Image& image, size_t i) {
  return image.uri.empty() || image.uri.rfind("data:", 0) == 0
             ? "image " + std::to_string(i)
             : "image " + std::to_string(i) + " ('" + shown_uri(image.uri) + "')";
}

bool looks_binary(const std::vector<uint8_t>& head) {
  return head.size() >= 4 && head[0] == 'g' && head[1] == 'l' && head[2] == 'T' && head[3] == 'F';
}

}  // namespace

namespace {

constexpr const char* kKtx2Key = "uvpress_ktx2";

std::string fingerprint_text(uint64_t h) {
  char text[32];
  std::snprintf(text, sizeof text, "fnv1a64:%016llx", (unsigned long long)h);
  return text;
}

// Each image's KTX2 copy named in its extras (what save_gltf writes), read through the same
// reference checks as image files; the key is removed from the model either way, so that a
// copy that is dropped is not named in the output.
void read_ktx2_sidecars(GltfFile& file, const RefPolicy& refs) {
  file.image_ktx2.assign(file.model.images.size(), {});
  for (size_t i = 0; i < file.model.images.size(); ++i) {
    auto& extras = file.model.images[i].extras;
    if (!extras.IsObject() || !extras.Has(kKtx2Key)) continue;
    const tinygltf::Value entry = extras.Get(kKtx2Key);
    extras.Get<tinygltf::Value::Object>().erase(kKtx2Key);
    if (extras.Get<tinygltf::Value::Object>().empty()) extras = tinygltf::Value();
    if (!entry.IsObject() || !entry.Get("uri").IsString() || !entry.Get("source").IsString()) continue;
    if (entry.Get("source").Get<std::string>() != fingerprint_text(image_fingerprint(file.image_bytes[i]))) continue;
    // Optional: a copy that is missing, refused by the reference rule or not a KTX2 file that
    // reads is dropped (the glTF is whole without it), never read past the checks.
    try {
      OpenRef ref = open_ref(file.path, {"image " + std::to_string(i) + " KTX2", entry.Get("uri").Get<std::string>(), false, -1}, refs);
      std::vector<uint8_t> bytes = ref.file.read_all();
      read_ktx2(bytes, file.path);
      file.image_ktx2[i] = {std::move(bytes), image_fingerprint(file.image_bytes[i])};
    } catch (const InputError&) {
    }
  }
}

}  // namespace

GltfFile load_gltf(const std::string& path, const RefPolicy& refs) {
  std::vector<uint8_t> bytes = read_file(path);
  if (bytes.empty()) throw InputError(path, "file is empty");
  GltfFile file;
  file.path = path;

  CheckedFiles files = read_references(path, bytes, refs);
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&checked_exists, &no_expansion, &read_checked, &no_write, &files});
  loader.SetImageLoader(&keep_image_bytes, &file.image_bytes);
  loader.SetStoreOriginalJSONForExtrasAndExtensions(false);
  std::string err, warn;
  std::string base_dir = fs::path(path).parent_path().string();
  bool ok;
  if (looks_binary(bytes)) {
    if (bytes.size() < 20) throw InputError(path, "truncated .glb (shorter than its header)");
    const uint32_t version = uint32_t(bytes[4]) | uint32_t(bytes[5]) << 8 | uint32_t(bytes[6]) << 16 | uint32_t(bytes[7]) << 24;
    if (version != 2) throw InputError(path, "glTF binary container version " + std::to_string(version) + " is not 2");
    ok = loader.LoadBinaryFromMemory(&file.model, &err, &warn, bytes.data(), unsigned(bytes.size()), base_dir);
  } else {
    std::string ext = extension_of(path);
    if (ext == ".glb") throw InputError(path, "not a glTF binary (wrong magic, expected 'glTF')");
    // Not JSON at all (an .obj, an image): say what is expected, not the parser's message.
    size_t first = 0;
    while (first < bytes.size() && std::isspace(bytes[first])) ++first;
    if (ext != ".gltf" && (first == bytes.size() || bytes[first] != '{'))
      throw InputError(path, "not a glTF file (.gltf or .glb)");
    ok = loader.LoadASCIIFromString(&file.model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                    unsigned(bytes.size()), base_dir);
  }
  if (!ok) throw InputError(path, one_line(err));
  if (file.model.asset.version.rfind("2.", 0) != 0)
    throw InputError(path, "glTF version '" + file.model.asset.version + "' is not 2.x");

  for (const std::string& ext : file.model.extensionsRequired)
    if (!is_supported_required_extension(ext)) throw InputError(path, "requires unsupported extension " + ext);

  // tinygltf only warns about an image it could not read; for uvpress that is an error.
  file.image_bytes.resize(file.model.images.size());
  for (size_t i = 0; i < file.model.images.size(); ++i) {
    const int v = file.model.images[i].bufferView;
    if (v < 0) continue;
    const auto& view = file.model.bufferViews[size_t(v)];  // index checked by tinygltf
    const auto& data = file.model.buffers[size_t(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      throw InputError(path, "image " + std::to_string(i) + ": bufferView " + std::to_string(v) + " lies outside its buffer");
    file.image_bytes[i].assign(data.begin() + long(view.byteOffset), data.begin() + long(view.byteOffset + view.byteLength));
  }
  for (size_t i = 0; i < file.model.images.size(); ++i) {
    const auto& image = file.model.images[i];
    if (file.image_bytes[i].empty()) throw InputError(path, image_label(image, i) + " is missing or empty");
    // Untouched images are written back byte for byte: carry only what is the image it claims.
    try {
      check_image(file.image_bytes[i], image.mimeType, path);
    } catch (const InputError& e) {
      throw InputError(path, image_label(image, i) + ": " + e.what());
    }
  }
  read_ktx2_sidecars(file, refs);
  return file;
}

namespace {

size_t align(size_t n, size_t a) { return (n + a - 1) / a * a; }

// True when image i's bytes still equal what its bufferView holds.
bool view_holds(const tinygltf::Model& m, const tinygltf::Image& image, const std::vector<uint8_t>& bytes) {
  if (image.bufferView < 0 || size_t(image.bufferView) >= m.bufferViews.size()) return false;
  const auto& view = m.bufferViews[size_t(image.bufferView)];
  if (view.buffer < 0 || size_t(view.buffer) >= m.buffers.size()) return false;
  const auto& data = m.buffers[size_t(view.buffer)].data;
  return view.byteLength == bytes.size() && view.byteOffset + view.byteLength <= data.size() &&
         std::equal(bytes.begin(), bytes.end(), data.begin() + long(view.byteOffset));
}

std::string extension_for(const std::vector<uint8_t>& bytes) {
  std::string f = sniff_image_format(bytes.data(), bytes.size());
  return f == "jpeg" ? ".jpg" : f.empty() ? ".bin" : "." + f;
}

// A file name that is safe to write beside the output: letters, digits, '-', '_', '.'.
std::string safe_name(std::string s) {
  for (auto& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
}

// Each image's KTX2 copy that still matches its bytes, written as dir/<name> and named in
// the image's extras; `unique` picks the file name.
void write_ktx2_sidecars(const GltfFile& file, tinygltf::Model& m, const fs::path& dir, const std::string& stem,
                         AtomicWriter& writer, const std::function<std::string(std::string)>& unique) {
  for (size_t i = 0; i < m.images.size() && i < file.image_ktx2.size(); ++i) {
    const Ktx2Sidecar& k = file.image_ktx2[i];
    if (k.bytes.empty() || k.source != image_fingerprint(file.image_bytes[i])) continue;
    const auto& image = file.model.images[i];
    std::string base = image.uri.empty() || image.uri.rfind("data:", 0) == 0 ? "" : fs::path(image.uri).stem().string();
    if (base.rfind(stem + "_", 0) == 0) base = base.substr(stem.size() + 1);  // a uvpress output's own name
    if (base.empty()) base = image.name.empty() ? "image" + std::to_string(i) : image.name;
    const std::string name = unique(stem + "_" + base + ".ktx2");
    writer.add((dir / name).string(), k.bytes);
    tinygltf::Value::Object entry;
    entry["uri"] = tinygltf::Value(name);
    entry["mimeType"] = tinygltf::Value(std::string("image/ktx2"));
    entry["byteLength"] = tinygltf::Value(int(k.bytes.size()));
    entry["source"] = tinygltf::Value(fingerprint_text(k.source));
    tinygltf::Value::Object extras;
    if (m.images[i].extras.IsObject()) extras = m.images[i].extras.Get<tinygltf::Value::Object>();
    extras[kKtx2Key] = tinygltf::Value(std::move(entry));
    m.images[i].extras = tinygltf::Value(std::move(extras));
  }
}

std::string serialize(tinygltf::Model& m, bool binary) {
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(&skip_image_write, nullptr);
  std::ostringstream out;
  if (!writer.WriteGltfSceneToStream(&m, out, !binary, binary)) throw std::runtime_error("glTF serialization failed");
  return out.str();
}

void save_glb(const GltfFile& file, const std::string& path, AtomicWriter& writer) {
  tinygltf::Model m = file.model;
  // One buffer: the BIN chunk. Every old buffer is appended at a 16-byte aligned offset.
  tinygltf::Buffer merged;
  std::vector<size_t> base(m.buffers.size());
  for (size_t b = 0; b < m.buffers.size(); ++b) {
    base[b] = align(merged.data.size(), 16);
    merged.data.resize(base[b]);
    merged.data.insert(merged.data.end(), m.buffers[b].data.begin(), m.buffers[b].data.end());
  }
  if (!m.buffers.empty()) {
    merged.name = m.buffers[0].name;
    merged.extras = m.buffers[0].extras;
  }
  for (auto& view : m.bufferViews) {
    if (view.buffer < 0 || size_t(view.buffer) >= base.size()) continue;
    view.byteOffset += base[size_t(view.buffer)];
    view.buffer = 0;
  }
  // Images that are not (or no longer) in a bufferView go into the BIN chunk.
  for (size_t i = 0; i < m.images.size(); ++i) {
    auto& image = m.images[i];
    const auto& bytes = file.image_bytes[i];
    if (view_holds(file.model, file.model.images[i], bytes)) continue;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = align(merged.data.size(), 16);
    view.byteLength = bytes.size();
    merged.data.resize(view.byteOffset);
    merged.data.insert(merged.data.end(), bytes.begin(), bytes.end());
    image.bufferView = int(m.bufferViews.size());
    image.mimeType = mime_of_format(sniff_image_format(bytes.data(), bytes.size()));
    image.uri.clear();
    m.bufferViews.push_back(view);
  }
  m.buffers.clear();
  if (!merged.data.empty()) {
    merged.data.resize(align(merged.data.size(), 4));
    m.buffers.push_back(std::move(merged));
  }
  std::set<std::string> used;
  write_ktx2_sidecars(file, m, fs::path(path).parent_path(), fs::path(path).stem().string(), writer,
                      [&](std::string name) {
                        name = safe_name(name);
                        std::string candidate = name;
                        for (int k = 1; used.count(candidate); ++k)
                          candidate = fs::path(name).stem().string() + "_" + std::to_string(k) + ".ktx2";
                        used.insert(candidate);
                        return candidate;
                      });
  writer.add(path, serialize(m, true));
}

// True when `path` is a regular file holding exactly `bytes`.
bool holds_bytes(const fs::path& path, const std::vector<uint8_t>& bytes) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec) || fs::file_size(path, ec) != bytes.size() || ec) return false;
  std::ifstream in(path, std::ios::binary);
  std::vector<char> have(bytes.size());
  return in.read(have.data(), std::streamsize(have.size())) && std::equal(have.begin(), have.end(), bytes.begin(), bytes.end(),
                                                                          [](char a, uint8_t b) { return uint8_t(a) == b; });
}

void save_text_gltf(const GltfFile& file, const std::string& path, const SaveOptions& options, AtomicWriter& writer) {
  tinygltf::Model m = file.model;
  fs::path target(path);
  const std::string stem = target.stem().string();
  const fs::path dir = target.parent_path();
  std::set<std::string> used;
  auto unique = [&](std::string name) {
    name = safe_name(name);
    std::string candidate = name;
    for (int k = 1; used.count(candidate); ++k)
      candidate = fs::path(name).stem().string() + "_" + std::to_string(k) + fs::path(name).extension().string();
    used.insert(candidate);
    return candidate;
  };

  // Images: kept in their bufferView when unchanged, otherwise one file each.
  for (size_t i = 0; i < m.images.size(); ++i) {
    auto& image = m.images[i];
    const auto& bytes = file.image_bytes[i];
    if (view_holds(file.model, file.model.images[i], bytes)) continue;
    std::string original = image.uri.rfind("data:", 0) == 0 ? "" : fs::path(image.uri).filename().string();
    std::string name;
    if (options.keep_image_names && !original.empty()) {
      // Its own name, unless this output already uses it, it is the .gltf itself, or the
      // folder holds other bytes under it (never overwrite a file that is not ours).
      const std::string own = safe_name(original);
      if (!used.count(own) && own != target.filename().string() && own != stem + ".bin" &&
          (!fs::exists(dir / own) || holds_bytes(dir / own, bytes)))
        name = unique(own);
    }
    if (name.empty())
      name = unique(stem + "_" + (original.empty() ? "image" + std::to_string(i) + extension_for(bytes) : original));
    writer.add((dir / name).string(), bytes);
    image.uri = name;
    image.bufferView = -1;
    image.mimeType.clear();
  }

  write_ktx2_sidecars(file, m, dir, stem, writer, unique);

  // Buffers: one .bin each. tinygltf would inline them as base64; serialize without the
  // bytes and patch uri and byteLength afterwards.
  std::vector<std::string> names;
  std::vector<size_t> lengths;
  for (size_t b = 0; b < m.buffers.size(); ++b) {
    names.push_back(unique(m.buffers.size() == 1 ? stem + ".bin" : stem + "_" + std::to_string(b) + ".bin"));
    lengths.push_back(m.buffers[b].data.size());
    writer.add((dir / names.back()).string(), m.buffers[b].data);
    m.buffers[b].data.clear();
  }
  nlohmann::ordered_json json = nlohmann::ordered_json::parse(serialize(m, false));
  for (size_t b = 0; b < names.size(); ++b) {
    json["buffers"][b]["uri"] = names[b];
    json["buffers"][b]["byteLength"] = lengths[b];
  }
  writer.add(path, json.dump(2) + "\n");
}

}  // namespace

void save_gltf(const GltfFile& file, const std::string& path, const SaveOptions& options) {
  AtomicWriter writer;
  save_gltf(file, path, options, writer);
  writer.commit();
}

void save_gltf(const GltfFile& file, const std::string& path, const SaveOptions& options, AtomicWriter& writer) {
  std::string ext = extension_of(path);
  if (ext == ".glb") return save_glb(file, path, writer);
  if (ext == ".gltf") return save_text_gltf(file, path, options, writer);
  throw InputError(path, "unsupported output format '" + ext + "' (use .gltf or .glb)");
}

}  // namespace uvpress::io
