// The checks of `rigbake validate` on real bakes: every error check passes on the sample and every
// shared asset with the measured numbers the bake promises, and each kind of corruption makes exactly
// the check for it fail, naming where.
#include "pipeline/checks.h"

#include <tiny_gltf.h>

#include <limits>

#include "core/error.h"
#include "formats/validate_config.h"
#include "pipeline/muscle_joint.h"
#include "validate_fixture.h"

using namespace rigbake;
using rigbake::test::checkOf;

namespace {

Report validate(const ValidationInputs& inputs, const ValidationConfig& config = {}) {
  return validateBakedCharacter(inputs, config);
}

bool anyFindingAt(const CheckResult& check, const std::string& location_prefix) {
  for (const CheckFinding& finding : check.findings) {
    if (finding.location.rfind(location_prefix, 0) == 0) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("checks: every error-severity check passes on the sample and every shared asset, with real numbers", "[shared:validated-bakes]") {
  for (const auto& baked : test::validatedBakes()) {
    INFO(baked->source);
    const Report report = validate(baked->inputs());
    for (const CheckResult& check : report.checks) {
      INFO(check.code << ": " << check.message << " at " << check.location);
      if (check.severity == Severity::kError) CHECK(check.status != CheckStatus::kFail);
    }
    CHECK(report.passed());
    REQUIRE(report.checks.size() == checkDefinitions().size());

    CHECK(checkOf(report, "LANDMARKS_RESOLVED").status == CheckStatus::kPass);

    const CheckResult& sum = checkOf(report, "WEIGHTS_SUM");
    REQUIRE(sum.has_measured);
    CHECK(sum.measured <= 0.001);
    // UNSIGNED_SHORT weights summing to 65535 exactly: only float rounding is left.
    CHECK(sum.measured < 1e-6);

    const CheckResult& negative = checkOf(report, "WEIGHTS_NON_NEGATIVE");
    REQUIRE(negative.has_measured);
    CHECK(negative.measured == 0.0);  // zero-weight slots exist at 10 influences

    CHECK(checkOf(report, "JOINT_INDEX_IN_RANGE").measured == 0.0);
    CHECK(checkOf(report, "JOINT_INDEX_IN_RANGE").status == CheckStatus::kPass);

    const CheckResult& count = checkOf(report, "INFLUENCE_COUNT");
    CHECK(count.measured >= 1.0);
    CHECK(count.measured <= 10.0);
    CHECK(report.influences == 10);

    // The measured margin is the smallest distance of any ratio sample to its band edge, and the
    // status follows it. Some clips of the shared assets (RobotExpressive's Punch, the Quaternius
    // Cyberpunk character) drive muscles past their clamp: a warning, the skinned joint saturates as
    // the talk's clamp intends. On the sample every sample is inside.
    const CheckResult& ratio = checkOf(report, "MUSCLE_RATIO_IN_RANGE");
    REQUIRE(ratio.has_measured);
    CHECK(ratio.severity == Severity::kWarning);
    REQUIRE(report.ratios.size() == static_cast<size_t>(std::max(baked->clip_count, 1)));
    double margin = std::numeric_limits<double>::max();
    int outside = 0;
    for (const ClipRatios& clip : report.ratios) {
      REQUIRE(clip.muscles.size() == baked->muscles.parts.size());
      for (const MuscleRatioSeries& series : clip.muscles) {
        REQUIRE(series.ratio.size() == clip.times.size());
        for (double r : series.ratio) {
          margin = std::min({margin, r - series.compression, series.stretch - r});
          outside += r < series.compression || r > series.stretch;
        }
      }
    }
    CHECK(ratio.measured == margin);
    CHECK(ratio.status == (outside == 0 ? CheckStatus::kPass : CheckStatus::kFail));
    if (baked.get() == &test::validatedSample()) {
      CHECK(outside == 0);
      CHECK(ratio.measured >= 0.0);
      CHECK(ratio.measured < 0.5);  // a real margin: the clips do move the muscles
    }

    const CheckResult& surface = checkOf(report, "LOCATOR_NEAR_SURFACE");
    REQUIRE(surface.status == CheckStatus::kPass);
    CHECK(surface.measured > 0.0);  // locators sit inside the body, some distance below the skin
    CHECK(surface.measured < 0.1);

    const CheckResult& deformation = checkOf(report, "PACKED_DEFORMATION_ERROR");
    REQUIRE(deformation.status == CheckStatus::kPass);
    CHECK(deformation.measured < 0.0005);
    REQUIRE(report.deformation.size() == static_cast<size_t>(std::max(baked->clip_count, 1)));

    CHECK(checkOf(report, "GLTF_STRUCTURE").measured == 0.0);
    CHECK(checkOf(report, "KHRONOS_VALIDATOR").status == CheckStatus::kSkipped);

    // Plot data covers the whole character.
    std::int64_t histogram_total = 0;
    for (std::int64_t n : report.influence_histogram) histogram_total += n;
    CHECK(histogram_total == report.vertices);
    CHECK(report.influence_histogram.size() == 13);  // 12 slots (3 sets of 4) + none
    CHECK(report.memory.size() == skinMemoryTable(0).size());
    CHECK(!report.figure.front.runs.empty());
    CHECK(!report.figure.side.runs.empty());
    CHECK(report.figure.muscles.size() == baked->muscles.parts.size());
    CHECK(!report.figure.bones.empty());
  }
}

TEST_CASE("checks: the ratio series are evaluateMuscle() at each clip's key times", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  const Character& character = sample.loaded.character;
  REQUIRE(!character.clips.empty());
  std::vector<ClipRatios> ratios = muscleRatiosOverClips(character, sample.muscles);
  const Clip& clip = character.clips.back();
  const ClipRatios& series = ratios.back();
  REQUIRE(series.times == sampleTimes(clip, 0.0));
  const size_t t = series.times.size() / 2;
  const Pose pose = sampleClip(character.skeleton, clip, series.times[t]);
  CHECK(series.muscles[3].ratio[t] == evaluateMuscle(sample.muscles.parts[3], character.skeleton, pose).ratio);
  // The clips really move the muscles: some ratio leaves rest by more than 1%.
  double furthest = 0.0;
  for (const ClipRatios& c : ratios) {
    for (const MuscleRatioSeries& m : c.muscles) {
      for (double r : m.ratio) furthest = std::max(furthest, std::abs(r - 1.0));
    }
  }
  CHECK(furthest > 0.01);
}

TEST_CASE("checks: a locator 1 m off the body fails LOCATOR_NEAR_SURFACE at that locator", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  MuscleSet moved = sample.muscles;
  moved.parts[2].insertion.world += sample.landmarks.body.forward * 1.0;
  ValidationInputs inputs = sample.inputs();
  inputs.muscles = &moved;
  const Report report = validate(inputs);
  const CheckResult& surface = checkOf(report, "LOCATOR_NEAR_SURFACE");
  CHECK(surface.status == CheckStatus::kFail);
  CHECK(surface.location == moved.parts[2].fullName() + "/insertion");
  // About 1 m minus the body's depth in front of the locator, in units of a ~1.8 m body.
  CHECK(surface.measured * sample.landmarks.body.height > 0.8);
  CHECK(surface.measured * sample.landmarks.body.height < 1.0);
  CHECK(!report.passed());
  // The mirror twin no longer matches either (a warning), and the figure marks the muscle.
  CHECK(checkOf(report, "LOCATOR_SYMMETRY").status == CheckStatus::kFail);
  for (const FigureMuscle& m : report.figure.muscles) {
    if (m.name == moved.parts[2].fullName()) CHECK(m.flagged);
  }
  // Everything unrelated still passes.
  CHECK(checkOf(report, "WEIGHTS_SUM").status == CheckStatus::kPass);
}

TEST_CASE("checks: an asymmetric locator is a LOCATOR_SYMMETRY warning, which does not fail the report", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  MuscleSet moved = sample.muscles;
  const double height = sample.landmarks.body.height;
  int right = -1;
  for (size_t m = 0; m < moved.parts.size() && right < 0; ++m) {
    if (moved.parts[m].side == "Right") right = static_cast<int>(m);
  }
  REQUIRE(right >= 0);
  moved.parts[right].origin.world += sample.landmarks.body.up * (0.05 * height);
  ValidationInputs inputs = sample.inputs();
  inputs.muscles = &moved;
  const Report report = validate(inputs);
  const CheckResult& symmetry = checkOf(report, "LOCATOR_SYMMETRY");
  CHECK(symmetry.status == CheckStatus::kFail);
  CHECK(symmetry.severity == Severity::kWarning);
  CHECK(symmetry.location == moved.parts[right].fullName() + "/origin");
  CHECK(symmetry.measured == Approx(0.05).margin(0.01));
  CHECK(report.passed());

  // The untouched bake is symmetric to well within the default threshold.
  const Report good = validate(sample.inputs());
  CHECK(checkOf(good, "LOCATOR_SYMMETRY").status == CheckStatus::kPass);
  CHECK(checkOf(good, "LOCATOR_SYMMETRY").measured < 0.005);
}

TEST_CASE("checks: a muscle band narrower than the motion fails MUSCLE_RATIO_IN_RANGE", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  MuscleSet narrow = sample.muscles;
  for (MusclePart& part : narrow.parts) {
    part.compression = 0.999;
    part.stretch = 1.001;
  }
  ValidationInputs inputs = sample.inputs();
  inputs.muscles = &narrow;
  const Report report = validate(inputs);
  const CheckResult& ratio = checkOf(report, "MUSCLE_RATIO_IN_RANGE");
  CHECK(ratio.status == CheckStatus::kFail);
  CHECK(ratio.measured < -0.005);
  CHECK(ratio.location.find(" @ ") != std::string::npos);
  CHECK(report.passed());  // a warning by default
  ValidationConfig strict;
  strict.severity["MUSCLE_RATIO_IN_RANGE"] = Severity::kError;
  CHECK(!validate(inputs, strict).passed());
}

TEST_CASE("checks: corrupted weights and indices fail the glTF skinning checks, naming the accessor", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  REQUIRE(!sample.file.skins.empty());
  const int slots = sample.file.skins[0].slots;

  SECTION("a vertex whose weights sum to 1.1") {
    BakedFileData file = sample.file;
    file.skins[0].weights[7 * slots] += 0.1;
    ValidationInputs inputs = sample.inputs();
    inputs.file = &file;
    const CheckResult check = checkWeightsSum(inputs, {});
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.measured == Approx(0.1).epsilon(1e-6));
    CHECK(check.location == file.skins[0].pointer + "/attributes/WEIGHTS_0");
    CHECK(check.findings.front().message.find("vertex 7 ") != std::string::npos);
  }
  SECTION("a negative weight") {
    BakedFileData file = sample.file;
    file.skins[0].weights[3 * slots + 1] = -0.25;
    ValidationInputs inputs = sample.inputs();
    inputs.file = &file;
    const CheckResult check = checkWeightsNonNegative(inputs, {});
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.measured == -0.25);
  }
  SECTION("a joint index past the skin, in JOINTS_n and in the packed records") {
    BakedFileData file = sample.file;
    FileSkinAttributes& skin = file.skins[0];
    skin.joints[5 * slots + 2] = skin.skin_joint_count + 3;
    REQUIRE(skin.has_packed);
    skin.packed.indices[0] = static_cast<std::uint8_t>(skin.skin_joint_count);
    REQUIRE(skin.packed.index_bytes == 1);
    ValidationInputs inputs = sample.inputs();
    inputs.file = &file;
    const CheckResult check = checkJointIndexInRange(inputs, {});
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.measured == 1.0);
    CHECK(anyFindingAt(check, skin.pointer + "/attributes/JOINTS_0"));
    CHECK(anyFindingAt(check, skin.pointer + "/attributes/_RIGBAKE_PACKED_JOINTS_0"));
  }
  SECTION("more influences than the configured budget") {
    ValidationInputs inputs = sample.inputs();
    ValidationConfig config;
    config.threshold["INFLUENCE_COUNT"] = 1;
    const CheckResult check = checkInfluenceCount(inputs, config);
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.threshold == 1.0);
    CHECK(check.measured > 1.0);
  }
}

