// Deformation quality measured from a baked file (see the header): fold the muscles' weight back onto
// their carriers for the input skinning (or take the input file's own weights when given), evaluate
// the rig as an engine does for the baked one, and hand both to measureDeformationQuality(); then draw
// each clip's worst region and each muscle kind at its peak compression.
#include "pipeline/baked_quality.h"
#include "core/file_name.h"

#include "pipeline/joint_regions.h"

#include "pipeline/centre_of_rotation.h"
#include "pipeline/crease_contact.h"
#include "pipeline/seam_opening.h"
#include "pipeline/surface_figures.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>

#include "core/error.h"
#include "pipeline/check_registry.h"
#include "pipeline/check_support.h"
#include "pipeline/influences.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/parallel.h"
#include "pipeline/pose.h"
#include "pipeline/skin_volume.h"
#include "pipeline/skinning.h"

namespace rigbake {
namespace {

struct FileMuscle {
  std::string name;
  int joint = -1;    // the skinned node's skeleton joint
  int carrier = -1;  // the joint its weight came from
  int rig_index = -1;  // in file.rig.rig.muscles, -1 when the file has no usable extension
};

// Relabels every slot through `fold` and merges slots that then name the same joint into the first.
InfluenceSet foldInfluences(const InfluenceSet& set, const std::vector<int>& fold) {
  InfluenceSet out = set;
  const int slots = set.slots_per_vertex;
  for (int v = 0; v < set.vertexCount(); ++v) {
    int* joints = &out.joints[static_cast<size_t>(v) * slots];
    double* weights = &out.weights[static_cast<size_t>(v) * slots];
    for (int k = 0; k < slots; ++k) joints[k] = fold[joints[k]];
    for (int k = 1; k < slots; ++k) {
      if (weights[k] == 0.0) continue;
      for (int first = 0; first < k; ++first) {
        if (joints[first] != joints[k] || weights[first] == 0.0) continue;
        weights[first] += weights[k];
        weights[k] = 0.0;
        break;
      }
    }
  }
  return out;
}

std::string formatSeconds(double t) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f s", t);
  return text;
}

// The three panels side by side.
RgbImage besideEachOther(const std::vector<RgbImage>& panels) {
  RgbImage all;
  all.height = panels.front().height;
  for (const RgbImage& panel : panels) all.width += panel.width;
  all.pixels.assign(static_cast<size_t>(all.width) * all.height * 3, 255);
  int left = 0;
  for (const RgbImage& panel : panels) {
    for (int y = 0; y < panel.height; ++y)
      std::copy_n(&panel.pixels[static_cast<size_t>(y) * panel.width * 3], panel.width * 3,
                  &all.pixels[(static_cast<size_t>(y) * all.width + left) * 3]);
    left += panel.width;
  }
  return all;
}

// A muscle is pictured when some clip shortens it at least this much (length ratio): a muscle the clips
// barely compress shows nothing.
constexpr double kPictureMinCompression = 0.98;

struct PicturePart {
  const MeshPart* mesh;
  const MeasuredPart* weights;
  VolumeSurface surface;
  std::vector<int> region_of_triangle;  // index into `regions`, -1 for none
};

// A picture to draw: one sample of clip `clip`, framed on the welded vertices `on` marks per part.
struct PictureRequest {
  std::string title, subject_name;
  size_t clip = 0;
  double time = 0.0;
  std::vector<std::vector<char>> on;
  // A crease's picture: plain skinning, dual quaternions, centres of rotation and the rig side by side
  // (no heatmap), with `note` as its caption.
  bool methods = false;
  std::string note;
  // A ring around one welded vertex of one drawn part (-1: none), and what it marks.
  int marker_part = -1, marker_vertex = -1;
  std::string marker;
};

// Each muscle kind (LeftBicep and RightBicep are one) at the most compressed sample of either side;
// each corrective kind where its skin moves most, compressed or stretched (a raised arm's armpit).
void addMusclePictureRequests(const DeformationQuality& quality, const std::vector<MeasuredClip>& clips,
                              const std::vector<PicturePart>& drawn, int joint_count, int measured_muscles,
                              std::vector<PictureRequest>* requests_out) {
  std::vector<PictureRequest>& requests = *requests_out;
  auto pictured = [&](size_t m) -> const MuscleSkinMove& {
    const MuscleQuality& figures = quality.muscles[m];
    if (figures.kind == PartKind::kMuscle || !figures.stretched.measured) return figures.compressed;
    if (!figures.compressed.measured) return figures.stretched;
    return std::abs(figures.stretched.mean) > std::abs(figures.compressed.mean) ? figures.stretched : figures.compressed;
  };
  auto better = [&](size_t a, size_t b) {  // is muscle a's picture a better pick than b's for their kind?
    if (quality.muscles[a].kind == PartKind::kMuscle) return pictured(a).ratio < pictured(b).ratio;
    return std::abs(pictured(a).mean) > std::abs(pictured(b).mean);
  };
  std::map<std::string, int> kind_pick;
  std::vector<std::string> kind_order;
  auto kindOf = [](const std::string& name) {
    for (const char* side : {"Left", "Right"})
      if (name.rfind(side, 0) == 0) return name.substr(std::string(side).size());
    return name;
  };
  for (size_t m = 0; m < quality.muscles.size(); ++m) {
    const MuscleSkinMove& move = pictured(m);
    if (!move.measured) continue;
    if (quality.muscles[m].kind == PartKind::kMuscle && move.ratio > kPictureMinCompression) continue;
    if (quality.muscles[m].kind == PartKind::kCorrective && move.max_in + move.max_out <= 0.0) continue;
    const std::string kind = kindOf(quality.muscles[m].muscle);
    auto it = kind_pick.find(kind);
    if (it == kind_pick.end()) {
      kind_pick[kind] = static_cast<int>(m);
      kind_order.push_back(kind);
    } else if (better(m, static_cast<size_t>(it->second))) {
      it->second = static_cast<int>(m);
    }
  }
  std::vector<std::vector<std::vector<MuscleSkinVertex>>> skin_of_drawn;  // per drawn part, per muscle
  if (!kind_order.empty()) {
    for (const PicturePart& part : drawn)
      skin_of_drawn.push_back(muscleSkin(part.weights->rig, part.surface.vertex_of_weld, joint_count, measured_muscles));
  }
  for (const std::string& kind : kind_order) {
    const int m = kind_pick[kind];
    const MuscleSkinMove& move = pictured(static_cast<size_t>(m));
    size_t c = 0;
    while (c < clips.size() && clips[c].name != move.clip) ++c;
    if (c == clips.size()) continue;
    // The muscle's skin, as its figures took it.
    std::vector<std::vector<char>> on(drawn.size());
    for (size_t p = 0; p < drawn.size(); ++p) {
      on[p].assign(drawn[p].surface.weldedCount(), 0);
      for (const MuscleSkinVertex& vertex : skin_of_drawn[p][static_cast<size_t>(m)]) on[p][vertex.welded] = 1;
    }
    char ratio[32];
    std::snprintf(ratio, sizeof(ratio), "%.2f", move.ratio);
    const bool stretched = move.ratio > 1.0;
    requests.push_back({quality.muscles[m].muscle + (quality.muscles[m].kind == PartKind::kCorrective ? " (corrective)" : "") +
                            " at its most " + (stretched ? "stretched" : "compressed") + " (length ratio " + ratio + "), " +
                            move.clip + " at " + formatSeconds(move.time),
                        quality.muscles[m].muscle, c, move.time, std::move(on), false, {}, -1, -1, {}});
  }
}

// Each crease kind (elbow, shoulder, knee, groin: the name before its side) at the clip that bends it
// most, four skinnings side by side, framed on the crease's skin.
void addCreasePictureRequests(const DeformationQuality& quality, const std::vector<Crease>& creases,
                              const std::vector<MeasuredPart>& parts, const std::vector<PicturePart>& drawn,
                              std::vector<PictureRequest>* requests_out) {
  std::vector<PictureRequest>& requests = *requests_out;
  std::vector<std::string> crease_kinds;
  std::map<std::string, std::pair<size_t, const CreaseContact*>> crease_pick;
  for (size_t c = 0; c < quality.clips.size(); ++c) {
    for (const CreaseContact& contact : quality.clips[c].creases) {
      const std::string kind = contact.crease.substr(0, contact.crease.rfind('_'));
      auto it = crease_pick.find(kind);
      if (it == crease_pick.end()) {
        crease_kinds.push_back(kind);
        crease_pick[kind] = {c, &contact};
      } else if (contact.bend > it->second.second->bend + 1e-9) {
        it->second = {c, &contact};
      }
    }
  }
  for (const std::string& kind : crease_kinds) {
    const auto [c, contact] = crease_pick[kind];
    const Crease* crease = nullptr;
    for (const Crease& candidate : creases)
      if (candidate.name == contact->crease) crease = &candidate;
    if (crease == nullptr) continue;
    std::vector<std::vector<char>> on(drawn.size());
    for (size_t p = 0; p < drawn.size(); ++p) {
      on[p].assign(drawn[p].surface.weldedCount(), 0);
      const size_t mesh = static_cast<size_t>(parts[p].mesh_part);
      for (const std::vector<int>* side : {&crease->proximal[mesh], &crease->distal[mesh]})
        for (int v : *side) on[p][static_cast<size_t>(drawn[p].surface.weld_of_vertex[static_cast<size_t>(v)])] = 1;
    }
    char bend[32];
    std::snprintf(bend, sizeof(bend), "%.0f", contact->bend * 180.0 / 3.14159265358979323846);
    std::string note = "skin vertices through the opposing skin:";
    const char* names[kSurfaceSkinnings] = {"plain", "dual quaternions", "centres of rotation", "rig"};
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      char figure[96];
      std::snprintf(figure, sizeof(figure), "%s %s %d (%.1f mm deep)", s == 0 ? "" : ",", names[s], contact->skinning[s].through,
                    1000.0 * contact->skinning[s].deepest);
      note += figure;
    }
    PictureRequest request{"crease " + contact->crease + " bent " + bend + " degrees, " + quality.clips[c].clip + " at " +
                               formatSeconds(contact->time),
                           contact->crease, c, contact->time, std::move(on), true, note, -1, -1, {}};
    requests.push_back(std::move(request));
  }
}
// The skinned muscle joints and their carriers: from the extension when it is usable (`with_rig`), else
// from the muscle nodes' extras; "" or why the file cannot be measured.
std::string fileMuscles(const Skeleton& skeleton, const BakedFileData& file, bool with_rig, std::vector<FileMuscle>* muscles) {
  const int joint_count = skeleton.size();
  if (with_rig) {
    for (size_t m = 0; m < file.rig.skinned_joint.size(); ++m)
      muscles->push_back({file.rig.names[m], file.rig.skinned_joint[m], file.rig.rig.muscles[m].carrier_joint, static_cast<int>(m)});
  } else {
    for (const FileMuscleNode& node : file.muscle_nodes) {
      if (node.role != "skinned") continue;
      const int carrier = node.carrier_joint.empty() ? -1 : skeleton.find(node.carrier_joint);
      if (carrier < 0) return "muscle node '" + node.name + "' does not name its carrier joint (a bake older than the carrier weights)";
      muscles->push_back({node.muscle, skeleton.find(node.name), carrier, -1});
    }
  }
  if (muscles->empty()) return "the file has no skinned muscle joints";
  for (const FileMuscle& muscle : *muscles) {
    if (muscle.joint < 0 || muscle.carrier < 0 || muscle.carrier >= joint_count)
      return "muscle '" + muscle.name + "' has no skinned joint or carrier in the skeleton";
  }
  return "";
}

