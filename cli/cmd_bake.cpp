// `rigbake bake CHAR --muscles muscles.json -o baked.glb`: muscle joints, their animation and skin
// weights into a new glTF, with the deformation error and memory figures of the chosen influence count.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "app/bake_job.h"
#include "core/error.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "formats/atomic_file.h"
#include "formats/bake_stats_json.h"
#include "pipeline/bake.h"
#include "pipeline/check_registry.h"
#include "pipeline/check_support.h"
#include "pipeline/leg_coverage.h"

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
  double fit_smoothness = rigbake::ResponseFitOptions{}.smoothness_weight;
  double fit_roughness_cap = rigbake::ResponseFitOptions{}.roughness_cap;
  std::string fit_volume = "signed";
  std::string fit_regions = "fitted-poses";
  // --fit-regions every-frame: the response is fitted on the written weights (its lines say so).
  bool fitsRegionsEveryFrame() const { return fit_regions == "every-frame"; }
  std::string muscle_motion = "runtime";
  bool helper_joints = false;
  std::string muscles_output;
  double fps = 0.0;
  int threads = 0;
  bool json = false;
  PresetOptions presets;
};

// The skin's surface figures are measured only when the bake writes figures (pipeline/bake.h measure_skin).
bool skinFiguresWritten(const BakeCommandOptions& options) { return !options.stats_output.empty() || options.json; }

// The clip whose rig is roughest against plain skinning, and, when the fitted rig is over
// SKIN_ROUGHNESS_RISE's bound on some clip with no cap set, the option that trades volume for it.
void printRoughness(const BakeCommandOptions& options, const BakeResult& bake) {
  const ClipQuality* roughest = nullptr;
  const double rough_allowed = checkAt<checkIndex("SKIN_ROUGHNESS_RISE")>().threshold;
  int rough_clips = 0, measured_clips = 0;
  for (const ClipQuality& clip : bake.quality.clips) {
    if (!clip.surface.measured) continue;
    ++measured_clips;
    rough_clips += roughnessRatio(clip.surface) > rough_allowed;
    if (!roughest || roughnessRatio(clip.surface) > roughnessRatio(roughest->surface)) roughest = &clip;
  }
  if (roughest) {
    const double* rise = roughest->surface.roughness_rise;
    std::cerr << std::setprecision(3) << "roughness rise (95th percentile of the moving skin), roughest against plain skinning in '"
              << roughest->clip << "': input skinning " << 1000.0 * rise[0] << " mm, dual quaternions " << 1000.0 * rise[1]
              << " mm, centres of rotation " << 1000.0 * rise[2] << " mm, rig " << 1000.0 * rise[3] << " mm";
    if (roughest->surface.lumpiest.at.found) std::cerr << "; " << lumpPlaceText(roughest->surface.lumpiest);
    // The fit buys volume with bulges; the cap is the other side of that trade (measured on eight
    // characters: docs/deformation-quality.md, "The roughness cap"), so a bake over the check says so.
    if (rough_clips > 0 && bake.fit.parameters > 0 && options.fit_roughness_cap == 0.0)
      std::cerr << "; the rig is rougher than " << std::setprecision(2) << rough_allowed << "x plain skinning on " << rough_clips << " of "
                << measured_clips << " clips (SKIN_ROUGHNESS_RISE): --fit-roughness-cap " << rough_allowed
                << " bounds it in the fit and keeps less of the volume (docs/deformation-quality.md, \"The roughness cap\")";
    std::cerr << "\n";
  }
}