TEST_CASE("checks: packed weights that disagree with WEIGHTS_n fail PACKED_DEFORMATION_ERROR", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  BakedFileData file = sample.file;
  FileSkinAttributes& skin = file.skins[0];
  REQUIRE(skin.has_packed);
  // Every vertex's largest influence re-pointed at skin joint 0: vertices on animated limbs then stay
  // behind while the standard weights move them.
  const int stride = packedIndexStride(skin.packed.influences, skin.packed.index_bytes);
  for (int v = 0; v < skin.packed.vertex_count; ++v) skin.packed.indices[static_cast<size_t>(v) * stride] = 0;
  ValidationInputs inputs = sample.inputs();
  inputs.file = &file;
  const Report report = validate(inputs);
  const CheckResult& check = checkOf(report, "PACKED_DEFORMATION_ERROR");
  CHECK(check.status == CheckStatus::kFail);
  CHECK(check.measured > 0.01);  // centimetres, not rounding
  CHECK(!report.passed());

  const Report good = validate(sample.inputs());
  CHECK(checkOf(good, "PACKED_DEFORMATION_ERROR").measured < 1e-4);
}

TEST_CASE("checks: GLTF_STRUCTURE names muscles missing from the bake and clips that do not animate them", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  SECTION("a muscle file with a muscle the bake lacks") {
    MuscleSet more = sample.muscles;
    more.parts.push_back(more.parts.front());
    more.parts.back().name = "Extra";
    ValidationInputs inputs = sample.inputs();
    inputs.muscles = &more;
    const CheckResult check = checkGltfStructure(inputs, {});
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.measured == 1.0);  // its skinned joint (helpers are optional)
    CHECK(check.findings.front().message.find(more.parts.back().fullName()) != std::string::npos);
  }
  SECTION("an animation without the scale channel of a skinned muscle joint") {
    LoadedCharacter loaded = loadCharacter(sample.glb);
    tinygltf::Model& model = modelOf(*loaded.document);
    REQUIRE(!model.animations.empty());
    auto& channels = model.animations[0].channels;
    auto scale = std::find_if(channels.begin(), channels.end(), [&](const tinygltf::AnimationChannel& c) {
      return c.target_path == "scale" && model.nodes[c.target_node].name.find("_muscleSkinned") != std::string::npos;
    });
    REQUIRE(scale != channels.end());
    const std::string node = model.nodes[scale->target_node].name;
    channels.erase(scale);
    const BakedFileData file = readBakedFileData(loaded);
    ValidationInputs inputs = sample.inputs();
    inputs.file = &file;
    const CheckResult check = checkGltfStructure(inputs, {});
    CHECK(check.status == CheckStatus::kFail);
    CHECK(check.measured == 1.0);
    CHECK(check.location == "/animations/0/channels");
    CHECK(check.findings.front().message == "no scale channel for " + node);
  }
}