std::vector<int> skinnedPartsWithVertices(const Character& character) {
  std::vector<int> parts;
  for (size_t p = 0; p < character.meshes.size(); ++p)
    if (character.meshes[p].skinned && !character.meshes[p].positions.empty()) parts.push_back(static_cast<int>(p));
  return parts;
}

// Per mesh part of the baked `file`, the input's own weights on the file's joints (matched by name),
// normalized: the plain skinning the bake measured. Empty for parts that are not skinned.
std::vector<InfluenceSet> inputWeightsOnFile(const Character& file, const Character& input) {
  const auto mismatch = [&](const std::string& what) {
    fail(errc::VALIDATE_INPUT_MISMATCH, input.source, what + ": not the character " + fileNameOf(file.source) + " was baked from");
  };
  const std::vector<int> file_parts = skinnedPartsWithVertices(file), input_parts = skinnedPartsWithVertices(input);
  if (file_parts.size() != input_parts.size())
    mismatch(std::to_string(input_parts.size()) + " skinned mesh parts where the baked file has " + std::to_string(file_parts.size()));
  std::vector<int> joint_in_file(input.skeleton.size());
  for (int j = 0; j < input.skeleton.size(); ++j) joint_in_file[j] = file.skeleton.find(input.skeleton.names[j]);
  std::vector<InfluenceSet> out(file.meshes.size());
  for (size_t i = 0; i < file_parts.size(); ++i) {
    const MeshPart& baked = file.meshes[file_parts[i]];
    const MeshPart& own = input.meshes[input_parts[i]];
    if (own.positions.size() != baked.positions.size())
      mismatch("mesh '" + own.name + "' has " + std::to_string(own.positions.size()) + " vertices where the baked file's '" + baked.name +
               "' has " + std::to_string(baked.positions.size()));
    // The bake writes the input's positions as 32-bit floats: equal to float precision of the mesh's size.
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : own.positions) box.extend(p);
    const double tolerance = 1e-5 * box.diagonal().norm() + 1e-12;
    for (size_t v = 0; v < own.positions.size(); ++v)
      if ((own.positions[v] - baked.positions[v]).norm() > tolerance)
        mismatch("mesh '" + own.name + "' vertex " + std::to_string(v) + " lies elsewhere than in the baked file");
    InfluenceSet weights = influencesFromMesh(own);
    for (size_t k = 0; k < weights.joints.size(); ++k) {
      const int joint = joint_in_file[weights.joints[k]];
      if (joint < 0 && weights.weights[k] != 0.0)
        mismatch("joint '" + input.skeleton.names[weights.joints[k]] + "' skins mesh '" + own.name + "' and is not in the baked file");
      weights.joints[k] = std::max(joint, 0);
    }
    out[file_parts[i]] = normalizedInfluences(weights);
  }
  return out;
}

