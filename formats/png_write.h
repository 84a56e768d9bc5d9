// PNG encoding of report pictures with libpng (Debian libpng-dev): the reference implementation of
// the format, so every browser and tool reads what rigbake writes. Deterministic: fixed compression
// settings and no time or text chunks, so the same pixels give the same bytes.
#pragma once

#include <string>

#include "pipeline/render.h"

namespace rigbake {

std::string encodePng(const RgbImage& image);

// "data:image/png;base64,..." for inlining into the HTML report.
std::string pngDataUri(const RgbImage& image);

}  // namespace rigbake