TEST_CASE("checks: without a muscle file or landmarks the dependent checks are skipped with a reason", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  ValidationInputs inputs = sample.inputs();
  inputs.muscles = nullptr;
  Report report = validate(inputs);
  for (const char* code : {"LOCATOR_SYMMETRY", "LOCATOR_NEAR_SURFACE", "MUSCLE_RATIO_IN_RANGE"}) {
    INFO(code);
    CHECK(checkOf(report, code).status == CheckStatus::kSkipped);
    // In the report's words; `rigbake validate` names the flag on stderr (cli validate's case).
    CHECK(checkOf(report, code).message == kNoMuscleFile);
  }
  CHECK(report.passed());
  CHECK(report.ratios.empty());
  CHECK(checkOf(report, "WEIGHTS_SUM").status == CheckStatus::kPass);

  inputs.landmarks = nullptr;
  inputs.landmark_problem = "LANDMARK_UNRESOLVED x.glb: landmark 'pelvis' matches no joint";
  report = validate(inputs);
  CHECK(checkOf(report, "LANDMARKS_RESOLVED").status == CheckStatus::kFail);
  CHECK(checkOf(report, "LANDMARKS_RESOLVED").message.rfind(inputs.landmark_problem, 0) == 0);
  CHECK(!report.passed());
}

