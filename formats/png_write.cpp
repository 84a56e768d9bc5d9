#include "formats/png_write.h"


#include <png.h>

#include "core/error.h"
#include "formats/base64.h"

namespace rigbake {

std::string encodePng(const RgbImage& image) {
  // libpng's simplified API (1.6): no setjmp, errors come back as a status and a message.
  png_image description{};
  description.version = PNG_IMAGE_VERSION;
  description.width = static_cast<png_uint_32>(image.width);
  description.height = static_cast<png_uint_32>(image.height);
  description.format = PNG_FORMAT_RGB;
  // One pass into a buffer of the largest size a PNG of this image can take (asking for the size first
  // compressed every picture twice: half of a report's writing time).
  png_alloc_size_t size = PNG_IMAGE_PNG_SIZE_MAX(description);
  std::string out(size, '\0');
  if (!png_image_write_to_memory(&description, out.data(), &size, 0, image.pixels.data(), 0, nullptr))
    fail(errc::INTERNAL, "", std::string("PNG encoding failed: ") + description.message);
  out.resize(size);
  png_image_free(&description);
  return out;
}

std::string pngDataUri(const RgbImage& image) { return "data:image/png;base64," + base64Encode(encodePng(image)); }

}  // namespace rigbake
