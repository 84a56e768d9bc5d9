// A path's file name without its directories ("models/hero.gltf" -> "hero.gltf"): what messages,
// reports and muscle files call a character by. One definition for every layer, which had four.
#pragma once

#include <string>

namespace rigbake {

inline std::string fileNameOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace rigbake
