// Base64 (RFC 4648, standard alphabet, padded), for inlining binary data into pages: the report's PNG
// pictures and the viewer's GLB.
#pragma once

#include <string>

namespace rigbake {

std::string base64Encode(const std::string& bytes);

}  // namespace rigbake