// The body region that loses most beyond plain skinning over every clip, where, and how much of it the
// cut to --influences makes.
void printRegionLine(const BakeCommandOptions& options, const BakeResult& bake) {
  const ClipQuality* region_clip = nullptr;
  size_t region = 0;
  for (const ClipQuality& clip : bake.quality.clips) {
    for (size_t r = 0; r < clip.regions.size() && r < bake.quality.regions.size(); ++r) {
      if (!region_clip || regionLossBeyondInput(clip.regions[r]) > regionLossBeyondInput(region_clip->regions[region])) {
        region_clip = &clip;
        region = r;
      }
    }
  }
  if (region_clip) {
    const SkinningVolumes& v = region_clip->regions[region];
    const double allowed = checkAt<checkIndex("SKIN_REGION_VOLUME_LOSS")>().threshold;
    const double loss = regionLossBeyondInput(v);
    std::cerr << std::setprecision(2) << "body region losing most beyond plain skinning: '" << bake.quality.regions[region] << "' in '"
              << region_clip->clip << "', " << loss << " points (input skinning " << std::showpos << 100.0 * v.input.change
              << " %, rig " << 100.0 * v.rig.change << " %)" << std::noshowpos;
    if (region < region_clip->region_places.size() && region_clip->region_places[region].at.found)
      std::cerr << ", " << regionLossPlaceText(region_clip->region_places[region]);
    // The part of it the fit did not see: the fit keeps the regions with the weights before the cut.
    // (With --fit-regions every-frame the fit keeps them with the written weights.)
    if (!options.fitsRegionsEveryFrame() && region < region_clip->region_places.size() &&
        region_clip->region_places[region].cut_measured && region_clip->region_places[region].cut_points < -0.005)
      std::cerr << "; " << fixedDecimals(-region_clip->region_places[region].cut_points, 2)
                << " points of the loss from cutting the weights to " << bake.influences
                << " influences and rounding them (the response fit keeps the regions with the weights before the cut"
                << (bake.influences < 10 ? "; more influences cut less" : "") << ", --fit-regions every-frame fits on the written ones)";
    if (loss > allowed)
      std::cerr << "; more than the " << std::setprecision(0) << allowed << " point `rigbake validate` allows by default (SKIN_REGION_VOLUME_LOSS, an error)";
    std::cerr << "\n";
  }
}

