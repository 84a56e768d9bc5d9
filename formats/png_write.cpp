#include "formats/png_write.h"

#include <png.h>

#include "anatomy/error.h"

namespace rigbake {

std::string encodePng(const RgbImage& image) {
  // libpng's simplified API (1.6): no setjmp, errors come back as a status and a message.
  png_image description{};
  description.version = PNG_IMAGE_VERSION;
  description.width = static_cast<png_uint_32>(image.width);
  description.height = static_cast<png_uint_32>(image.height);
  description.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&description, nullptr, &size, 0, image.pixels.data(), 0, nullptr))
    fail("INTERNAL", "", std::string("PNG encoding failed: ") + description.message);
  std::string out(size, '\0');
  if (!png_image_write_to_memory(&description, out.data(), &size, 0, image.pixels.data(), 0, nullptr))
    fail("INTERNAL", "", std::string("PNG encoding failed: ") + description.message);
  out.resize(size);
  png_image_free(&description);
  return out;
}

std::string pngDataUri(const RgbImage& image) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const std::string bytes = encodePng(image);
  std::string out = "data:image/png;base64,";
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace rigbake
