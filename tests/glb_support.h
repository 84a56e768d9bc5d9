// Reads a written GLB's JSON chunk, for tests that check what rigbake put into a file.
#pragma once

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

namespace rigbake::test {

// `glb` is the file's bytes (GLB or VRM).
inline nlohmann::json glbJson(const std::string& glb) {
  REQUIRE(glb.size() >= 20);
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  REQUIRE(20 + static_cast<size_t>(json_length) <= glb.size());
  return nlohmann::json::parse(glb.substr(20, json_length));
}

}  // namespace rigbake::test