// Every skinned part with positions, in order (BodyRegion::triangles is indexed the same way): the input
// skinning's weights (the input's own when `input` is given, else each muscle's folded onto its carrier)
// and the rig's (relabelled by `rig_label`), and the character as the input skinning sees it in *folded
// (regions are cut on these weights). "" or why the file cannot be measured.
std::string measuredParts(const Character& character, const std::vector<int>& fold, const std::vector<int>& rig_label,
                          const Character* input, Character* folded, std::vector<MeasuredPart>* parts) {
  const int joint_count = character.skeleton.size();
  const std::vector<InfluenceSet> input_weights = input ? inputWeightsOnFile(character, *input) : std::vector<InfluenceSet>();
  for (size_t p = 0; p < character.meshes.size(); ++p) {
    const MeshPart& mesh = character.meshes[p];
    if (!mesh.skinned || mesh.positions.empty()) continue;
    const InfluenceSet file_weights = influencesFromMesh(mesh);
    if (!checkInfluences(file_weights, joint_count).empty()) return "mesh '" + mesh.name + "' has invalid skin weights (WEIGHTS_* checks)";
    MeasuredPart part;
    part.mesh_part = static_cast<int>(p);
    part.input = input ? input_weights[p] : normalizedInfluences(foldInfluences(file_weights, fold));
    part.rig = normalizedInfluences(foldInfluences(file_weights, rig_label));
    folded->meshes[p].joints = part.input.joints;
    folded->meshes[p].weights = part.input.weights;
    folded->meshes[p].influences_per_vertex = part.input.slots_per_vertex;
    parts->push_back(std::move(part));
  }
  if (parts->empty()) return "no skinned mesh with valid weights and triangles";
  return "";
}

