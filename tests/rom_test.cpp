// Range-of-motion clips (pipeline/rom.h): they reproduce the mannequin's own clips, they validate, and
// read back from the written file every clip's joints turn by the stated angle about the stated axis.
#include "pipeline/rom.h"

#include <tiny_gltf.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "external_tools.h"
#include "formats/gltf_bake.h"
#include "formats/gltf_clips.h"
#include "formats/gltf_write.h"
#include "formats/rom_json.h"
#include "glb_support.h"
#include "pipeline/bake.h"
#include "pipeline/pose.h"
#include "sample/sample_character.h"

using namespace rigbake;

namespace {

constexpr double kTestPi = 3.14159265358979323846;
constexpr double kTestDegree = kTestPi / 180.0;

const RomPreset& defaultRom() {
  static const RomPreset preset = readRomPreset(test::presetsDir() + "/rom/default.json");
  return preset;
}

double angleOf(const Eigen::Quaterniond& q) { return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w())); }

Eigen::Quaterniond rotationOfWorld(const Eigen::Affine3d& m) { return decomposeTrs(m).rotation; }

const Clip* romClipNamed(const Character& character, const std::string& name) {
  for (const Clip& clip : character.clips) {
    if (clip.name == name) return &clip;
  }
  return nullptr;
}

struct WrittenRom {
  std::string path;
  RomResult rom;       // as built on the input
  Character original;  // the input as loaded
};

// Builds the default ROM on `input` and writes it the way `rigbake rom` does.
WrittenRom writeRom(const std::string& input, const std::string& output) {
  LoadedCharacter loaded = loadCharacter(input);
  test::Resolved resolved = test::resolveWithShippedPresets(loaded.character);
  WrittenRom written;
  written.path = output;
  written.rom = buildRom(resolved.character, resolved.landmarks, defaultRom());
  std::vector<Clip> clips;
  for (const RomClip& clip : written.rom.clips) clips.push_back(clip.clip);
  writeGltf(modelWithClips(*loaded.document, resolved.character, clips), output);
  written.original = std::move(resolved.character);
  return written;
}

// The body frame as the joint of landmark `frame` carries it from bind to rest, recomputed here from
// the file's own landmarks, and a named body direction in it.
Eigen::Vector3d bodyDirection(const test::Resolved& r, const Pose& rest, const std::string& frame,
                              const std::string& name, const std::string& side) {
  const int joint = r.landmarks.get(frame).joint;
  const Eigen::Quaterniond carry =
      rotationOfWorld(rest.world[joint]) * rotationOfWorld(r.character.skeleton.bind_world[joint]).conjugate();
  const BodyFrame& body = r.landmarks.body;
  const double toward_side = side == "r" ? -1.0 : 1.0;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  if (name == "up") v = body.up;
  if (name == "down") v = -body.up;
  if (name == "forward") v = body.forward;
  if (name == "back") v = -body.forward;
  if (name == "lateral") v = toward_side * body.lateral;
  if (name == "medial") v = -toward_side * body.lateral;
  return carry * v;
}

std::string sidedFor(const std::string& base, const std::string& side) {
  return side.empty() ? base : sidedName(base, side);
}

// Bone direction from landmark a towards landmark b in `pose`: b's bind offset carried by a's joint.
Eigen::Vector3d segmentIn(const test::Resolved& r, const Pose& pose, const std::string& a, const std::string& b) {
  const Landmark& from = r.landmarks.get(a);
  const Landmark& to = r.landmarks.get(b);
  const Eigen::Affine3d carry = pose.world[from.joint] * r.character.skeleton.bind_world[from.joint].inverse();
  return carry * to.position - carry * from.position;
}

