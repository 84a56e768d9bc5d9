// `rigbake sample`: writes the procedural mannequin (sample/sample_character.h) as GLB, glTF or VRM.
#include <iostream>
#include <memory>

#include "cli/common.h"
#include "cli/commands.h"
#include "formats/sample_gltf.h"
#include "sample/sample_character.h"

namespace rigbake::cli {

namespace {

struct SampleCommandOptions {
  std::string output;
  int vertices = SampleOptions{}.target_vertices;
  int vrm = -1;  // -1: plain glTF, 0: VRM 0.x, 1: VRM 1.0
  bool no_upper_chest = false;
};

int runSample(const SampleCommandOptions& options) {
  checkOutputOptions({{"-o", options.output, true}});
  SampleOptions sample;
  sample.target_vertices = options.vertices;
  sample.vrm = options.vrm == 0 ? SampleVrm::kVrm0 : options.vrm == 1 ? SampleVrm::kVrm1 : SampleVrm::kNone;
  sample.upper_chest = !options.no_upper_chest;
  SampleCharacter character = makeSampleCharacter(sample);
  writeSampleGltf(character, options.output);
  std::cout << "wrote " << options.output << ": " << character.joints.size() << " joints, "
            << character.mesh.positions.size() << " vertices, " << character.mesh.triangles.size() << " triangles, "
            << character.clips.size() << " clips\n";
  return 0;
}

}  // namespace

void addSampleCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<SampleCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "sample",
      "Write a procedural skinned humanoid to test the pipeline with: a closed-surface mannequin 1.8 m tall, in "
      "metres, Y-up, facing +Z with its left at +X (VRM 0.x: facing -Z, as that spec requires), arms in a T-pose, "
      "feet on y = 0. Its 30 joints carry the God of War Ragnarok animation-skeleton names (JOPelvis1, JOBack1-3, "
      "JONeck1, JOHead1, JOLeftClavicle1, JOLeftAcromion1, JOLeftScapula1, JOLeftUpperArm1, LeftUpperArm1Twist0, "
      "JOLeftLowerArm1, LeftLowerArm1Twist0, JOLeftHand1, JOLeftUpLeg1, JOLeftLeg1, JOLeftFoot1, JOLeftToe1 and "
      "the Right twins); the spine lies on x = 0, z = 0 and the body is an exact mirror image across x = 0. Three "
      "2 s clips at 30 keys/s, linear: ElbowFlexion (to 130 degrees), ArmRaise (abduction 10 to 170 degrees with "
      "clavicle elevation) and ForearmTwist (+-80 degrees over the forearm and its roll bone). The same input "
      "always gives the same bytes.");
  command->add_option("-o,--output", options->output,
                      "Output file: .glb or .vrm writes binary glTF, anything else (.gltf) JSON glTF with the buffer "
                      "embedded")
      ->required();
  command
      ->add_option("--vertices", options->vertices,
                   "Wanted vertex count of the body mesh; the result is within a few percent of it")
      ->check(CLI::Range(kMinSampleVertices, kMaxSampleVertices))
      ->capture_default_str();
  command
      ->add_option("--vrm", options->vrm,
                   "Emit a VRM avatar instead: 0 for VRM 0.x (extension \"VRM\"), 1 for VRM 1.0 (\"VRMC_vrm\"). "
                   "Joints are then named bone_00, bone_01, ... so that only the extension's humanoid bone map "
                   "says what they are. Use a .vrm output name.")
      ->check(CLI::IsMember({0, 1}));
  command
      ->add_flag("--no-upper-chest", options->no_upper_chest,
                 "With --vrm: leave upperChest out of the humanoid bone map (the joint stays in the skeleton, "
                 "unmapped), as many VRM 0.x exports do: the map then has spine, chest and neck only")
      ->needs("--vrm");
  command->callback([runner, options]() { *runner = [options]() { return runSample(*options); }; });
}

}  // namespace rigbake::cli
