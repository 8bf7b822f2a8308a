#include "io/image_io.h"

#include "core/error.h"
#include "io/jpeg_encode.h"
#include "io/jpeg_header.h"
#include "io/png_encode.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <memory>
#include <mutex>
#include <unistd.h>

namespace uvpress::io {

namespace oiio = OIIO;

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

// OpenImageIO's messages may span lines (libpng's are "...\nPNG read error: ..."); the user
// gets one.
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (size_t at; (at = s.find('\n')) != std::string::npos;) s.replace(at, 1, "; ");
  return s.empty() ? "unreadable data" : s;
}

// libpng's default error handler (which OpenImageIO keeps) also prints each error on
// stderr, while OpenImageIO returns the same text: keep stderr to one line per error by
// sending fd 2 to /dev/null while a decoder runs. Serialized, since fd 2 is per process.
class QuietStderr {
 public:
  QuietStderr() : lock_(mutex()) {
    std::fflush(stderr);
    saved_ = ::dup(2);
    int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    if (saved_ >= 0) {
      ::dup2(saved_, 2);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int saved_ = -1;
};

// Opens an in-memory PNG or JPEG; the proxy must outlive the input.
std::unique_ptr<oiio::ImageInput> open_memory(const std::vector<uint8_t>& bytes, const std::string& name,
                                              oiio::Filesystem::IOMemReader& proxy, std::string& format) {
  if (bytes.empty()) throw InputError(name, "image is empty (0 bytes)");
  format = sniff_image_format(bytes.data(), bytes.size());
  if (format.empty()) throw InputError(name, "image is not PNG or JPEG (unrecognized data)");
  if (format != "png" && format != "jpeg")
    throw InputError(name, "image format " + format + " is not supported (PNG and JPEG are)");
  if (format == "png" && bytes.size() >= 24 && std::memcmp(&bytes[12], "IHDR", 4) == 0) {
    // The declared size, before a decoder reads (or allocates) anything.
    auto be32 = [&](size_t at) { return uint32_t(bytes[at]) << 24 | uint32_t(bytes[at + 1]) << 16 | uint32_t(bytes[at + 2]) << 8 | bytes[at + 3]; };
    const uint32_t w = be32(16), h = be32(20);
    if (w > kMaxImageSide || h > kMaxImageSide)
      throw InputError(name, "image declares " + std::to_string(w) + "x" + std::to_string(h) + ", larger than the supported " +
                                 std::to_string(kMaxImageSide) + " per side");
  }
  oiio::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // keep straight alpha as stored, no premultiply
  void* proxy_ptr = &proxy;
  config.attribute("oiio:ioproxy", oiio::TypeDesc::PTR, &proxy_ptr);
  auto in = oiio::ImageInput::open(format == "png" ? "memory.png" : "memory.jpg", &config, &proxy);
  if (!in) throw InputError(name, "corrupt " + format + " image: " + one_line(oiio::geterror()));
  const oiio::ImageSpec& s = in->spec();
  if (s.width <= 0 || s.height <= 0 || s.nchannels <= 0 || s.nchannels > 4)
    throw InputError(name, "image has an invalid size or channel count");
  if (uint32_t(s.width) > kMaxImageSide || uint32_t(s.height) > kMaxImageSide)
    throw InputError(name, "image is " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                               ", larger than the supported " + std::to_string(kMaxImageSide) + " per side");
  return in;
}

uint32_t bits_of(const oiio::ImageSpec& s) { return s.format.size() >= 2 ? 16 : 8; }

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
  oiio::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  QuietStderr quiet;
  ImageHeader h;
  auto in = open_memory(bytes, name, proxy, h.format);
  const auto& s = in->spec();
  h.width = uint32_t(s.width), h.height = uint32_t(s.height), h.channels = uint32_t(s.nchannels), h.bits = bits_of(s);
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
    read_image_header(bytes, name);  // opens the header with the decoder that re-bakes it
    return;
  }
  const auto [w, h] = declared_size(bytes, format);
  if (w == 0 || h == 0) throw InputError(name, "corrupt " + format + " image (no readable size in its header)");
  if (w > kMaxImageSide || h > kMaxImageSide)
    throw InputError(name, "image declares " + std::to_string(w) + "x" + std::to_string(h) + ", larger than the supported " +
                               std::to_string(kMaxImageSide) + " per side");
}

Image decode_image(const std::vector<uint8_t>& bytes, const std::string& name) {
  oiio::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  QuietStderr quiet;
  std::string format;
  auto in = open_memory(bytes, name, proxy, format);
  const auto& s = in->spec();
  Image image;
  image.width = uint32_t(s.width), image.height = uint32_t(s.height), image.channels = uint32_t(s.nchannels);
  image.bits = bits_of(s);
  image.pixels.resize(size_t(image.width) * image.height * image.channels);
  // Read as float: OIIO maps 8- and 16-bit unsigned values to [0,1] exactly (v / 255, v / 65535).
  if (!in->read_image(0, 0, 0, s.nchannels, oiio::TypeDesc::FLOAT, image.pixels.data()))
    throw InputError(name, "corrupt " + format + " image: " + one_line(in->geterror()));
  return image;
}

EncodeSettings encode_settings_of(const std::vector<uint8_t>& bytes) {
  EncodeSettings s;
  const std::string format = sniff_image_format(bytes.data(), bytes.size());
  if (format == "png") {
    // IHDR's colour type (byte 25 of the file): 3 is indexed colour.
    s.palette = bytes.size() >= 26 && std::memcmp(&bytes[12], "IHDR", 4) == 0 && bytes[25] == 3;
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
  if (s.format == "png") return s.palette ? "png (8-bit palette)" : "png";
  const char* sub = s.jpeg_h_sampling == 2 && s.jpeg_v_sampling == 2   ? "4:2:0"
                    : s.jpeg_h_sampling == 2 && s.jpeg_v_sampling == 1 ? "4:2:2"
                    : s.jpeg_h_sampling == 1 && s.jpeg_v_sampling == 1 ? "4:4:4"
                                                                       : "other";
  return "jpeg (quality " + std::to_string(s.jpeg_quality) + ", " + sub + (s.progressive ? ", progressive)" : ")");
}

std::vector<uint8_t> encode_image(const Image& image, const EncodeSettings& settings) {
  if (image.width == 0 || image.height == 0 || image.channels == 0 || image.channels > 4 ||
      image.pixels.size() != size_t(image.width) * image.height * image.channels)
    throw std::invalid_argument("encode_image: inconsistent image");
  if (settings.format == "png") {
    PngOptions o;
    o.palette = settings.palette;
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