// The motion's angle in `pose`, measured as docs/rom.md defines it, about `axis`.
double measuredAngle(const test::Resolved& r, const Pose& pose, const Pose& rest, const RomClipSpec& spec,
                     const std::string& side, const Eigen::Vector3d& axis) {
  const RomMotion& motion = spec.motion;
  const std::vector<std::string>& l = motion.landmarks;
  if (motion.kind == RomMotionKind::kHinge) {
    const Eigen::Vector3d upper = segmentIn(r, pose, sidedFor(l[0], side), sidedFor(l[1], side));
    const Eigen::Vector3d lower = segmentIn(r, pose, sidedFor(l[1], side), sidedFor(l[2], side));
    const Eigen::Vector3d across = upper - axis * upper.dot(axis);
    return std::atan2(across.cross(lower).dot(axis), across.dot(lower)) / kTestDegree;
  }
  const Eigen::Vector3d segment = segmentIn(r, pose, sidedFor(l[0], side), sidedFor(l[1], side));
  const Eigen::Vector3d from = bodyDirection(r, rest, spec.frame, motion.from, side.empty() ? "l" : side);
  return std::atan2(segment.dot(axis.cross(from)), segment.dot(from)) / kTestDegree;
}

// Reads the written file back with the loader, re-resolves its landmarks, samples every ROM clip at its
// start and its peaks with pipeline/pose, and checks each keyed joint's world turn against the axis
// and angle the preset states (0.1 degree), the axis against one recomputed here from the landmarks
// and the body frame, and measured motions' absolute angles.
void checkWrittenPeaks(const WrittenRom& written) {
  const test::Resolved back = test::resolveShipped(written.path);
  const Skeleton& skeleton = back.character.skeleton;
  const Pose rest = restPose(skeleton);
  for (const RomClip& clip : written.rom.clips) {
    INFO(written.path << " clip " << clip.clip.name);
    const Clip* read = romClipNamed(back.character, clip.clip.name);
    REQUIRE(read);
    REQUIRE(read->tracks.size() == clip.clip.tracks.size());
    const RomClipSpec& spec = *clip.spec;
    const double start_angle = romAngleAt(spec, 0.0);
    std::vector<std::pair<double, double>> peaks = {{clip.peak_time, spec.to_deg}};
    if (spec.curve == RomCurve::kSwing) peaks.push_back({clip.low_time, spec.from_deg});
    const Pose start = sampleClip(skeleton, *read, 0.0);
    for (const RomSweep& sweep : clip.sweeps) {
      INFO("side '" << sweep.side << "'");
      const std::string dir_side = sweep.side.empty() ? "l" : sweep.side;
      // The axis, from what the preset says and the file's landmarks.
      Eigen::Vector3d axis = sweep.axis;
      const RomMotion& motion = spec.motion;
      if (motion.kind == RomMotionKind::kBodyAxis) {
        axis = bodyDirection(back, rest, sidedFor(spec.frame, sweep.side), motion.from, dir_side)
                   .cross(bodyDirection(back, rest, sidedFor(spec.frame, sweep.side), motion.towards.front(), dir_side))
                   .normalized();
      } else if (motion.kind == RomMotionKind::kTwist) {
        axis = (sweep.side == "r" ? -1.0 : 1.0) * segmentIn(back, rest, sidedFor(motion.landmarks[0], sweep.side),
                                                            sidedFor(motion.landmarks[1], sweep.side))
                                                      .normalized();
      } else {
        // A hinge's axis is square to the bending bone at rest.
        const Eigen::Vector3d lower =
            segmentIn(back, rest, sidedFor(motion.landmarks[1], sweep.side), sidedFor(motion.landmarks[2], sweep.side));
        CHECK(std::abs(axis.dot(lower.normalized())) < 1e-6);
      }
      CHECK(std::acos(std::min(1.0, axis.dot(sweep.axis))) / kTestDegree < 0.01);
      if (motion.measured)
        CHECK(std::abs(measuredAngle(back, start, rest, spec, sweep.side, axis) - start_angle) < 0.1);
      for (const auto& [time, angle] : peaks) {
        INFO("at " << time << " s, " << angle << " degrees");
        const Pose peak = sampleClip(skeleton, *read, time);
        for (const RomKeyedJoint& keyed : sweep.joints) {
          if (keyed.follower) continue;
          INFO("joint " << skeleton.names[keyed.joint] << " share " << keyed.share);
          const Eigen::Quaterniond turned =
              rotationOfWorld(peak.world[keyed.joint]) * rotationOfWorld(start.world[keyed.joint]).conjugate();
          const Eigen::Quaterniond stated(Eigen::AngleAxisd(keyed.share * (angle - start_angle) * kTestDegree, axis));
          CHECK(angleOf(turned * stated.conjugate()) / kTestDegree < 0.1);
        }
        if (motion.measured) CHECK(std::abs(measuredAngle(back, peak, rest, spec, sweep.side, axis) - angle) < 0.1);
        // A hinge that rests straight bends towards its first `towards` direction: the forearm to the
        // front of the body, the shin to the back.
        if (motion.kind == RomMotionKind::kHinge && std::abs(sweep.zero_deg) < 10.0) {
          const Eigen::Vector3d lower = segmentIn(back, peak, sidedFor(motion.landmarks[1], sweep.side),
                                                  sidedFor(motion.landmarks[2], sweep.side));
          const Eigen::Vector3d towards = bodyDirection(back, rest, spec.frame, motion.towards.front(), dir_side);
          CHECK(lower.normalized().dot(towards) > 0.5);
        }
      }
    }
  }
}

}  // namespace

