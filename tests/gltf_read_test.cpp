#include "formats/gltf_document.h"

#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "cli_support.h"
#include "test_support.h"

using namespace rigbake;

namespace {
std::string errorCodeOf(const std::string& path) {
  try {
    loadCharacter(path);
  } catch (const Error& error) {
    return error.code();
  }
  return "";
}
}  // namespace

TEST_CASE("every shared asset loads with a skeleton and meshes in metres") {
  for (const std::string& name : test::sharedAssetNames()) {
    std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    LoadedCharacter loaded = loadCharacter(path);
    const Character& c = loaded.character;
    INFO(name);
    CHECK(c.skeleton.size() >= 19);
    for (int j = 0; j < c.skeleton.size(); ++j) CHECK(c.skeleton.parents[j] < j);
    double min_y = 1e9, max_y = -1e9;
    for (const MeshPart& part : c.meshes) {
      if (!part.skinned && part.rigid_joint < 0) continue;
      for (const auto& p : part.positions) {
        min_y = std::min(min_y, p.y());
        max_y = std::max(max_y, p.y());
      }
    }
    // All five are Y-up in the scene, between 1 m (KayKit) and 5 m (the RobotExpressive giant) tall.
    CHECK(max_y - min_y > 1.0);
    CHECK(max_y - min_y < 5.0);
  }
}

TEST_CASE("CesiumMan's Z-up bind space comes out Y-up and its walk clip is read") {
  std::string path = test::requireAsset("CesiumMan.glb");
  if (path.empty()) return;
  Character c = loadCharacter(path).character;
  int neck = c.skeleton.find("Skeleton_neck_joint_1");
  int pelvis = c.skeleton.find("Skeleton_torso_joint_1");
  REQUIRE(neck >= 0);
  REQUIRE(pelvis >= 0);
  Eigen::Vector3d up = c.skeleton.bindPosition(neck) - c.skeleton.bindPosition(pelvis);
  CHECK(up.normalized().y() > 0.99);
  REQUIRE(c.clips.size() == 1);
  CHECK(c.clips[0].tracks.size() == 57);
  CHECK(c.clips[0].duration == Approx(2.0).margin(0.1));
}

TEST_CASE("bad files give stable error codes") {
  CHECK(errorCodeOf("/nonexistent/file.glb") == "IO_FILE_NOT_FOUND");
  CHECK(errorCodeOf(test::sourceDir() + "/CMakeLists.txt") == "GLTF_PARSE_FAILED");
}

namespace {
// Whether `text` is one line of well-formed UTF-8 (what every error line must be, docs/errors.md).
bool isOnePrintableLine(const std::string& text) {
  for (size_t i = 0; i < text.size();) {
    const size_t length = utf8SequenceAt(text, i);
    if (length == 0 || static_cast<unsigned char>(text[i]) < 0x20) return false;
    i += length;
  }
  return true;
}

// Loads `bytes` as a file: nothing, or the Error's code after checking its exit status and line. Any
// other exception is what the CLI reports as INTERNAL, a bug, and fails the test.
std::string loadFailure(const test::TempDir& dir, const std::string& bytes, const std::string& name) {
  const std::string path = dir / name;
  std::ofstream(path, std::ios::binary) << bytes;
  try {
    loadCharacter(path);
  } catch (const Error& error) {
    CHECK(error.exitCode() == ExitCode::kInvalidInput);
    CHECK(isOnePrintableLine(error.what()));
    return error.code();
  } catch (const std::exception& error) {
    FAIL("not a rigbake::Error (the CLI would say INTERNAL): " << error.what());
  }
  return "";
}
}  // namespace

TEST_CASE("glTF read: damaged files fail with an invalid-input code and one printable line, never anything else") {
  // The sample GLB cut short, its header and chunk words overwritten, bytes of its JSON changed one at a
  // time into other digits, letters or punctuation (so that most stay JSON and reach the reader's own
  // checks), and stretches of its binary chunk flipped; under the sanitizer pass, a memory-safety check of
  // the reader too. Found this way: a stray byte in the JSON made the error line invalid UTF-8, which
  // took `rigbake build` to INTERNAL through its summary.
  const std::string bytes = test::slurp(test::sampleGlbPath());
  uint32_t json_length = 0;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const size_t json_end = 20 + json_length;
  test::TempDir dir;
  std::vector<std::string> damaged;
  for (int k = 0; k < 24; ++k) damaged.push_back(bytes.substr(0, bytes.size() * static_cast<size_t>(k) / 24));
  for (size_t at : {size_t{4}, size_t{8}, size_t{12}, size_t{16}, json_end, json_end + 4}) {
    for (uint32_t value : {0u, 1u, 19u, 0xFFFFFFFFu}) {
      std::string changed = bytes;
      std::memcpy(&changed[at], &value, 4);
      damaged.push_back(changed);
    }
  }
  std::uint32_t state = 12345;  // a fixed linear congruential sequence: the same damage on every run
  auto next = [&state](std::uint32_t bound) {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) % bound;
  };
  for (int k = 0; k < 96; ++k) {
    std::string changed = bytes;
    const size_t at = 20 + next(json_length);
    const char c = changed[at];
    const char* pool = std::isdigit(static_cast<unsigned char>(c)) ? "0123456789-.e"
                       : std::isalpha(static_cast<unsigned char>(c)) ? "abcxyzAJO"
                                                                      : "{}[],:\"0 \xA3";
    changed[at] = pool[next(static_cast<std::uint32_t>(std::strlen(pool)))];
    damaged.push_back(changed);
  }
  for (int k = 0; k < 24; ++k) {
    std::string changed = bytes;
    const size_t at = json_end + 8 + (bytes.size() - json_end - 8) * static_cast<size_t>(k) / 24;
    for (size_t i = at; i < std::min(changed.size(), at + 64); ++i) changed[i] = static_cast<char>(changed[i] ^ 0x5a);
    damaged.push_back(changed);
  }
  std::map<std::string, int> codes;
  for (size_t d = 0; d < damaged.size(); ++d) {
    INFO("damage " << d);
    ++codes[loadFailure(dir, damaged[d], "damaged.glb")];
  }
  // Most damage is caught, and by the container and parse checks first.
  CHECK(codes["GLTF_PARSE_FAILED"] >= 40);
  CHECK(codes[""] < static_cast<int>(damaged.size()) / 2);
}
