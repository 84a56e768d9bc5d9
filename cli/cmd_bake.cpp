// `rigbake bake CHAR --muscles muscles.json -o baked.glb`: muscle joints, their animation and skin
// weights into a new glTF, with the deformation error and memory figures of the chosen influence count.
#include <iomanip>
#include <sstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy/placement.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "formats/atomic_file.h"
#include "formats/gltf_bake.h"
#include "formats/gltf_write.h"
#include "formats/jiggle_json.h"
#include "formats/json_text.h"
#include "formats/muscle_json.h"
#include "formats/packed_file.h"
#include "formats/preset_json.h"
#include "formats/quality_json.h"
#include "formats/vrm_spring.h"
#include "pipeline/bake.h"
#include "pipeline/leg_coverage.h"
#include "pipeline/memory_table.h"
#include "pipeline/rom.h"

namespace rigbake::cli {
namespace {

struct BakeCommandOptions {
  std::string character;
  std::string muscles;
  std::string preset = "gow_biped";
  std::string progress = "auto";  // --progress
  std::string output;
  std::string packed_output;
  std::string stats_output;
  std::string jiggle;
  std::string hits;
  std::string rom;  // ROM preset to measure on (--rom), empty: none
  bool springs_only = false;
  std::string vrm;  // --vrm: "0", "1" or empty (as the input is)
  int influences = 4;
  std::string gltf_weights = "milli";
  std::string regions = "body";
  std::string response = "auto";
  int fit_poses = rigbake::ResponseFitOptions{}.max_poses;
  std::string muscle_motion = "runtime";
  bool helper_joints = false;
  std::string muscles_output;
  double fps = 0.0;
  int threads = 0;
  bool json = false;
  PresetOptions presets;
};

nlohmann::json errorJson(const DeformationError& error) {
  return {{"max", error.max_displacement * 1000.0}, {"rms", error.rms_displacement * 1000.0}};
}

// Where to look in the input file: the glTF mesh, primitive and vertex, and when in which clip.
nlohmann::json peakJson(const Character& character, const BakedClip& clip, const ErrorPeak& peak) {
  if (peak.vertex < 0) return nullptr;
  const MeshPart& mesh = character.meshes[peak.mesh_part];
  return {{"clip", clip.name},          {"time_s", peak.time},
          {"mesh", mesh.name},          {"gltf_mesh", mesh.gltf_mesh},
          {"primitive", mesh.gltf_primitive}, {"vertex", peak.vertex}};
}

// max, rms, worst and per_clip of one set of rounded weights.
nlohmann::json deformationJson(const Character& character, const BakeResult& bake, const DeformationFigures& figures) {
  nlohmann::json per_clip = nlohmann::json::object();
  for (size_t c = 0; c < bake.clips.size(); ++c) {
    per_clip[bake.clips[c].name] = errorJson(figures.per_clip[c]);
    per_clip[bake.clips[c].name]["worst"] = peakJson(character, bake.clips[c], figures.peaks[c]);
  }
  nlohmann::json error = errorJson(figures.overall);
  error["worst"] = figures.peak_clip < 0
                       ? nlohmann::json()
                       : peakJson(character, bake.clips[figures.peak_clip], figures.peaks[figures.peak_clip]);
  error["per_clip"] = per_clip;
  return error;
}

nlohmann::json statsJson(const BakeCommandOptions& options, const Character& character, const MuscleSet& muscles,
                         const BakeResult& bake) {
  int gltf_bytes = 0, packed_bytes = 0;
  if (!bake.parts.empty()) {
    const BakedPart& first = bake.parts.front();
    for (const VertexAttributeData& a : first.standard) gltf_bytes += static_cast<int>(a.bytes.size() / a.accessor.count);
    packed_bytes = packedSkinBytesPerVertex(bake.influences, first.packed.index_bytes);
  }
  nlohmann::json table = nlohmann::json::array();
  for (const SkinLayoutSize& layout : skinMemoryTable(bake.vertex_count)) {
    table.push_back({{"layout", layout.id},
                     {"influences", layout.influences},
                     {"bytes_per_vertex", layout.bytes_per_vertex},
                     {"total_bytes", layout.total_bytes}});
  }
  nlohmann::json stats = {
      {"character", fileNameOf(options.character)},
      {"output", fileNameOf(options.output)},
      {"units", "m"},
      {"influences", bake.influences},
      {"muscle_joints", muscles.parts.size()},
      // Nodes the file gains: each muscle's skinned joint, and its base, tip and driver with --helper-joints.
      {"joints_added", bake.helper_joints ? bake.joints.size() : muscles.parts.size()},
      {"vertices", bake.vertex_count},
      {"clips", bake.clips.size()},
      {"deformation_error_mm", deformationJson(character, bake, bake.error)},
      {"gltf_weights", gltfWeightsName(bake.gltf_weights)},
      {"bytes_per_vertex", {{"gltf", gltf_bytes}, {"packed", packed_bytes}}},
      {"bytes_total", {{"gltf", static_cast<long long>(gltf_bytes) * bake.vertex_count},
                       {"packed", static_cast<long long>(packed_bytes) * bake.vertex_count}}},
      {"memory_table", table},
  };
  if (bake.gltf_weights == GltfWeights::kUnorm16) stats["gltf_deformation_error_mm"] = deformationJson(character, bake, bake.gltf_error);
  stats["deformation_quality"] = deformationQualityJson(bake.quality);
  return stats;
}

int run(const BakeCommandOptions& options) {
  checkOutputOptions({{"-o", options.output, true},
                      {"--packed-out", options.packed_output, false},
                      {"--stats", options.stats_output, false, true},
                      {"--muscles-out", options.muscles_output, false, true}},
                     options.json);
  ProgressLine progress("rigbake bake", options.progress);
  progress.show("loading the character");
  MusclePreset preset = loadMusclePreset(options.presets, options.preset);
  LoadOptions load;
  if (!options.vrm.empty()) load.vrm = options.vrm == "1" ? VrmTarget::kVrm1 : VrmTarget::kVrm0;
  ResolvedCharacter resolved = loadAndResolve(options.character, options.presets, load);
  // --rom: the range-of-motion clips join the character's own in memory only, so the weight rounding and
  // the deformation figures see them, but the written file does not hold them (docs/rom.md).
  RomPreset rom_preset;  // outlives `rom`, whose clips point at their specs in it
  RomResult rom;
  if (!options.rom.empty()) {
    rom_preset = loadRomPreset(options.presets, options.rom);
    rom = buildRom(resolved.loaded.character, resolved.landmarks, rom_preset);
    appendMeasureOnlyClips(&resolved.loaded.character, rom);
  }
  const Character& character = resolved.loaded.character;
  progress.show(options.muscles.empty() ? "placing the muscles" : "reading the muscles");
  MuscleSet muscles = options.muscles.empty()
                          ? placeMuscles(character, resolved.landmarks, preset, Sides::kBoth)
                          : readMuscleJson(options.muscles, character, resolved.landmarks, preset);
  BakeOptions bake_options;
  bake_options.influences = options.influences;
  parseGltfWeights(options.gltf_weights, &bake_options.gltf_weights);  // CLI11 has checked the name
  bake_options.fps = options.fps;
  bake_options.threads = options.threads;
  parseResponseMode(options.response, &bake_options.response);  // CLI11 has checked the name
  bake_options.fit.max_poses = options.fit_poses;
  parseMuscleMotion(options.muscle_motion, &bake_options.motion);
  bake_options.helper_joints = options.helper_joints;
  const RegionPreset region_preset = readRegionPreset(presetFile(options.presets, "regions", options.regions));
  bake_options.regions = resolveBodyRegions(character, resolved.landmarks, region_preset);
  bake_options.creases = resolveCreases(character, resolved.landmarks, region_preset.creases);
  if (!options.jiggle.empty()) {
    bake_options.jiggles =
        resolveJiggles(readJigglePreset(presetFile(options.presets, "jiggle", options.jiggle)), character.skeleton, &resolved.landmarks, &muscles);
  } else if (!options.hits.empty()) {
    fail(errc::USAGE, "--hits", "needs --jiggle: hits kick jiggle joints");
  }
  if (!options.hits.empty()) bake_options.hits = readHits(options.hits);
  if (options.springs_only && options.jiggle.empty()) fail(errc::USAGE, "--vrm-springs-only", "needs --jiggle");
  BakeOptions baked_motion = bake_options;
  if (options.springs_only) baked_motion.jiggles.clear();
  baked_motion.progress = progress.report();
  BakeResult bake = bakeCharacter(character, muscles, baked_motion);
  progress.show("writing the files");
  nlohmann::json stats = statsJson(options, character, muscles, bake);
  if (!options.rom.empty()) stats["rom"] = romJson(rom, character.skeleton);
  const LegCoverage legs = legCoverage(character, resolved.landmarks, muscles);
  const bool legs_uncovered = legs.legs && !legs.covered && legs.largest_turn_deg > kLegTurnWorthMuscles;
  stats["legs"] = {{"found", legs.legs}, {"covered_by_muscles", legs.covered}, {"largest_turn_deg", legs.largest_turn_deg},
                   {"clip", legs.clip}, {"joint", legs.joint}};

  // Everything is computed before anything is written, so a failure leaves no output behind.
  const bool vrm_springs = !bake_options.jiggles.empty() && isVrmDocument(*resolved.loaded.document);
  if (options.springs_only && !vrm_springs)
    fail(errc::USAGE, "--vrm-springs-only", options.character + " is not a VRM, so there is nowhere to put spring bones");
  const BakedFile file = writeBakedFile(*resolved.loaded.document, character, bake, isBinaryGltfPath(options.output),
                                        vrm_springs ? bake_options.jiggles : std::vector<JiggleSetup>{});
  stats["animation_bytes"] = {{"input", file.input_animation_bytes}, {"output", file.animation_bytes},
                              {"muscle_motion", muscleMotionName(bake.motion)}};
  std::vector<PackedInfluences> packed;
  for (const BakedPart& part : bake.parts) packed.push_back(part.packed);
  // All the outputs or none: a --stats that cannot be written must not leave a new -o behind.
  OutputBatch outputs;
  outputs.add(options.output, file.bytes);
  if (!options.packed_output.empty()) outputs.add(options.packed_output, encodePackedFile(packed));
  if (!options.stats_output.empty()) outputs.add(options.stats_output, jsonText(stats) + "\n");
  if (!options.muscles_output.empty())
    outputs.add(options.muscles_output, muscleJson(bake.muscles, character.skeleton, options.preset));
  outputs.commit();

  progress.clear();
  if (options.json) std::cout << jsonText(stats) << "\n";
  std::cerr << std::fixed << std::setprecision(4) << "baked " << muscles.parts.size() << " muscles ("
            << stats["joints_added"].get<int>() << " joints added) into " << options.output << ": " << bake.influences
            << " influences/vertex, " << bake.vertex_count << " vertices, " << bake.clips.size() << " clips; ";
  // Without a clip nothing moved, so there is no deformation to state (never "max 0.0000 mm").
  if (bake.clips.empty())
    std::cerr << "no clip, so no deformation measured (--rom measures on range-of-motion clips)";
  else
    std::cerr << "deformation error max " << stats["deformation_error_mm"]["max"].get<double>() << " mm, rms "
              << stats["deformation_error_mm"]["rms"].get<double>() << " mm";
  std::cerr << "; skin data " << stats["bytes_per_vertex"]["gltf"].get<int>() << " B/vertex as glTF, "
            << stats["bytes_per_vertex"]["packed"].get<int>() << " B/vertex packed\n";
  if (bake.gltf_weights == GltfWeights::kUnorm16) {
    std::cerr << "WEIGHTS_n in 1/65535 steps: deformation error max "
              << stats["gltf_deformation_error_mm"]["max"].get<double>() << " mm, rms "
              << stats["gltf_deformation_error_mm"]["rms"].get<double>() << " mm (the figures above are the packed "
              << "0.001 weights')\n";
  }
  if (bake.error.peak_clip >= 0) {
    const ErrorPeak& peak = bake.error.peaks[bake.error.peak_clip];
    std::cerr << std::setprecision(3) << "largest error at vertex " << peak.vertex << " of mesh '"
              << character.meshes[peak.mesh_part].name << "' in clip '" << bake.clips[bake.error.peak_clip].name
              << "' at " << peak.time << " s\n";
  }
  if (bake.fit.parameters > 0) {
    std::cerr << std::setprecision(3) << "response fitted: " << bake.fit.fitted_parts << " parts, " << bake.fit.parameters
              << " keys over " << bake.fit.poses << " poses; whole-body volume change (RMS) " << 100.0 * bake.fit.body_rms_before
              << " % -> " << 100.0 * bake.fit.body_rms_after << " %\n";
  }
  for (const ClipQuality& clip : bake.quality.clips) {
    std::cerr << std::setprecision(2) << "volume in '" << clip.clip << "': input skinning " << std::showpos
              << 100.0 * clip.body.input.change << " %, dual quaternions " << 100.0 * clip.body.dual_quaternion.change
              << " %, rig " << 100.0 * clip.body.rig.change << " %";
    if (clip.surface.measured) std::cerr << ", centres of rotation " << 100.0 * clip.surface.centre_of_rotation.change << " %";
    std::cerr << std::noshowpos << " (largest change against the bind pose)\n";
  }
  const ClipQuality* roughest = nullptr;
  for (const ClipQuality& clip : bake.quality.clips) {
    if (!clip.surface.measured) continue;
    auto ratio = [](const ClipQuality& c) { return c.surface.roughness_rise[3] / std::max(c.surface.roughness_rise[0], 1e-5); };
    if (!roughest || ratio(clip) > ratio(*roughest)) roughest = &clip;
  }
  if (roughest) {
    const double* rise = roughest->surface.roughness_rise;
    std::cerr << std::setprecision(3) << "roughness rise (95th percentile of the moving skin), roughest against plain skinning in '"
              << roughest->clip << "': input skinning " << 1000.0 * rise[0] << " mm, dual quaternions " << 1000.0 * rise[1]
              << " mm, centres of rotation " << 1000.0 * rise[2] << " mm, rig " << 1000.0 * rise[3] << " mm\n";
  }
  // The crease whose rig passes more skin through the opposing skin than plain skinning does, most of all.
  const ClipQuality* crease_clip = nullptr;
  const CreaseContact* crease = nullptr;
  for (const ClipQuality& clip : bake.quality.clips) {
    for (const CreaseContact& contact : clip.creases) {
      auto excess = [](const CreaseContact& c) { return c.skinning[3].through - c.skinning[0].through; };
      if (!crease || excess(contact) > excess(*crease)) {
        crease = &contact;
        crease_clip = &clip;
      }
    }
  }
  if (crease) {
    auto through = [](const CreaseMethodContact& c) {
      std::ostringstream text;
      text << c.through << " (" << std::setprecision(3) << 1000.0 * c.deepest << " mm deep)";
      return text.str();
    };
    std::cerr << std::setprecision(3) << "crease '" << crease->crease << "' in '" << crease_clip->clip << "' bent "
              << crease->bend * 180.0 / 3.14159265358979323846 << " deg: skin vertices through the opposing skin, input skinning "
              << through(crease->skinning[0]) << ", dual quaternions " << through(crease->skinning[1]) << ", centres of rotation "
              << through(crease->skinning[2]) << ", rig " << through(crease->skinning[3]) << "\n";
  }
  // The joint region (pipeline/joint_regions.h) that loses most beyond plain skinning: not fitted, so
  // it shows what the fitted body regions hide.
  const ClipQuality* joint_clip = nullptr;
  size_t joint_region = 0;
  for (const ClipQuality& clip : bake.quality.clips) {
    for (size_t r = 0; r < clip.joint_regions.size() && r < bake.quality.joint_regions.size(); ++r) {
      if (!joint_clip || clip.joint_regions[r].loss > joint_clip->joint_regions[joint_region].loss) {
        joint_clip = &clip;
        joint_region = r;
      }
    }
  }
  if (joint_clip) {
    const JointRegionLoss& loss = joint_clip->joint_regions[joint_region];
    std::cerr << std::setprecision(3) << "joint region losing most beyond plain skinning: the skin of '"
              << bake.quality.joint_regions[joint_region] << "' in '" << joint_clip->clip << "', " << 100.0 * loss.loss
              << " points (input skinning " << 100.0 * loss.input << " %, rig " << 100.0 * loss.rig << " %, volume about the joint)\n";
  }
  if (bake.quality.seam_places > 0 && !bake.quality.clips.empty()) {
    const ClipQuality* worst = nullptr;
    for (const ClipQuality& clip : bake.quality.clips)
      if (!worst || clip.seams.rig - clip.seams.input > worst->seams.rig - worst->seams.input) worst = &clip;
    std::cerr << std::setprecision(4) << "seams: " << bake.quality.seam_places
              << " places where skin vertices share a bind position; the rig opens them at most "
              << std::max(0.0, 1000.0 * (worst->seams.rig - worst->seams.input)) << " mm beyond the input skinning (in '"
              << worst->clip << "')\n";
  }
  if (legs_uncovered) {
    std::cerr << std::setprecision(0) << "note: " << (options.muscles.empty() ? "preset '" + options.preset + "'" : options.muscles)
              << " has no muscle across the hips or knees, and clip '" << legs.clip << "' turns " << legs.joint << " by "
              << legs.largest_turn_deg << " degrees: the legs stay plain skinning (--preset gow_fullbody covers them)\n";
  }
  if (!bake_options.jiggles.empty()) {
    // Where the jiggle lives in the file: a runtime bake writes no channels, so its jiggles are the
    // extension's, simulated by the engine (docs/jiggle.md).
    const char* where = options.springs_only                   ? "not baked"
                        : bake.motion == MuscleMotion::kRuntime ? "in the RIGBAKE_muscle_rig extension, simulated at run time (no channels)"
                        : bake.motion == MuscleMotion::kBoth    ? "baked into every clip, and in the RIGBAKE_muscle_rig extension"
                                                                : "baked into every clip";
    std::cerr << "jiggle: " << bake_options.jiggles.size() << " joints, " << bake_options.hits.size() << " hits, " << where
              << (vrm_springs ? "; exported as VRM spring bones, without their cones (VRM springs have none; docs/jiggle.md)" : "")
              << "\n";
  }
  if (file.vrm_constrained_muscles > 0) {
    std::cerr << "VRM 1.0: the base and tip joints of " << file.vrm_constrained_muscles
              << " muscles carry VRMC_node_constraint aim constraints (docs/extensions.md)\n";
  }
  return 0;
}

}  // namespace

void addBakeCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<BakeCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "bake",
      "Bake muscle joints into a character: per muscle a base, tip, driver and skinned joint (the skinned one "
      "volume-preserving, docs/muscle-model.md) added to the skeleton and every skin, with the muscles' response "
      "(bulge, scale) fitted to the character's clips so that the skin keeps its volume where plain skinning loses "
      "it; skin weights pruned to 4, 7 or 10 influences per vertex at 0.001 precision, written as JOINTS_n/WEIGHTS_n "
      "and as packed buffers (docs/packed-influences.md). By default the muscles move at run time from the "
      "RIGBAKE_muscle_rig extension, adding no animation data (docs/runtime.md). Reports the weights' deformation "
      "error in mm and the volume per clip against plain and dual-quaternion skinning (--stats for every body "
      "region).\n\nExample: rigbake bake hero.glb --influences 10 -o hero_baked.glb --stats stats.json");
  command->add_option("character", options->character, "Character file (.glb, .gltf, .vrm, .fbx)")->required();
  command->add_option("-o,--output", options->output, "Baked glTF to write (.glb/.vrm binary, .gltf JSON)")->required();
  command->add_option("--muscles", options->muscles,
                      "Muscle JSON from `rigbake place` (default: place --preset on the character now)");
  command->add_option("--preset", options->preset, "Muscle preset used when --muscles is absent or positions-only")
      ->capture_default_str();
  command->add_option("--influences", options->influences, "Influences per vertex: 4, 7 or 10")
      ->check(CLI::IsMember({4, 7, 10}))
      ->capture_default_str();
  command->add_option("--gltf-weights", options->gltf_weights,
                      "Precision of WEIGHTS_n: milli = the talk's 0.001 steps, the very weights the packed buffers "
                      "hold; unorm16 = 1/65535 steps, for engines that skin with WEIGHTS_n (same bytes, about a "
                      "fiftieth of the deformation error; the packed buffers keep 0.001, docs/muscle-weights.md)")
      ->check(CLI::IsMember({"milli", "unorm16"}))
      ->capture_default_str();
  command->add_option("--fps", options->fps, "Sample clips at this rate (frames per second); 0 = at their own keys")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--threads", options->threads,
                      "Threads to bake with (0 = one per core); the outputs are byte-identical at any count")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--packed-out", options->packed_output, "Also write the packed influences as a raw file");
  command->add_option("--stats", options->stats_output,
                      "Write figures (deformation error, volume against plain and dual-quaternion skinning per clip and "
                      "body region, bytes per vertex) as JSON; - for standard output");
  command->add_option("--response", options->response,
                      "Muscle response (the set-driven bulge and scale keys): auto = fit to the clips the parts that still "
                      "have their preset's curves, keep curves a muscle file brings; fit = fit every part; keep = fit "
                      "nothing (docs/muscle-model.md)")
      ->check(CLI::IsMember({"auto", "fit", "keep"}))
      ->capture_default_str();
  command->add_option("--fit-poses", options->fit_poses,
                      "Poses the response fit solves over, chosen from every clip's frames where they spread the "
                      "muscles' drivers most (more: slower, closer to every frame)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  command->add_option("--muscle-motion", options->muscle_motion,
                      "How the muscle joints move in the file: runtime = the RIGBAKE_muscle_rig extension only, for "
                      "engines that evaluate the rig (no sampled muscle channels; a plain viewer plays the input's own "
                      "skinning); sampled = channels for the skinned joints, no extension; both = the extension and the "
                      "channels (docs/runtime.md)")
      ->check(CLI::IsMember({"runtime", "sampled", "both"}))
      ->capture_default_str();
  command->add_flag("--helper-joints", options->helper_joints,
                    "Also write each muscle's base, tip and driver joints (the talk's aim and point constraints) as nodes, "
                    "sampled when the motion is sampled; in a VRM 1.0 the base and tip also carry their aim constraints "
                    "as VRMC_node_constraint");
  command->add_option("--muscles-out", options->muscles_output,
                      "Write the muscles as baked (fitted response curves included) as muscle JSON, to edit or retarget; - for "
                      "standard output");
  command->add_option("--regions", options->regions,
                      "Body regions for the volume figures (a file, or a name under presets/regions/)")
      ->capture_default_str();
  command->add_option("--jiggle", options->jiggle,
                      "Jiggle preset (a file, or a name under presets/jiggle/, e.g. biceps): spring joints with cone "
                      "limits simulated on a fixed 240 Hz step and baked into every clip; on a VRM also exported as "
                      "spring bones (docs/jiggle.md)");
  command->add_option("--hits", options->hits, "Hit reactions (JSON, docs/jiggle.md) that kick the jiggle joints");
  command->add_option("--rom", options->rom,
                      "Also measure on range-of-motion clips (a ROM preset; alone: default), so that characters without "
                      "clips get deformation figures: the clips take part in the weight rounding and the error figures "
                      "(per_clip rom_*) but are not written into the output (`rigbake rom` writes them; docs/rom.md). "
                      "Put it after the character, or write --rom=PRESET")
      ->expected(0, 1)
      ->default_str("default");
  command->add_flag("--vrm-springs-only", options->springs_only,
                    "VRM only: export the --jiggle joints as spring bones for the runtime to simulate, and do not "
                    "also bake them into the clips");
  command->add_option("--vrm", options->vrm,
                      "VRM version to write: 1 converts a VRM 0.x avatar to VRM 1.0 (humanoid, meta, spring bones and "
                      "colliders; turned to face +Z; the helper joints' VRMC_node_constraint with --helper-joints); 0 keeps "
                      "a VRM 0.x. Default: as the input is. docs/extensions.md says what is converted and what is lost")
      ->check(CLI::IsMember({"0", "1"}));
  addPresetOptions(command, &options->presets);
  command->add_flag("--json", options->json, "Print the figures as JSON on stdout");
  addProgressOption(command, &options->progress);
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