TEST_CASE("the ROM preset parses: ten clips, mirrored limbs and central trunk clips") {
  const RomPreset& preset = defaultRom();
  REQUIRE(preset.clips.size() == 10);
  CHECK(preset.animation_prefix == "rom_");
  CHECK(preset.keys_per_second == 30.0);
  for (const RomClipSpec& spec : preset.clips) {
    const bool trunk = spec.name.rfind("spine", 0) == 0 || spec.name.rfind("neck", 0) == 0;
    CHECK(spec.sided == !trunk);
  }
}

TEST_CASE("ROM presets are read strictly: unknown keys, sided names and mixed clips are errors with a pointer") {
  std::ifstream file(test::presetsDir() + "/rom/default.json");
  std::stringstream text;
  text << file.rdbuf();
  nlohmann::json preset = nlohmann::json::parse(text.str());
  auto codeOf = [](const nlohmann::json& json, std::string* where) {
    try {
      parseRomPreset(json, "rom.json");
    } catch (const Error& e) {
      *where = e.where();
      return e.code();
    }
    return std::string("none");
  };
  std::string where;
  nlohmann::json typo = preset;
  typo["clips"][1]["to_degs"] = 170;
  CHECK(codeOf(typo, &where) == "PRESET_INVALID");
  CHECK(where == "rom.json#/clips/1/to_degs");
  nlohmann::json sided = preset;
  sided["clips"][0]["joints"][0]["landmark"] = "forearm_l";
  CHECK(codeOf(sided, &where) == "PRESET_LANDMARK_UNKNOWN");
  CHECK(where == "rom.json#/clips/0/joints/0/landmark");
  nlohmann::json mixed = preset;
  mixed["clips"][4]["joints"].push_back({{"landmark", "clavicle"}});
  CHECK(codeOf(mixed, &where) == "PRESET_INVALID");
  CHECK(where == "rom.json#/clips/4");
  nlohmann::json flat = preset;
  flat["clips"][1]["motion"]["towards"] = "up";
  CHECK(codeOf(flat, &where) == "PRESET_INVALID");
  CHECK(where == "rom.json#/clips/1/motion/towards");
  nlohmann::json twin = preset;
  twin["clips"][2]["name"] = "elbow_flexion";
  CHECK(codeOf(twin, &where) == "PRESET_INVALID");
  nlohmann::json share = preset;
  share["clips"][3]["joints"][0]["share"] = 1.5;
  CHECK(codeOf(share, &where) == "PRESET_INVALID");
  CHECK(where == "rom.json#/clips/3/joints/0/share");
}