// Every clip's sample times with the skin matrices (the skeleton's, then the measured muscles' skinned
// joints again at joint_count + m) into *frames, one list per clip (the rest pose for a character
// without clips), and each measured muscle's clamped length ratio there.
std::vector<MeasuredClip> measuredClips(const Character& character, const BakedFileData& file, const std::vector<FileMuscle>& muscles,
                                        int measured_muscles, std::vector<std::vector<SkinFrame>>* frames) {
  const Skeleton& skeleton = character.skeleton;
  frames->assign(std::max<size_t>(character.clips.size(), 1), {});
  std::vector<MeasuredClip> clips;
  auto addClip = [&](const Clip* clip, size_t c) {
    MeasuredClip measured;
    measured.name = clip ? clip->name : "(rest pose)";
    measured.times = clip ? sampleTimes(*clip, 0.0) : std::vector<double>{};
    if (measured.times.empty()) measured.times.push_back(0.0);
    for (double t : measured.times) {
      const Pose pose = clip ? sampleClip(skeleton, *clip, t) : restPose(skeleton);
      std::vector<Eigen::Affine3d> frame = bakedSkinMatrices(character, file, pose);
      for (int m = 0; m < measured_muscles; ++m) frame.push_back(frame[muscles[m].joint]);
      (*frames)[c].push_back(std::move(frame));
      std::vector<double> ratio(measured_muscles, 1.0);
      if (measured_muscles > 0) {
        const RigEvaluation evaluation = evaluateRig(file.rig.rig, pose, false);
        for (int m = 0; m < measured_muscles; ++m) ratio[m] = evaluation.drivers[muscles[m].rig_index].clamped_ratio;
      }
      measured.ratio.push_back(std::move(ratio));
    }
    measured.frames = &(*frames)[c];
    clips.push_back(std::move(measured));
  };
  for (size_t c = 0; c < character.clips.size(); ++c) addClip(&character.clips[c], c);
  if (character.clips.empty()) addClip(nullptr, 0);
  return clips;
}

