#include "formats/gltf_document.h"

#include "anatomy/error.h"
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