TEST_CASE("the mannequin's ROM reproduces its built-in ElbowFlexion, ArmRaise and ForearmTwist within 1e-6 rad") {
  // Plain: every track. VRM 0.x (turned to face -Z) and 1.0: every track of the joints VRM names.
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"elbow_flexion", "ElbowFlexion"}, {"shoulder_abduction", "ArmRaise"}, {"forearm_twist", "ForearmTwist"}};
  for (SampleVrm variant : {SampleVrm::kNone, SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    const test::Resolved r = test::resolveShipped(test::sampleGlbPath(variant));
    INFO("variant " << static_cast<int>(variant) << " map " << r.landmarks.map_name);
    const RomResult rom =
        buildRom(r.character, r.landmarks, defaultRom(), {"elbow_flexion", "shoulder_abduction", "forearm_twist"});
    REQUIRE(rom.clips.size() == 3);
    // The built-in clips as the character itself holds them in memory (doubles), and as the file stores
    // them (floats): joint order is the sample's, so match tracks by joint name.
    SampleOptions options;
    options.vrm = variant;
    const SampleCharacter sample = makeSampleCharacter(options);
    for (size_t c = 0; c < pairs.size(); ++c) {
      INFO(pairs[c].first << " vs " << pairs[c].second);
      const Clip& generated = rom.clips[c].clip;
      const Clip* stored = romClipNamed(r.character, pairs[c].second);
      REQUIRE(stored);
      // VRM has no roll bones, so there the twist keys the forearm and the hand only (both as the
      // mannequin keys them); the roll bone stays at rest.
      if (variant == SampleVrm::kNone || c != 2) REQUIRE(generated.tracks.size() == stored->tracks.size());
      else REQUIRE(generated.tracks.size() == stored->tracks.size() - 2);
      const SampleClip* built_in = nullptr;
      for (const SampleClip& clip : sample.clips) built_in = clip.name == pairs[c].second ? &clip : built_in;
      REQUIRE(built_in);
      double worst_stored = 0.0, worst_built_in = 0.0;
      for (const Track& track : generated.tracks) {
        const std::string& joint = r.character.skeleton.names[track.joint];
        INFO(joint);
        const Track* file_track = nullptr;
        for (const Track& t : stored->tracks) file_track = t.joint == track.joint ? &t : file_track;
        const SampleTrack* sample_track = nullptr;
        for (const SampleTrack& t : built_in->tracks)
          sample_track = sample.joints[t.joint].name == joint ? &t : sample_track;
        REQUIRE(file_track);
        REQUIRE(sample_track);
        REQUIRE(track.times.size() == file_track->times.size());
        REQUIRE(track.times.size() == sample_track->times.size());
        for (size_t k = 0; k < track.times.size(); ++k) {
          CHECK(std::abs(track.times[k] - sample_track->times[k]) < 1e-12);
          CHECK(std::abs(track.times[k] - file_track->times[k]) < 1e-6);
          const Eigen::Quaterniond mine(track.values[4 * k + 3], track.values[4 * k], track.values[4 * k + 1],
                                        track.values[4 * k + 2]);
          const Eigen::Quaterniond in_file(file_track->values[4 * k + 3], file_track->values[4 * k],
                                           file_track->values[4 * k + 1], file_track->values[4 * k + 2]);
          worst_stored = std::max(worst_stored, angleOf(mine * in_file.normalized().conjugate()));
          worst_built_in = std::max(worst_built_in, angleOf(mine * sample_track->rotations[k].conjugate()));
        }
      }
      CHECK(worst_stored < 1e-6);
      CHECK(worst_built_in < 1e-6);
    }
  }
}

TEST_CASE("the ROM of the mannequin and every shared character passes the Khronos validator, own clips kept") {
  if (!test::external::requireTool(test::external::validatorAvailable(), test::external::validatorHint())) return;
  test::external::ScratchDir scratch;
  std::vector<std::string> inputs = test::sampleAndAssetPaths();
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) inputs.push_back(test::sampleGlbPath(vrm));
  for (size_t i = 0; i < inputs.size(); ++i) {
    INFO(inputs[i]);
    const WrittenRom written = writeRom(inputs[i], scratch.file("rom" + std::to_string(i) + ".glb"));
    CHECK(written.rom.clips.size() == 10);
    CHECK(written.rom.skipped.empty());
    const test::external::ValidationSummary summary = test::external::validateWithKhronos(written.path);
    INFO(summary.raw);
    CHECK(summary.errors == 0);
    // The character's own clips come back exactly, first, in their order; the ROM clips after them.
    const Character back = loadCharacter(written.path).character;
    REQUIRE(back.clips.size() == written.original.clips.size() + 10);
    for (size_t c = 0; c < written.original.clips.size(); ++c) {
      const Clip& before = written.original.clips[c];
      const Clip& after = back.clips[c];
      CHECK(after.name == before.name);
      REQUIRE(after.tracks.size() == before.tracks.size());
      for (size_t t = 0; t < before.tracks.size(); ++t) {
        CHECK(after.tracks[t].joint == before.tracks[t].joint);
        CHECK(after.tracks[t].times == before.tracks[t].times);
        CHECK(after.tracks[t].values == before.tracks[t].values);
      }
    }
  }
}