// What the pictures read: the parts drawn, the frames and clips measured, and the centres of rotation
// (filled before a crease's picture is drawn).
struct PictureScene {
  const LandmarkSet& landmarks;
  const BakedQualityOptions& options;
  const std::vector<PicturePart>& drawn;
  const std::vector<std::vector<SkinFrame>>& frames;
  const std::vector<MeasuredClip>& clips;
  const std::vector<RotationCentres>& centres;
};

// The clip's sample nearest `time`.
size_t sampleIndex(const MeasuredClip& clip, double time) {
  const std::vector<double>& times = clip.times;
  size_t best = 0;
  for (size_t t = 1; t < times.size(); ++t)
    if (std::abs(times[t] - time) < std::abs(times[best] - time)) best = t;
  return best;
}

// Seen across the subject's long axis (a limb from the side, not end on). When the skin around it lies
// in a plane (a bent elbow, a raised arm against the torso), from that plane's normal, so the bend
// shows; otherwise from where the subject's skin faces (a muscle's patch), else from the front.
Camera pictureCamera(const LandmarkSet& landmarks, const std::vector<std::vector<Eigen::Vector3d>>& skin,
                     const std::function<bool(size_t, int)>& subject, const Eigen::Vector3d& centre, const Eigen::Vector3d& facing,
                     int count, double radius) {
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero(), around = Eigen::Matrix3d::Zero();
  for (size_t p = 0; p < skin.size(); ++p) {
    for (size_t w = 0; w < skin[p].size(); ++w) {
      const Eigen::Vector3d d = skin[p][w] - centre;
      if (subject(p, static_cast<int>(w))) spread += d * d.transpose();
      if (d.norm() <= 1.5 * radius) around += d * d.transpose();
    }
  }
  const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvectors().col(2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> plane(around);
  auto across = [&](const Eigen::Vector3d& d) { return Eigen::Vector3d(d - d.dot(axis) * axis); };
  Eigen::Vector3d view = Eigen::Vector3d::Zero();
  if (plane.eigenvalues()[1] > 3.0 * plane.eigenvalues()[0]) {
    view = plane.eigenvectors().col(0);
    const Eigen::Vector3d toward = facing.norm() > 0.3 * count ? facing : landmarks.body.forward;
    if (view.dot(toward) < 0.0) view = -view;
  } else if (facing.norm() > 0.3 * count) {
    view = across(facing);
  }
  if (view.norm() < 1e-6) view = across(landmarks.body.forward);
  if (view.norm() < 1e-6) view = across(landmarks.body.lateral);
  view.normalize();
  Eigen::Vector3d up = landmarks.body.up - landmarks.body.up.dot(view) * view;
  if (up.norm() < 1e-6) up = axis - axis.dot(view) * view;
  Camera camera;
  camera.centre = centre;
  camera.forward = -view;
  camera.up = up.normalized();
  camera.half_height = std::max(1.3 * radius, 0.05 * landmarks.body.height);
  return camera;
}

// Draws one request into `drawn_picture`; false when it frames nothing.
bool drawPicture(const PictureScene& scene, const PictureRequest& request, QualityPicture* drawn_picture) {
  const std::vector<PicturePart>& drawn = scene.drawn;
  const LandmarkSet& landmarks = scene.landmarks;
  const size_t c = request.clip;
  auto subject = [&request](size_t p, int w) { return request.on[p][static_cast<size_t>(w)] != 0; };
  const size_t sample = sampleIndex(scene.clips[c], request.time);
  const SkinFrame& frame = scene.frames[c][sample];
  std::vector<std::vector<Eigen::Vector3d>> input(drawn.size()), rig(drawn.size()), normals(drawn.size());
  std::vector<std::vector<double>> along(drawn.size());
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), facing = Eigen::Vector3d::Zero();
  int count = 0;
  for (size_t p = 0; p < drawn.size(); ++p) {
    const PicturePart& part = drawn[p];
    input[p] = weldedPositions(part.surface, skinLinearBlend(part.mesh->positions, part.weights->input, frame));
    rig[p] = weldedPositions(part.surface, skinLinearBlend(part.mesh->positions, part.weights->rig, frame));
    normals[p] = vertexNormals(part.surface.whole, input[p]);
    along[p].resize(input[p].size());
    for (size_t w = 0; w < input[p].size(); ++w) {
      along[p][w] = (rig[p][w] - input[p][w]).dot(normals[p][w]);
      if (!subject(p, static_cast<int>(w))) continue;
      centre += input[p][w];
      facing += normals[p][w];
      ++count;
    }
  }
  if (count == 0) return false;
  centre /= count;
  QualityPicture picture;
  picture.title = request.title;
  picture.clip = scene.clips[c].name;
  picture.time = scene.clips[c].times[sample];
  picture.subject = request.subject_name;
  double radius = 0.0;
  for (size_t p = 0; p < drawn.size(); ++p) {
    for (size_t w = 0; w < rig[p].size(); ++w) {
      if (!subject(p, static_cast<int>(w))) continue;
      radius = std::max(radius, (input[p][w] - centre).norm());
      picture.max_out = std::max(picture.max_out, along[p][w]);
      picture.max_in = std::max(picture.max_in, -along[p][w]);
    }
  }
  // Framed on the input skinning, never the rig: every bake of one character then shows a crease or a
  // muscle from the same camera, so two reports (say with and without --fit-smoothness) compare side by
  // side. The 1.3x margin keeps the rig's bulges in the frame.
  const Camera camera = pictureCamera(landmarks, input, subject, centre, facing, count, radius);
  picture.scale = std::max({picture.max_out, picture.max_in, 1e-4 * landmarks.body.height});
  std::vector<std::vector<Eigen::Vector3f>> colours(drawn.size());
  for (size_t p = 0; p < drawn.size(); ++p)
    // Square root: a move a tenth of the largest still shows a third of the colour.
    for (double a : along[p]) colours[p].push_back(divergingColour(std::copysign(std::sqrt(std::abs(a) / picture.scale), a)));
  std::vector<RenderSurface> plain_input, plain_rig, heat;
  for (size_t p = 0; p < drawn.size(); ++p) {
    plain_input.push_back({&input[p], &drawn[p].surface.whole.triangles, nullptr});
    plain_rig.push_back({&rig[p], &drawn[p].surface.whole.triangles, nullptr});
    heat.push_back({&rig[p], &drawn[p].surface.whole.triangles, &colours[p]});
  }
  const int size = scene.options.picture_size;
  if (request.methods) {
    const DualQuaternionFrame rotations = dualQuaternionFrame(frame);
    std::vector<std::vector<Eigen::Vector3d>> quaternion(drawn.size()), centred(drawn.size());
    std::vector<RenderSurface> plain_quaternion, plain_centred;
    for (size_t p = 0; p < drawn.size(); ++p) {
      const PicturePart& part = drawn[p];
      quaternion[p] = weldedPositions(part.surface, skinDualQuaternion(part.mesh->positions, part.weights->input, rotations));
      centred[p] = weldedPositions(
          part.surface, skinCentreOfRotation(part.mesh->positions, part.weights->input, scene.centres[p], frame, rotations));
      plain_quaternion.push_back({&quaternion[p], &part.surface.whole.triangles, nullptr});
      plain_centred.push_back({&centred[p], &part.surface.whole.triangles, nullptr});
    }
    picture.panels = "plain skinning | dual quaternions | centres of rotation | rig";
    picture.note = request.note;
    picture.image = besideEachOther({renderSurfaces(plain_input, camera, size, size), renderSurfaces(plain_quaternion, camera, size, size),
                                     renderSurfaces(plain_centred, camera, size, size), renderSurfaces(plain_rig, camera, size, size)});
  } else {
    std::vector<RgbImage> panels = {renderSurfaces(plain_input, camera, size, size), renderSurfaces(plain_rig, camera, size, size),
                                    renderSurfaces(heat, camera, size, size)};
    if (request.marker_part >= 0) {
      const size_t p = static_cast<size_t>(request.marker_part), w = static_cast<size_t>(request.marker_vertex);
      drawRing(camera, input[p][w], &panels[0]);
      drawRing(camera, rig[p][w], &panels[1]);
      drawRing(camera, rig[p][w], &panels[2]);
      picture.marker = request.marker;
    }
    picture.image = besideEachOther(panels);
  }
  *drawn_picture = std::move(picture);
  return true;
}