// The figures on stderr: the bake, its error and where it peaks, volumes, roughness, creases, seams,
// legs, jiggles and VRM constraints.
void printFigures(const BakeCommandOptions& options, const app::BakeOutputs& out) {
  const Character& character = out.character.loaded.character;
  const BakeResult& bake = out.bake;
  const LegCoverage& legs = out.legs;
  std::cerr << std::fixed << std::setprecision(4) << "baked " << bake.muscles.parts.size() << " muscles ("
            << jointsAdded(bake) << " joints added) into " << options.output << ": " << bake.influences
            << " influences/vertex, " << bake.vertex_count << " vertices, " << bake.clips.size() << " clips; ";
  // Without a clip nothing moved, so there is no deformation to state (never "max 0.0000 mm").
  if (bake.clips.empty())
    std::cerr << "no clip, so no deformation measured (--rom measures on range-of-motion clips)";
  else
    std::cerr << "deformation error max " << 1000.0 * bake.error.overall.max_displacement << " mm, rms "
              << 1000.0 * bake.error.overall.rms_displacement << " mm";
  // The error is against the weights before the cut under the fitted response; every-frame fits the
  // response to the written weights, so that rig is one no engine plays.
  if (!bake.clips.empty() && options.fitsRegionsEveryFrame())
    std::cerr << " (against the weights before the cut, which --fit-regions every-frame did not fit the response to)";
  std::cerr << "; skin data " << skinBytesPerVertex(bake).gltf << " B/vertex as glTF, "
            << skinBytesPerVertex(bake).packed << " B/vertex packed\n";
  if (bake.gltf_weights == GltfWeights::kUnorm16) {
    std::cerr << "WEIGHTS_n in 1/65535 steps: deformation error max "
              << 1000.0 * bake.gltf_error.overall.max_displacement << " mm, rms "
              << 1000.0 * bake.gltf_error.overall.rms_displacement << " mm (the figures above are the packed "
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
              << " keys over " << bake.fit.poses << " poses";
    if (bake.fit.added_poses > 0) std::cerr << " and " << bake.fit.added_poses << " frames where a body region fell below its band";
    std::cerr << "; whole-body volume change (RMS) " << 100.0 * bake.fit.body_rms_before
              << " % -> " << 100.0 * bake.fit.body_rms_after << " %\n";
  }
  for (const ClipQuality& clip : bake.quality.clips) {
    std::cerr << std::setprecision(2) << "volume in '" << clip.clip << "': input skinning " << std::showpos
              << 100.0 * clip.body.input.change << " %, dual quaternions " << 100.0 * clip.body.dual_quaternion.change
              << " %, rig " << 100.0 * clip.body.rig.change << " %";
    if (clip.surface.measured) std::cerr << ", centres of rotation " << 100.0 * clip.surface.centre_of_rotation.change << " %";
    std::cerr << std::noshowpos << " (largest change against the bind pose)\n";
  }
  // The body region that loses most beyond plain skinning (measured in every bake), and whether that is
  // more than validate's SKIN_REGION_VOLUME_LOSS allows: an error there, so the bake says it first.
  printRegionLine(options, bake);
  // The occupied volume (each point inside the skin once): the rig against plain skinning over every
  // clip, and the clip whose signed figure counts most of the rig's volume twice.
  int occupied_clips = 0, occupied_better = 0, occupied_half = 0;
  const ClipQuality* overstated = nullptr;
  for (const ClipQuality& clip : bake.quality.clips) {
    if (!clip.surface.measured) continue;
    const VolumeExtreme* occupied = clip.surface.occupied;
    ++occupied_clips;
    occupied_better += std::abs(occupied[3].change) < std::abs(occupied[0].change);
    occupied_half += std::abs(occupied[3].change) <= 0.5 * std::abs(occupied[0].change);
    auto gap = [](const ClipQuality& c) { return c.body.rig.change - c.surface.occupied[3].change; };
    if (!overstated || gap(clip) > gap(*overstated)) overstated = &clip;
  }
  if (overstated) {
    std::cerr << std::setprecision(3) << "occupied volume (each point inside the skin once, docs/deformation-quality.md): the rig changes it less than plain skinning on "
              << occupied_better << " of " << occupied_clips << " clips, by at most half as much on " << occupied_half
              << "; most counted twice in '" << overstated->clip << "': the rig's largest change " << std::showpos << 100.0 * overstated->body.rig.change
              << " % signed, " << 100.0 * overstated->surface.occupied[3].change << " % occupied (plain skinning "
              << 100.0 * overstated->surface.occupied[0].change << " %)" << std::noshowpos << "\n";
  }
  printRoughness(options, bake);
  // Strain: the clip whose rig stretches or squashes its skin most against plain skinning (as validate's
  // SKIN_STRAIN takes it).
  const ClipQuality* strained = nullptr;
  for (const ClipQuality& clip : bake.quality.clips) {
    if (clip.surface.measured && (!strained || strainRatio(clip.surface) > strainRatio(strained->surface))) strained = &clip;
  }
  if (strained) {
    const double* edge = strained->surface.edge_strain;
    const double* area = strained->surface.area_strain;
    std::cerr << std::setprecision(3) << "strain (95th percentile of the moving skin's edge lengths / triangle areas), most against plain skinning in '"
              << strained->clip << "': input skinning " << 100.0 * edge[0] << " / " << 100.0 * area[0] << " %, dual quaternions "
              << 100.0 * edge[1] << " / " << 100.0 * area[1] << " %, centres of rotation " << 100.0 * edge[2] << " / " << 100.0 * area[2]
              << " %, rig " << 100.0 * edge[3] << " / " << 100.0 * area[3] << " %\n";
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
  if (!skinFiguresWritten(options) && !bake.quality.clips.empty()) {
    std::cerr << "skin figures (seams, roughness, strain, occupied volume, creases, joint regions, centres of rotation): not measured; --stats or "
                 "--json measures them here, `rigbake validate` in the baked file\n";
  }
  if (bake.quality.seam_places > 0 && !bake.quality.clips.empty()) {
    const ClipQuality* worst = nullptr;
    for (const ClipQuality& clip : bake.quality.clips)
      if (!worst || clip.seams.rig - clip.seams.input > worst->seams.rig - worst->seams.input) worst = &clip;
    std::cerr << std::setprecision(4) << "seams: " << bake.quality.seam_places
              << " places where skin vertices share a bind position; the rig opens them at most "
              << std::max(0.0, 1000.0 * (worst->seams.rig - worst->seams.input)) << " mm beyond the input skinning (in '"
              << worst->clip << "')";
    // Where the input gives one place different weights it opens there itself, and rounding those
    // weights to 0.001 scales its opening: that is not a crack the muscles make (validate, which takes
    // the written weights less the muscles' as the input, measures it as none).
    if (1000.0 * worst->seams.input > checkAt<checkIndex("SKIN_SEAM_OPEN")>().threshold)
      std::cerr << ", where the input itself opens " << 1000.0 * worst->seams.input
                << " mm (its weights differ at one place; rounding them to 0.001 scales that, `rigbake validate` compares the "
                   "written weights)";
    std::cerr << "\n";
  }
  if (bake.rigid_piece_vertices > 0) {
    std::cerr << "rigid pieces: " << bake.rigid_piece_vertices << " of the " << bake.vertex_count
              << " skinned vertices are on pieces one joint moves alone (armour, props, hair): no muscle takes weight "
                 "there, they move as the input's skinning moves them (docs/muscle-weights.md, \"Rigid pieces\")\n";
  }
  if (legs.legs && !legs.covered && legs.largest_turn_deg > kLegTurnWorthMuscles) {
    std::cerr << std::setprecision(0) << "note: " << (options.muscles.empty() ? "preset '" + options.preset + "'" : options.muscles)
              << " has no muscle across the hips or knees, and clip '" << legs.clip << "' turns " << legs.joint << " by "
              << legs.largest_turn_deg << " degrees: the legs stay plain skinning (--preset gow_fullbody covers them)\n";
  }
  if (options.fit_volume == "occupied" && options.fit_smoothness == 0.0 && bake.fit.parameters > 0) {
    // Measured: without the smoothness term the occupied fit's result turns on which skin the grid finds
    // inside a fold (Cyberpunk: 3 to 21 of 22 clips halved as the grid changes), with it it does not.
    std::cerr << "note: --fit-volume occupied without --fit-smoothness is not stable (which skin counts as inside a fold "
                 "decides it); --fit-smoothness 300 makes it so (docs/deformation-quality.md)\n";
  }
  if (out.jiggles > 0) {
    // Where the jiggle lives in the file: a runtime bake writes no channels, so its jiggles are the
    // extension's, simulated by the engine (docs/jiggle.md).
    const char* where = options.springs_only                   ? "not baked"
                        : bake.motion == MuscleMotion::kRuntime ? "in the RIGBAKE_muscle_rig extension, simulated at run time (no channels)"
                        : bake.motion == MuscleMotion::kBoth    ? "baked into every clip, and in the RIGBAKE_muscle_rig extension"
                                                                : "baked into every clip";
    std::cerr << "jiggle: " << out.jiggles << " joints, " << out.hits << " hits, " << where
              << (out.vrm_springs ? "; exported as VRM spring bones, without their cones (VRM springs have none; docs/jiggle.md)" : "")
              << "\n";
  }
  if (out.vrm_constrained_muscles > 0) {
    std::cerr << "VRM 1.0: the base and tip joints of " << out.vrm_constrained_muscles
              << " muscles carry VRMC_node_constraint aim constraints (docs/extensions.md)\n";
  }
}

// Where each field of app::BakeRequest and BakeOptions comes from on the command line.
// (The fields app::bakeJob and bakeCharacter name in an InvalidOption, and "map", which a landmark that
// does not resolve asks for in a FixableByOption.)
const std::vector<FlagName> kBakeFlags = {{"influences", "--influences"}, {"fps", "--fps"}, {"hits", "--hits"},
                                          {"springs_only", "--vrm-springs-only"}, {"map", "--map"},
                                          {"fit_poses", "--fit-poses"}, {"fit_smoothness", "--fit-smoothness"},
                                          {"fit_roughness_cap", "--fit-roughness-cap"}, {"fit_regions", "--fit-regions"}};

app::BakeRequest bakeRequestOf(const BakeCommandOptions& options, const ProgressReport& progress) {
  app::BakeRequest request;
  request.character.path = options.character;
  if (!options.vrm.empty()) request.character.load.vrm = options.vrm == "1" ? VrmTarget::kVrm1 : VrmTarget::kVrm0;
  request.character.map = options.presets.map;
  request.output = options.output;
  request.preset = options.preset;
  request.muscles = options.muscles;
  request.rom = options.rom;
  request.regions = options.regions;
  request.jiggle = options.jiggle;
  request.hits = options.hits;
  request.springs_only = options.springs_only;
  request.packed = !options.packed_output.empty();
  BakeOptions& bake = request.options;
  bake.influences = options.influences;
  parseGltfWeights(options.gltf_weights, &bake.gltf_weights);  // CLI11 has checked the name
  bake.fps = options.fps;
  bake.threads = options.threads;
  parseResponseMode(options.response, &bake.response);  // CLI11 has checked the name
  bake.fit.max_poses = options.fit_poses;
  bake.fit.smoothness_weight = options.fit_smoothness;
  bake.fit.roughness_cap = options.fit_roughness_cap;
  bake.fit.occupied_volume = options.fit_volume == "occupied";  // CLI11 has checked the name
  bake.fit.every_frame_regions = options.fitsRegionsEveryFrame();
  parseMuscleMotion(options.muscle_motion, &bake.motion);
  bake.helper_joints = options.helper_joints;
  bake.measure_skin = skinFiguresWritten(options);
  request.progress = progress;
  request.notes = printNotesOf(options.character);
  return request;
}

int run(const BakeCommandOptions& options) {
  checkOutputOptions({{"-o", options.output, true},
                      {"--packed-out", options.packed_output, false},
                      {"--stats", options.stats_output, false, true},
                      {"--muscles-out", options.muscles_output, false, true}},
                     options.json);
  if (!options.hits.empty() && options.jiggle.empty()) fail(errc::USAGE, "--hits", "needs --jiggle: hits kick jiggle joints");
  if (options.springs_only && options.jiggle.empty()) fail(errc::USAGE, "--vrm-springs-only", "needs --jiggle");
  ProgressLine progress("rigbake bake", options.progress);
  const app::Presets presets = app::loadPresets(presetsDirectory(options.presets));
  const app::BakeOutputs out = withFlagNames(kBakeFlags, [&] { return app::bakeJob(bakeRequestOf(options, progress.report()), presets); });

  // All the outputs or none: a --stats that cannot be written must not leave a new -o behind.
  OutputBatch outputs;
  outputs.add(options.output, out.model);
  if (!options.packed_output.empty()) outputs.add(options.packed_output, out.packed);
  if (!options.stats_output.empty()) outputs.add(options.stats_output, out.stats_json);
  if (!options.muscles_output.empty()) outputs.add(options.muscles_output, out.muscles_json);
  outputs.commit();

  progress.clear();
  if (options.json) std::cout << out.stats_json;
  printFigures(options, out);
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
      "region and the skin's figures: seams, roughness, strain, occupied volume, creases, joint regions, centres of rotation, which also "
      "print their worst case here; `rigbake validate` checks them in the baked file).\n\nExample: rigbake bake hero.glb --influences 10 -o hero_baked.glb --stats stats.json");
  command->add_option("character", options->character, "Character file (.glb, .gltf, .vrm, .fbx)")->required();
  command->add_option("-o,--output", options->output, "Baked glTF to write (.glb/.vrm binary, .gltf JSON)")->required();
  command->add_option("--muscles", options->muscles,
                      "Muscle JSON from `rigbake place` (default: place --preset on the character now)");
  command->add_option("--preset", options->preset, "Muscle preset used when --muscles is absent or positions-only")
      ->capture_default_str();
  command->add_option("--influences", options->influences,
                      "Influences per vertex: 4, 7 or 10. Where a vertex has "
                      "more, the bake keeps the joints and weights that best follow all of them over the clips' "
                      "frames: on the eight shared characters at 4, the largest deformation error against all of "
                      "them is 1.3-73 mm (RMS 0.02-2 mm) instead of 12-310 mm keeping the strongest "
                      "(docs/muscle-weights.md, \"Refitting the kept weights\")")
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
                      "body region, bytes per vertex, and the skin's: seams, roughness, strain, occupied volume, creases and "
                      "joint regions against plain, dual-quaternion and centre-of-rotation skinning) as JSON; - for "
                      "standard output. Where a figure fails it names the vertex to look at: the one taking most of a "
                      "region's lost volume (lost_most_at, with cut_points: how much of the loss cutting the weights to "
                      "--influences made, which the response fit does not see) and where the skin is lumpiest "
                      "(lumpiest_at), by mesh, vertex and bind position. The skin's figures cost more than the rest of the bake: a bake without "
                      "--stats or --json skips them");
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
  command->add_option("--fit-smoothness", options->fit_smoothness,
                      "Weight of the response fit's smoothness term (per metre of the root mean square umbrella Laplacian "
                      "of the muscles' move along the normal, on a 1.8 m body: it scales with the body's height, so a "
                      "character's unit does not matter; the body's volume change weighs 30 per unit): 0 fits volume "
                      "alone; 300 keeps as much volume on the FBX characters within 1.3x plain skinning's roughness, "
                      "1000 every tested character but the mannequin within 1.41x with less volume kept, 3000 within "
                      "1.08x with little volume kept (docs/deformation-quality.md, \"The fit's smoothness term\")")
      ->check(CLI::Range(0.0, 1.0e6))
      ->capture_default_str();
  command->add_option("--fit-roughness-cap", options->fit_roughness_cap,
                      "Bound the response fit by the skin's roughness: at every fitted pose no vertex the muscles move "
                      "may stand out of its neighbours' plane by more than plain skinning's there plus what keeps the "
                      "95th percentile within this many times plain skinning's roughness rise (issue 29's goal is "
                      "1.2); the muscles then keep what volume they can within it. 0: no bound. Measured on eight "
                      "characters at 1.2 and 10 influences: every clip within 1.2x plain skinning's roughness (without "
                      "the cap 83 of 128), but the rig's volume change is 0.94 of plain skinning's on the median clip "
                      "instead of 0.76, and 1 of 20 arm clips keeps half of it instead of 7 (scripts/skin-goals.sh; "
                      "docs/deformation-quality.md, \"The roughness cap\")")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  command->add_option("--fit-volume", options->fit_volume,
                      "Which volume the response fit keeps: signed = the enclosed volume, where skin pushed into a fold "
                      "counts twice; occupied = skin inside other skin at a fitted pose earns nothing, so the muscles do "
                      "not swell into folds. Use it with --fit-smoothness (alone it is not stable): at 200 on Quaternius "
                      "Cyberpunk (10 influences) it is 1.24x plain skinning's roughness against the signed fit's 1.26x, "
                      "and halves plain skinning's occupied-volume change on 0 of 22 clips against 1 "
                      "(docs/deformation-quality.md, \"The fit on the occupied volume\")")
      ->check(CLI::IsMember({"signed", "occupied"}))
      ->capture_default_str();
  command->add_option("--fit-regions", options->fit_regions,
                      "Where the response fit keeps each body region within 0.5 points of plain skinning's volume "
                      "change: fitted-poses = at the fitted poses, on the weights before the cut to --influences; "
                      "every-frame = on the weights as written (cut and rounded before the fit), then checked at "
                      "every clip frame, the frames where a region falls below joining the fit. Measured on the eight "
                      "shared characters at 4 influences: every-frame keeps every region within 1 point of plain "
                      "skinning on all 8 (fitted-poses 5; the cut to 4 influences made most of the rest), and halves "
                      "11 of 20 arm clips, as fitted-poses does, but 79 of 128 clips are within 1.2x plain skinning's "
                      "roughness (88), and as many of 565 crease samples are no worse (476); the first bake takes 1.3 to "
                      "1.9 times as long, and its "
                      "deformation error is against the weights before the cut, which the response is no longer fitted to "
                      "(docs/deformation-quality.md, \"Every region at every frame\")")
      ->check(CLI::IsMember({"fitted-poses", "every-frame"}))
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