TEST_CASE(
    "at every ROM clip's peak, read back from the written file, each keyed joint has turned by the stated angle") {
  test::external::ScratchDir scratch;
  std::vector<std::string> inputs = test::sampleAndAssetPaths();
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) inputs.push_back(test::sampleGlbPath(vrm));
  for (size_t i = 0; i < inputs.size(); ++i) {
    checkWrittenPeaks(writeRom(inputs[i], scratch.file("peaks" + std::to_string(i) + ".glb")));
  }
}

TEST_CASE("a character without legs gets the arm and trunk clips, and asking for a leg clip is ROM_CLIP_UNAVAILABLE") {
  const test::Resolved full = test::resolveShipped(test::sampleGlbPath());
  const test::Resolved legless = test::resolveWithShippedPresets(test::withoutLegs(full.character));
  const RomResult rom = buildRom(legless.character, legless.landmarks, defaultRom());
  CHECK(rom.clips.size() == 7);
  REQUIRE(rom.skipped.size() == 3);
  CHECK(rom.skipped[0].name == "hip_flexion");
  CHECK(rom.skipped[0].reason.find("upper_leg_l") != std::string::npos);
  CHECK(rom.skipped[1].name == "knee_flexion");
  CHECK(rom.skipped[2].name == "hip_abduction");
  try {
    buildRom(legless.character, legless.landmarks, defaultRom(), {"elbow_flexion", "knee_flexion"});
    FAIL("knee_flexion was built without legs");
  } catch (const Error& e) {
    CHECK(e.code() == "ROM_CLIP_UNAVAILABLE");
  }
  try {
    buildRom(legless.character, legless.landmarks, defaultRom(), {"elbow_flexion", "wrist_flexion"});
    FAIL("an unknown clip was accepted");
  } catch (const Error& e) {
    CHECK(e.code() == "ROM_CLIP_UNKNOWN");
  }
}

TEST_CASE("a ROM output cannot get the same ROM again: ROM_CLIP_EXISTS") {
  test::external::ScratchDir scratch;
  const WrittenRom written = writeRom(test::sampleGlbPath(), scratch.file("once.glb"));
  const test::Resolved back = test::resolveShipped(written.path);
  try {
    buildRom(back.character, back.landmarks, defaultRom());
    FAIL("a second ROM was built");
  } catch (const Error& e) {
    CHECK(e.code() == "ROM_CLIP_EXISTS");
  }
}

TEST_CASE("measure-only ROM clips move the bake's figures but are not written") {
  const std::string kaykit = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (kaykit.empty()) return;
  LoadedCharacter loaded = loadCharacter(kaykit);
  test::Resolved r = test::resolveWithShippedPresets(loaded.character);
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  BakeOptions options;
  options.influences = 10;
  const BakeResult plain = bakeCharacter(r.character, muscles, options);
  CHECK(plain.error.overall.max_displacement == 0.0);  // no clips: nothing moves
  appendMeasureOnlyClips(&r.character, buildRom(r.character, r.landmarks, defaultRom()));
  const BakeResult measured = bakeCharacter(r.character, muscles, options);
  REQUIRE(measured.clips.size() == 10);
  CHECK(measured.clips.front().measure_only);
  CHECK(measured.error.overall.max_displacement > 0.0);
  const tinygltf::Model model = bakedModel(*loaded.document, r.character, measured);
  CHECK(model.animations.empty());
}