TEST_CASE("checks: a config file changes thresholds and severities, and rejects unknown codes and keys", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  test::TempDir dir;
  const std::string path = dir / "config.json";
  std::ofstream(path) << R"({"checks": {"LOCATOR_NEAR_SURFACE": {"threshold": 0.001},
                                        "WEIGHTS_SUM": {"severity": "warning", "threshold": 0.0}}})";
  const ValidationConfig config = readValidationConfig(path);
  Report report = validate(sample.inputs(), config);
  CHECK(checkOf(report, "LOCATOR_NEAR_SURFACE").threshold == 0.001);
  CHECK(checkOf(report, "LOCATOR_NEAR_SURFACE").status == CheckStatus::kFail);
  CHECK(checkOf(report, "WEIGHTS_SUM").severity == Severity::kWarning);
  CHECK(!report.passed());

  std::ofstream(path) << R"({"checks": {"LOCATOR_NEAR_SURFACE": {"severity": "info", "threshold": 0.001}}})";
  report = validate(sample.inputs(), readValidationConfig(path));
  CHECK(checkOf(report, "LOCATOR_NEAR_SURFACE").status == CheckStatus::kFail);
  CHECK(report.passed());  // an info finding does not fail the report

  auto codeOf = [&](const std::string& text) {
    std::ofstream(path) << text;
    try {
      readValidationConfig(path);
    } catch (const Error& e) {
      return e.code() + " " + e.where();
    }
    return std::string("accepted");
  };
  CHECK(codeOf(R"({"checks": {"LOCATOR_NEAR_SURFAC": {"threshold": 1}}})") ==
        "VALIDATE_CONFIG_INVALID " + path + "#/checks/LOCATOR_NEAR_SURFAC");
  CHECK(codeOf(R"({"checks": {"WEIGHTS_SUM": {"treshold": 1}}})") ==
        "VALIDATE_CONFIG_INVALID " + path + "#/checks/WEIGHTS_SUM/treshold");
  CHECK(codeOf(R"({"checks": {"WEIGHTS_SUM": {"severity": "fatal"}}})") ==
        "VALIDATE_CONFIG_INVALID " + path + "#/checks/WEIGHTS_SUM/severity");
  CHECK(codeOf(R"({"check": {}})") == "VALIDATE_CONFIG_INVALID " + path + "#/check");
  CHECK(codeOf(R"({"checks": {"WEIGHTS_SUM": {"threshold": "0.1"}}})") ==
        "VALIDATE_CONFIG_INVALID " + path + "#/checks/WEIGHTS_SUM/threshold");
}

TEST_CASE("checks: the body figure's silhouettes span the body height, and bones exclude muscle joints", "[shared:validated-bakes]") {
  const test::ValidatedBake& sample = test::validatedSample();
  const Figure figure = bodyFigure(sample.loaded.character, sample.landmarks, &sample.muscles);
  for (const Silhouette* s : {&figure.front, &figure.side}) {
    REQUIRE(s->rows > 0);
    int lowest = s->rows, highest = -1;
    for (const auto& run : s->runs) {
      lowest = std::min(lowest, run[0]);
      highest = std::max(highest, run[0]);
      CHECK(run[1] < run[2]);
    }
    CHECK((highest - lowest + 1) * s->cell == Approx(sample.landmarks.body.height).epsilon(0.03));
  }
  // The front silhouette of a T/A-posed body is wider than its side silhouette is deep.
  CHECK(figure.front.columns > figure.side.columns);
  for (const FigureMuscle& m : figure.muscles) CHECK(!m.flagged);
  CHECK(figure.landmarks.size() >= 20);
}
