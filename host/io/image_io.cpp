#include "io/image_io.h"

#include "core/error.h"
#include "io/image_decode.h"
#include "io/jpeg_encode.h"
#include "io/jpeg_header.h"
#include "io/png_encode.h"

#include <array>
#include <cstring>

namespace uvpress::io {

std::string sniff_image_format(const uint8_t* b, size_t n) {
  auto starts = [&](const char* magic, size_t len, size_t at = 0) {
    return n >= at + len && std::memcmp(b + at, magic, len) == 0;
  };
  if (starts("\x89PNG\r\n\x1a\n", 8)) return "png";
  if (starts("\xff\xd8\xff", 3)) return "jpeg";
  if (starts("\xabKTX 20\xbb\r\n\x1a\n", 12)) return "ktx2";
  if (starts("RIFF", 4) && starts("WEBP", 4, 8)) return "webp";
  if (starts("GIF8", 4)) return "gif";
  if (starts("BM", 2)) return "bmp";
  return "";
}

std::string mime_of_format(const std::string& f) {
  if (f == "png") return "image/png";
  if (f == "jpeg") return "image/jpeg";
  if (f == "ktx2") return "image/ktx2";
  if (f == "webp") return "image/webp";
  return "application/octet-stream";
}

namespace {

// Decodes an in-memory PNG or JPEG (its header alone when `header_only`).
Image decode(const std::vector<uint8_t>& bytes, const std::string& name, bool header_only, std::string& format) {
  if (bytes.empty()) throw InputError(name, "image is empty (0 bytes)");
  format = sniff_image_format(bytes.data(), bytes.size());
  if (format.empty()) throw InputError(name, "image is not PNG or JPEG (unrecognized data)");
  if (format != "png" && format != "jpeg")
    throw InputError(name, "image format " + format + " is not supported (PNG and JPEG are)");
  try {
    return format == "png" ? decode_png(bytes.data(), bytes.size(), header_only, kMaxImageSide)
                           : decode_jpeg(bytes.data(), bytes.size(), header_only, kMaxImageSide);
  } catch (const ImageTooLarge& e) {
    throw InputError(name, e.what());
  } catch (const DecodeError& e) {
    throw InputError(name, "corrupt " + format + " image: " + e.what());
  }
}

uint32_t le(const std::vector<uint8_t>& b, size_t at, int bytes) {
  uint32_t v = 0;
  for (int k = bytes - 1; k >= 0; --k) v = v << 8 | b[at + size_t(k)];
  return v;
}

// Width and height from a KTX2 or WebP header ({0, 0} when the header is cut short or
// unknown): uvpress does not decode these, it only carries them.
std::array<uint32_t, 2> declared_size(const std::vector<uint8_t>& b, const std::string& format) {
  if (format == "ktx2") return b.size() >= 80 ? std::array<uint32_t, 2>{le(b, 20, 4), le(b, 24, 4)} : std::array<uint32_t, 2>{0, 0};
  // WebP: RIFF....WEBP then a VP8 (lossy), VP8L (lossless) or VP8X (extended) chunk.
  if (b.size() >= 30 && std::memcmp(&b[12], "VP8X", 4) == 0) return {le(b, 24, 3) + 1, le(b, 27, 3) + 1};
  if (b.size() >= 25 && std::memcmp(&b[12], "VP8L", 4) == 0 && b[20] == 0x2f) {
    const uint32_t bits = le(b, 21, 4);
    return {(bits & 0x3fff) + 1, (bits >> 14 & 0x3fff) + 1};
  }
  if (b.size() >= 30 && std::memcmp(&b[12], "VP8 ", 4) == 0 && b[23] == 0x9d && b[24] == 0x01 && b[25] == 0x2a)
    return {le(b, 26, 2) & 0x3fff, le(b, 28, 2) & 0x3fff};
  return {0, 0};
}

}  // namespace

ImageHeader read_image_header(const std::vector<uint8_t>& bytes, const std::string& name) {
  ImageHeader h;
  const Image image = decode(bytes, name, true, h.format);
  h.width = image.width, h.height = image.height, h.channels = image.channels, h.bits = image.bits;
  return h;
}

void check_image(const std::vector<uint8_t>& bytes, const std::string& mime_type, const std::string& name) {
  const std::string format = sniff_image_format(bytes.data(), bytes.size());
  if (format != "png" && format != "jpeg" && format != "ktx2" && format != "webp")
    throw InputError(name, "is not a PNG, JPEG, KTX2 or WebP image (" + (format.empty() ? "unrecognized" : format) + " data)");
  const bool jpg_alias = format == "jpeg" && mime_type == "image/jpg";  // common in the wild
  if (!mime_type.empty() && mime_type != mime_of_format(format) && !jpg_alias)
    throw InputError(name, "holds " + format + " data, but its mimeType says '" + mime_type.substr(0, 40) + "'");
  if (format == "png" || format == "jpeg") {
    read_image_header(bytes, name);  // reads the header with the decoder that re-bakes it
    return;
  }
  const auto [w, h] = declared_size(bytes, format);
  if (w == 0 || h == 0) throw InputError(name, "corrupt " + format + " image (no readable size in its header)");
  if (w > kMaxImageSide || h > kMaxImageSide)
    throw InputError(name, "image declares " + std::to_string(w) + "x" + std::to_string(h) + ", larger than the supported " +
                               std::to_string(kMaxImageSide) + " per side");
}

Image decode_image(const std::vector<uint8_t>& bytes, const std::string& name) {
  std::string format;
  return decode(bytes, name, false, format);
}

EncodeSettings encode_settings_of(const std::vector<uint8_t>& bytes) {
  EncodeSettings s;
  const std::string format = sniff_image_format(bytes.data(), bytes.size());
  if (format == "png") {
    // IHDR's colour type (byte 25 of the file): 3 is indexed colour.
    const bool header = bytes.size() >= 26 && std::memcmp(&bytes[12], "IHDR", 4) == 0;
    s.palette = header && bytes[25] == 3;
    if (s.palette) s.palette_colours = read_png_palette(bytes.data(), bytes.size());
    // 8-bit RGB or RGBA: a palette where it loses (almost) nothing (PngOptions). Grey keeps
    // its one byte a texel.
    s.palette_when_faithful = header && (bytes[25] == 2 || bytes[25] == 6) && bytes[24] == 8;
  } else if (format == "jpeg") {
    const JpegHeader h = read_jpeg_header(bytes.data(), bytes.size());
    s.format = "jpeg";
    if (h.valid) {
      if (h.quality > 0) s.jpeg_quality = h.quality;
      s.jpeg_h_sampling = h.components >= 3 ? h.h_sampling : 1;
      s.jpeg_v_sampling = h.components >= 3 ? h.v_sampling : 1;
      s.progressive = h.progressive;
    }
  }
  return s;
}

std::string describe(const EncodeSettings& s) {
  if (s.format == "png") {
    if (s.palette && !s.palette_colours.empty())
      return "png (8-bit palette: the input's " + std::to_string(s.palette_colours.size()) + " colours)";
    return s.palette ? "png (8-bit palette)" : s.palette_when_faithful ? "png (8-bit palette where faithful)" : "png";
  }
  const char* sub = s.jpeg_h_sampling == 2 && s.jpeg_v_sampling == 2   ? "4:2:0"
                    : s.jpeg_h_sampling == 2 && s.jpeg_v_sampling == 1 ? "4:2:2"
                    : s.jpeg_h_sampling == 1 && s.jpeg_v_sampling == 1 ? "4:4:4"
                                                                       : "other";
  return "jpeg (quality " + std::to_string(s.jpeg_quality) + ", " + sub + (s.progressive ? ", progressive)" : ")");
}

std::string describe_encoded(const std::vector<uint8_t>& bytes) {
  EncodeSettings s = encode_settings_of(bytes);
  s.palette_when_faithful = false;  // choices for re-encoding, not properties of these bytes
  s.palette_colours.clear();
  return describe(s);
}

std::vector<uint8_t> encode_image(const Image& image, const EncodeSettings& settings) {
  if (image.width == 0 || image.height == 0 || image.channels == 0 || image.channels > 4 ||
      image.pixels.size() != size_t(image.width) * image.height * image.channels)
    throw std::invalid_argument("encode_image: inconsistent image");
  if (settings.format == "png") {
    PngOptions o;
    o.palette = settings.palette;
    o.fixed_palette = settings.palette_colours;
    o.palette_when_faithful = settings.palette_when_faithful;
    o.importance = settings.importance;
    o.draft = settings.draft;
    return encode_png(image, o);
  }
  if (settings.format != "jpeg") throw std::invalid_argument("encode_image: format must be png or jpeg");
  JpegOptions o;
  o.quality = settings.jpeg_quality;
  o.h_sampling = settings.jpeg_h_sampling, o.v_sampling = settings.jpeg_v_sampling;
  o.progressive = settings.progressive;
  return encode_jpeg(image, o);
}

std::vector<uint8_t> encode_image(const Image& image, const std::string& format) {
  if (format != "png" && format != "jpeg") throw std::invalid_argument("encode_image: format must be png or jpeg");
  EncodeSettings s;
  s.format = format;
  return encode_image(image, s);
}

}  // namespace uvpress::io
