// Texture images: decode from the bytes a glTF carries (file, data: URI or bufferView
// alike; libpng and libjpeg, io/image_decode.h), encode back to PNG or JPEG. Formats are recognized by their
// magic bytes, not by names, because glTF mimeTypes and URIs are often wrong.
#pragma once

#include "core/image.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::io {

// "png", "jpeg", "ktx2", "webp", "gif", "bmp", or "" when unknown.
std::string sniff_image_format(const uint8_t* bytes, size_t size);
// "image/png", "image/jpeg", ... for a sniffed format.
std::string mime_of_format(const std::string& format);

struct ImageHeader {
  uint32_t width = 0, height = 0, channels = 0, bits = 8;
  std::string format;
};

// Limits that keep a declared size from exhausting memory (16K x 16K texels).
constexpr uint32_t kMaxImageSide = 16384;

// `name` labels errors (the asset file and image index). Throws InputError.
ImageHeader read_image_header(const std::vector<uint8_t>& bytes, const std::string& name);

// For images carried byte for byte: throws InputError(name, reason) unless `bytes` are a
// PNG, JPEG, KTX2 or WebP image whose header reads, whose sides are within kMaxImageSide,
// and whose format is the one `mime_type` names (when it names one). Decodes no pixels.
void check_image(const std::vector<uint8_t>& bytes, const std::string& mime_type, const std::string& name);
Image decode_image(const std::vector<uint8_t>& bytes, const std::string& name);

// How a texture is written: the input's codec and the choices its encoder made, so that a
// re-baked texture costs what its author accepted (issue 18).
struct EncodeSettings {
  std::string format = "png";  // "png" | "jpeg"
  bool palette = false;        // PNG: an 8-bit palette (the input was paletted)
  // PNG with palette: the input's own palette (RGBA, entry order), drawn from and no other
  // colour (PngOptions::fixed_palette); empty: a new palette for the new texels.
  std::vector<std::array<uint8_t, 4>> palette_colours;
  bool palette_when_faithful = false;  // PNG: a palette where it is near-lossless (PngOptions; 8-bit truecolour inputs)
  // PNG with a new palette: per texel (row-major) how much its colour weighs in the palette's
  // fit and in the faithful test (PngOptions::importance); empty: all alike.
  std::vector<uint8_t> importance;
  int jpeg_quality = 95;       // JPEG: IJG quality, estimated from the input's tables
  int jpeg_h_sampling = 2, jpeg_v_sampling = 2;  // JPEG: luma sampling factors (2, 2: 4:2:0)
  bool progressive = false;    // JPEG: progressive when the input was
  bool draft = false;          // PNG: one fast pass, the same texels (PngOptions::draft); never for output
};

// The settings that reproduce `bytes`' encoding: PNG (paletted or not) or JPEG (quality
// from its quantization tables, subsampling, progressive). Anything else: plain PNG.
EncodeSettings encode_settings_of(const std::vector<uint8_t>& bytes);
// In words, for reports: "png (8-bit palette: the input's 54 colours)", "jpeg (quality 87,
// 4:2:0, progressive)".
std::string describe(const EncodeSettings& settings);
// What `bytes` are, in the same words: "png (8-bit palette)", "png", "jpeg (quality 87, 4:2:0)".
std::string describe_encoded(const std::vector<uint8_t>& bytes);

// PNG: 8 or 16 bit as image.bits says, the smallest of a few row filter choices deflated by
// libdeflate at its strongest, no alpha channel when every texel is opaque, in a palette when
// settings.palette (the input's own where settings.palette_colours holds it; io/png_encode.h).
// JPEG: libjpeg at the settings (io/jpeg_encode.h).
std::vector<uint8_t> encode_image(const Image& image, const EncodeSettings& settings);
// The same with default settings for `format` ("png": not paletted; "jpeg": quality 95, 4:2:0).
std::vector<uint8_t> encode_image(const Image& image, const std::string& format);

}  // namespace uvpress::io