// Each clip: the region whose rig change departs most from the input's, at the rig's extreme.
void addRegionPictureRequests(const DeformationQuality& quality, const std::vector<BodyRegion>& regions,
                              const std::vector<PicturePart>& drawn, std::vector<PictureRequest>* requests) {
  auto regionIndex = [&](const std::string& name) {
    for (size_t r = 0; r < regions.size(); ++r)
      if (regions[r].name == name) return static_cast<int>(r);
    return -1;
  };
  // Welded vertices of each part on a region's triangles.
  auto regionVertices = [&](int r) {
    std::vector<std::vector<char>> on(drawn.size());
    for (size_t p = 0; p < drawn.size(); ++p) {
      on[p].assign(drawn[p].surface.weldedCount(), 0);
      const MeshPart& mesh = *drawn[p].mesh;
      for (int triangle : regions[r].triangles[p])
        for (int corner : mesh.triangles[triangle]) on[p][drawn[p].surface.weld_of_vertex[corner]] = 1;
    }
    return on;
  };
  for (size_t c = 0; c < quality.clips.size(); ++c) {
    const ClipQuality& figures = quality.clips[c];
    // The region SKIN_REGION_VOLUME_LOSS fails in this clip, the one losing most, when there is one (so
    // that the check's finding has its picture); else the region whose rig departs most from the input.
    int worst = -1;
    double worst_gap = -1.0, worst_loss = checkAt<checkIndex("SKIN_REGION_VOLUME_LOSS")>().threshold;
    for (size_t r = 0; r < figures.regions.size(); ++r) {
      const double loss = regionLossBeyondInput(figures.regions[r]);
      if (loss > worst_loss) {
        worst_loss = loss;
        worst = static_cast<int>(r);
        worst_gap = std::numeric_limits<double>::infinity();
      }
      const double gap = std::abs(figures.regions[r].rig.change - figures.regions[r].input.change);
      if (gap > worst_gap) {
        worst_gap = gap;
        worst = static_cast<int>(r);
      }
    }
    if (worst < 0) continue;
    const int r = regionIndex(quality.regions[worst]);
    if (r < 0) continue;
    const double time = figures.regions[worst].rig.time;
    PictureRequest request{figures.clip + " at " + formatSeconds(time) + ": " + quality.regions[worst], quality.regions[worst], c,
                           time, regionVertices(r), false, {}, -1, -1, {}};
    // Where the region loses most against the input skinning, when it loses beyond it.
    if (static_cast<size_t>(worst) < figures.region_places.size() && figures.region_places[worst].at.found) {
      const RegionLossPlace& place = figures.region_places[worst];
      for (size_t p = 0; p < drawn.size(); ++p) {
        if (drawn[p].weights->mesh_part != place.at.mesh_part) continue;
        request.marker_part = static_cast<int>(p);
        request.marker_vertex = drawn[p].surface.weld_of_vertex[static_cast<size_t>(place.at.vertex)];
        request.marker = "the ring: " + regionLossPlaceText(place) + ", of the " +
                         fixedDecimals(regionLossBeyondInput(figures.regions[worst]), 2) + " points the region loses beyond the input skinning";
      }
    }
    requests->push_back(std::move(request));
  }
}

}  // namespace

