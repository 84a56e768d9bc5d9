// Reads a written GLB's JSON chunk and skin weights, for tests that check what rigbake put into a file.
#pragma once

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "formats/gltf_document.h"

namespace rigbake::test {

// `glb` is the file's bytes (GLB or VRM).
inline nlohmann::json glbJson(const std::string& glb) {
  REQUIRE(glb.size() >= 20);
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  REQUIRE(20 + static_cast<size_t>(json_length) <= glb.size());
  return nlohmann::json::parse(glb.substr(20, json_length));
}

// How far the file's skin weights lie from multiples of 0.001, in thousandths: under 1000/65535 for
// the 0.001 weights stored as UNSIGNED_SHORT, up to 0.5 for finer ones.
inline double largestOffMilliLattice(const std::string& path) {
  double largest = 0.0;
  for (const MeshPart& mesh : loadCharacter(path).character.meshes)
    for (double w : mesh.weights) largest = std::max(largest, std::abs(w * 1000.0 - std::round(w * 1000.0)));
  return largest;
}

}  // namespace rigbake::test
