// Blender's glTF importer (Debian's blender, headless) reads every baked file: the armature has the
// muscles' skinned joints as bones and every skinned mesh a vertex group for each.
#include <tiny_gltf.h>

#include "anatomy_fixture.h"
#include "cli_support.h"
#include "external_tools.h"
#include "formats/gltf_bake.h"
#include "formats/gltf_write.h"
#include "pipeline/bake.h"

using namespace rigbake;
namespace ext = rigbake::test::external;

TEST_CASE("bake: Blender imports every baked file with the muscle bones and their vertex groups, in every muscle motion mode") {
  if (!ext::requireTool(ext::onPath("blender"), "blender (Debian package blender)")) return;
  test::TempDir dir;
  std::vector<std::string> inputs = test::sampleAndAssetPaths();
  std::vector<GltfWeights> weights(inputs.size(), GltfWeights::kMilli);
  std::vector<MuscleMotion> motions(inputs.size(), MuscleMotion::kRuntime);
  // The sample once more with --gltf-weights unorm16, and with its muscles sampled into the clips
  // (--muscle-motion sampled and both, the modes a player without the runtime plays).
  inputs.push_back(inputs.front());
  weights.push_back(GltfWeights::kUnorm16);
  motions.push_back(MuscleMotion::kRuntime);
  for (MuscleMotion motion : {MuscleMotion::kSampled, MuscleMotion::kBoth}) {
    inputs.push_back(inputs.front());
    weights.push_back(GltfWeights::kMilli);
    motions.push_back(motion);
  }
  std::vector<std::string> baked_paths;
  std::vector<std::vector<std::string>> expected_bones;
  for (size_t i = 0; i < inputs.size(); ++i) {
    test::Resolved r = test::resolveShipped(inputs[i]);
    LoadedCharacter loaded = loadCharacter(inputs[i]);
    MuscleSet muscles = placeMuscles(loaded.character, r.landmarks, test::gowPreset(), Sides::kBoth);
    BakeOptions options;
    options.influences = 7;
    options.gltf_weights = weights[i];
    options.motion = motions[i];
    BakeResult bake = bakeCharacter(loaded.character, muscles, options);
    std::string out = dir / ("baked" + std::to_string(i) + ".glb");
    writeGltf(bakedModel(*loaded.document, loaded.character, bake), out);
    baked_paths.push_back(out);
    std::vector<std::string> bones;
    for (const MusclePart& part : muscles.parts) bones.push_back(muscleJointName(part, MuscleJointRole::kSkinned));
    expected_bones.push_back(bones);
  }
  std::string script = dir / "inspect.py";
  std::ofstream(script) << R"PY(import sys, json
import numpy
# Debian's Blender 3.4 glTF importer still uses numpy.bool and friends, which numpy 1.24 removed.
for name, alias in (("bool", bool), ("int", int), ("float", float), ("object", object)):
    if name not in numpy.__dict__:
        setattr(numpy, name, alias)
import bpy
for path in sys.argv[sys.argv.index("--") + 1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    bones = sorted({b.name for o in bpy.data.objects if o.type == "ARMATURE" for b in o.data.bones})
    meshes = [{"name": o.name, "groups": sorted(g.name for g in o.vertex_groups),
               "skinned": any(m.type == "ARMATURE" for m in o.modifiers)}
              for o in bpy.data.objects if o.type == "MESH"]
    print("RIGBAKE_BLENDER " + json.dumps({"path": path, "bones": bones, "meshes": meshes}))
)PY";
  std::string command = "blender --background --factory-startup --python-exit-code 1 --python " + ext::shellQuote(script) + " --";
  for (const std::string& path : baked_paths) command += " " + ext::shellQuote(path);
  ext::CommandResult run = ext::runCommand(command + " 2>&1");
  INFO(run.output.substr(0, 4000));
  REQUIRE(run.exit_code == 0);
  size_t at = 0;
  for (size_t i = 0; i < baked_paths.size(); ++i) {
    INFO(inputs[i]);
    at = run.output.find("RIGBAKE_BLENDER ", at);
    REQUIRE(at != std::string::npos);
    size_t end = run.output.find('\n', at);
    nlohmann::json report = nlohmann::json::parse(run.output.substr(at + 16, end - at - 16));
    at = end;
    CHECK(report["path"] == baked_paths[i]);
    std::vector<std::string> bones = report["bones"].get<std::vector<std::string>>();
    int skinned_meshes = 0;
    for (const std::string& bone : expected_bones[i]) {
      INFO(bone);
      CHECK(std::find(bones.begin(), bones.end(), bone) != bones.end());
    }
    for (const nlohmann::json& mesh : report["meshes"]) {
      if (!mesh["skinned"].get<bool>()) continue;
      ++skinned_meshes;
      std::vector<std::string> groups = mesh["groups"].get<std::vector<std::string>>();
      for (const std::string& bone : expected_bones[i]) {
        INFO(mesh["name"] << " " << bone);
        CHECK(std::find(groups.begin(), groups.end(), bone) != groups.end());
      }
    }
    CHECK(skinned_meshes > 0);
  }
}