BakedQuality measureBakedQuality(const Character& character, const LandmarkSet& landmarks, const RegionPreset& preset,
                                 const BakedFileData& file, const BakedQualityOptions& options) {
  BakedQuality out;
  const Skeleton& skeleton = character.skeleton;
  const int joint_count = skeleton.size();
  const bool with_rig = file.rig.present && file.rig.problems.empty() && !file.rig.rig.muscles.empty();
  std::vector<FileMuscle> muscles;
  out.skip_reason = fileMuscles(skeleton, file, with_rig, &muscles);
  if (!out.skip_reason.empty()) return out;
  std::vector<int> fold(joint_count);
  for (int j = 0; j < joint_count; ++j) fold[j] = j;
  for (const FileMuscle& muscle : muscles) fold[muscle.joint] = muscle.carrier;
  // With the extension, muscle m is joint (joint_count + m) of the rig's weights, as the bake measures
  // it, so that the per-muscle figures can find its skin.
  const int measured_muscles = with_rig ? static_cast<int>(muscles.size()) : 0;
  std::vector<int> rig_label(joint_count);
  for (int j = 0; j < joint_count; ++j) rig_label[j] = j;
  for (int m = 0; m < measured_muscles; ++m) rig_label[muscles[m].joint] = joint_count + m;

  Character folded = character;
  std::vector<MeasuredPart> parts;
  out.skip_reason = measuredParts(character, fold, rig_label, options.input, &folded, &parts);
  if (!out.skip_reason.empty()) return out;
  if (options.input) out.input_source = fileNameOf(options.input->source);
  const std::vector<BodyRegion> regions = resolveBodyRegions(folded, landmarks, preset);

  MuscleSet muscle_set;
  muscle_set.body_height = landmarks.body.height;
  for (int m = 0; m < measured_muscles; ++m) {
    MusclePart part;
    part.name = muscles[m].name;
    const runtime::RigMuscle<double>& rig = file.rig.rig.muscles[muscles[m].rig_index];
    part.compression = rig.compression;
    part.stretch = rig.stretch;
    part.kind = file.rig.kinds[muscles[m].rig_index];
    muscle_set.parts.push_back(std::move(part));
  }
  std::vector<std::vector<SkinFrame>> frames;
  const std::vector<MeasuredClip> clips = measuredClips(character, file, muscles, measured_muscles, &frames);

  out.quality = measureDeformationQuality(character, regions, parts, muscle_set, clips, options.threads);
  measureSeams(character, parts, clips, bodyWeldTolerance(landmarks.body.height), options.threads, &out.quality);
  measureJointRegions(character, parts, clips, options.threads, &out.quality);
  const std::vector<Crease> creases = resolveCreases(folded, landmarks, preset.creases);
  measureSurfaceFigures(character, parts, clips, joint_count, landmarks.body.height, options.threads,
                        &out.quality, creases);
  out.measured = true;
  if (!options.pictures) return out;

  // ---- Pictures ----
  const double tolerance = bodyWeldTolerance(landmarks.body.height);
  std::vector<PicturePart> drawn;
  for (const MeasuredPart& part : parts) {
    PicturePart picture{&character.meshes[part.mesh_part], &part, buildVolumeSurface(character.meshes[part.mesh_part], tolerance), {}};
    drawn.push_back(std::move(picture));
  }
  std::vector<RotationCentres> centres;
  std::vector<PictureRequest> requests;
  addRegionPictureRequests(out.quality, regions, drawn, &requests);
  addMusclePictureRequests(out.quality, clips, drawn, joint_count, measured_muscles, &requests);
  addCreasePictureRequests(out.quality, creases, parts, drawn, &requests);
  if (std::any_of(requests.begin(), requests.end(), [](const PictureRequest& request) { return request.methods; })) {
    for (const PicturePart& part : drawn) centres.push_back(optimizedRotationCentres(*part.mesh, part.weights->input, options.threads));
  }
  // Each picture on its own (the requests only read the frames, the surfaces and the figures), in the
  // requests' order.
  const PictureScene scene{landmarks, options, drawn, frames, clips, centres};
  std::vector<QualityPicture> pictures(requests.size());
  std::vector<char> framed(requests.size(), 0);
  parallelForEach(options.threads, requests.size(), [&](size_t i) { framed[i] = drawPicture(scene, requests[i], &pictures[i]); });
  for (size_t i = 0; i < requests.size(); ++i)
    if (framed[i]) out.pictures.push_back(std::move(pictures[i]));
  return out;
}

}  // namespace rigbake
