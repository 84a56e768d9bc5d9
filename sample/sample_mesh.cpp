// The mannequin's skinned body (sample/sample_mesh.h).
//
// Mesh: each body segment is a closed tube (rings of an elliptic cross-section, closed by a pole at
// each end, superellipse end profile), so the whole body is a union of closed surfaces. Skin weights
// are inverse-distance weights to the bone segments (distance divided by the segment's flesh radius,
// to the 4th power), limited to the bones near each body segment, 4 largest kept.
#include "sample/sample_mesh.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <utility>

namespace rigbake::sample_internal {

namespace {

// Influences below this are dropped (and the rest renormalised): they cost a slot and move nothing.
constexpr double kMinWeight = 0.005;

// ---------------------------------------------------------------------------------------------------
// Bone segments for skin weights: a bone owns the stretch of body from its joint towards the next
// joint down the chain; `radius` is the flesh thickness around it, so distances are compared in
// "body radii" and a thin forearm is not outweighed by the thick spine.

struct BoneSegment {
  int joint = -1;
  Eigen::Vector3d from, to;
  double radius = 0.0;
};

double distanceToSegment(const Eigen::Vector3d& p, const BoneSegment& bone) {
  Eigen::Vector3d axis = bone.to - bone.from;
  double length2 = axis.dot(axis);
  double t = length2 > 0.0 ? std::clamp((p - bone.from).dot(axis) / length2, 0.0, 1.0) : 0.0;
  return (p - (bone.from + t * axis)).norm();
}

std::vector<BoneSegment> buildBoneSegments(const CanonicalSkeleton& skeleton) {
  auto pos = [&](const char* name) { return skeleton.world[skeleton.at(name)]; };
  std::vector<BoneSegment> left_and_central = {
      {skeleton.at("JOPelvis1"), {0.0, 0.86, 0.0}, pos("JOBack1"), 0.15},
      {skeleton.at("JOBack1"), pos("JOBack1"), pos("JOBack2"), 0.14},
      {skeleton.at("JOBack2"), pos("JOBack2"), pos("JOBack3"), 0.15},
      {skeleton.at("JOBack3"), pos("JOBack3"), pos("JONeck1"), 0.16},
      {skeleton.at("JONeck1"), pos("JONeck1"), pos("JOHead1"), 0.055},
      {skeleton.at("JOHead1"), pos("JOHead1"), {0.0, 1.75, 0.02}, 0.10},
      // The clavicle carries the top of the shoulder out to the acromion.
      {skeleton.at("JOLeftClavicle1"), pos("JOLeftClavicle1"), pos("JOLeftAcromion1"), 0.07},
      // The scapula joint carries the skin over the shoulder blade down towards its inferior angle.
      {skeleton.at("JOLeftScapula1"), pos("JOLeftScapula1"), {0.095, 1.29, -0.075}, 0.04},
      {skeleton.at("JOLeftUpperArm1"), pos("JOLeftUpperArm1"), pos("LeftUpperArm1Twist0"), 0.05},
      {skeleton.at("LeftUpperArm1Twist0"), pos("LeftUpperArm1Twist0"), pos("JOLeftLowerArm1"), 0.045},
      {skeleton.at("JOLeftLowerArm1"), pos("JOLeftLowerArm1"), pos("LeftLowerArm1Twist0"), 0.04},
      {skeleton.at("LeftLowerArm1Twist0"), pos("LeftLowerArm1Twist0"), pos("JOLeftHand1"), 0.032},
      {skeleton.at("JOLeftHand1"), pos("JOLeftHand1"), {0.92, 1.42, 0.0}, 0.03},
      {skeleton.at("JOLeftUpLeg1"), pos("JOLeftUpLeg1"), pos("JOLeftLeg1"), 0.075},
      {skeleton.at("JOLeftLeg1"), pos("JOLeftLeg1"), pos("JOLeftFoot1"), 0.05},
      {skeleton.at("JOLeftFoot1"), pos("JOLeftFoot1"), pos("JOLeftToe1"), 0.045},
      {skeleton.at("JOLeftToe1"), pos("JOLeftToe1"), {0.09, 0.025, 0.20}, 0.03},
  };
  std::vector<BoneSegment> segments(skeleton.names.size());
  for (const BoneSegment& bone : left_and_central) {
    segments[bone.joint] = bone;
    int twin = skeleton.mirror[bone.joint];
    if (twin != bone.joint) segments[twin] = {twin, mirrorX(bone.from), mirrorX(bone.to), bone.radius};
  }
  return segments;
}

// ---------------------------------------------------------------------------------------------------
// Closed tubes.

struct Tube {
  Eigen::Vector3d start, end;  // axis end points, where the poles close the surface
  Eigen::Vector3d front;       // unit, across the axis: the direction of ring angle 0
  // Half-widths of the cross-section at axis parameter t in [0, 1]: x() along side = axis x front,
  // y() along front.
  std::function<Eigen::Vector2d(double)> radii;
  std::function<Eigen::Vector3d(double)> offset;  // bend of the centre line, may be empty
  double cap_power = 4.0;  // end profile (1 - |u|^p)^(1/p): 2 = ellipsoid, larger = blunter ends
  std::vector<std::string> bones;  // joints that may skin it
};

struct RingCounts {
  int around = 8;  // vertices per ring, even
  int along = 6;   // segments between the poles
};

int tubeVertexCount(const RingCounts& counts) { return counts.around * (counts.along - 1) + 2; }

RingCounts ringCountsFor(const Tube& tube, double spacing) {
  double widest = 0.0;
  for (int i = 1; i < 10; ++i) {
    Eigen::Vector2d r = tube.radii(i / 10.0);
    widest = std::max(widest, kPi * (r.x() + r.y()));  // ellipse perimeter, Euler's estimate
  }
  double length = (tube.end - tube.start).norm();
  RingCounts counts;
  counts.around = std::max(8, 2 * static_cast<int>(std::lround(widest / spacing / 2.0)));
  counts.along = std::max(6, static_cast<int>(std::lround(length / spacing)));
  return counts;
}

struct MeshPiece {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> bones;  // canonical joint indices
};

double signedVolume(const MeshPiece& piece) {
  double volume = 0.0;
  for (const auto& t : piece.triangles)
    volume += piece.positions[t[0]].dot(piece.positions[t[1]].cross(piece.positions[t[2]]));
  return volume / 6.0;
}

// The ring angle tables are built so that angle j and angle (around - j) differ only in the sign of
// the sine, exactly: a tube whose side axis is +X and whose centre line has x = 0 is then an exact
// mirror image of itself.
MeshPiece buildTube(const Tube& tube, const RingCounts& counts) {
  const int around = counts.around;
  const int along = counts.along;
  std::vector<double> sines(around), cosines(around);
  for (int j = 0; j <= around / 2; ++j) {
    double angle = 2.0 * kPi * j / around;
    sines[j] = (j == 0 || 2 * j == around) ? 0.0 : std::sin(angle);
    cosines[j] = j == 0 ? 1.0 : (2 * j == around ? -1.0 : std::cos(angle));
  }
  for (int j = around / 2 + 1; j < around; ++j) {
    sines[j] = -sines[around - j];
    cosines[j] = cosines[around - j];
  }
  const Eigen::Vector3d axis = (tube.end - tube.start).normalized();
  const Eigen::Vector3d side = axis.cross(tube.front);
  auto centre = [&](double t) {
    Eigen::Vector3d c = (1.0 - t) * tube.start + t * tube.end;
    return tube.offset ? Eigen::Vector3d(c + tube.offset(t)) : c;
  };
  MeshPiece piece;
  piece.positions.push_back(centre(0.0));
  for (int i = 1; i < along; ++i) {
    // Rings crowd a little towards the poles, where the profile turns fastest.
    double s = 2.0 * i / along - 1.0;
    double u = 0.5 * s + 0.5 * std::sin(0.5 * kPi * s);
    double t = 0.5 * (u + 1.0);
    double profile = std::pow(1.0 - std::pow(std::abs(u), tube.cap_power), 1.0 / tube.cap_power);
    Eigen::Vector2d r = tube.radii(t) * profile;
    Eigen::Vector3d c = centre(t);
    for (int j = 0; j < around; ++j) piece.positions.push_back(c + (r.x() * sines[j]) * side + (r.y() * cosines[j]) * tube.front);
  }
  piece.positions.push_back(centre(1.0));
  const int last_pole = static_cast<int>(piece.positions.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * around + (j % around); };
  for (int j = 0; j < around; ++j) piece.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < along; ++i) {
    for (int j = 0; j < around; ++j) {
      int a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j + 1), d = ring(i + 1, j);
      piece.triangles.push_back({a, b, c});
      piece.triangles.push_back({a, c, d});
    }
  }
  for (int j = 0; j < around; ++j) piece.triangles.push_back({last_pole, ring(along - 1, j), ring(along - 1, j + 1)});
  // The winding above is consistent; make it face outwards.
  if (signedVolume(piece) < 0.0) {
    for (auto& t : piece.triangles) std::swap(t[1], t[2]);
  }
  return piece;
}

MeshPiece mirrorPiece(const MeshPiece& piece, const CanonicalSkeleton& skeleton) {
  MeshPiece mirrored;
  for (const Eigen::Vector3d& p : piece.positions) mirrored.positions.push_back(mirrorX(p));
  for (const auto& t : piece.triangles) mirrored.triangles.push_back({t[0], t[2], t[1]});
  for (int bone : piece.bones) mirrored.bones.push_back(skeleton.mirror[bone]);
  return mirrored;
}

// Smooth profile through (key, value) pairs: cubic Hermite with Catmull-Rom tangents.
double smoothProfile(const std::vector<std::pair<double, double>>& keys, double x) {
  if (x <= keys.front().first) return keys.front().second;
  if (x >= keys.back().first) return keys.back().second;
  size_t k = 0;
  while (x > keys[k + 1].first) ++k;
  auto slope = [&](size_t i) {
    size_t lo = i == 0 ? 0 : i - 1;
    size_t hi = std::min(i + 1, keys.size() - 1);
    return (keys[hi].second - keys[lo].second) / (keys[hi].first - keys[lo].first);
  };
  double h = keys[k + 1].first - keys[k].first;
  double s = (x - keys[k].first) / h;
  double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * keys[k].second + (s3 - 2 * s2 + s) * h * slope(k) +
         (-2 * s3 + 3 * s2) * keys[k + 1].second + (s3 - s2) * h * slope(k + 1);
}

Eigen::Vector2d taper(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double t, double bulge) {
  return ((1.0 - t) * from + t * to) * (1.0 + bulge * std::sin(kPi * t));
}

// Body segments on the midline and on the left; the right ones are their mirror images.
std::vector<Tube> centralTubes() {
  std::vector<Tube> tubes;
  {
    // Torso from the crotch to the top of the shoulders; widths after adult proportions (hips, waist,
    // ribcage, shoulder girdle). Slightly in front of the spine, which runs near the back.
    static const std::vector<std::pair<double, double>> kHalfWidth = {
        {0.83, 0.150}, {0.92, 0.170}, {1.00, 0.160}, {1.08, 0.140}, {1.18, 0.145},
        {1.30, 0.160}, {1.40, 0.180}, {1.48, 0.185}, {1.53, 0.150}};
    static const std::vector<std::pair<double, double>> kHalfDepth = {
        {0.83, 0.100}, {0.92, 0.110}, {1.00, 0.105}, {1.08, 0.095}, {1.18, 0.100},
        {1.30, 0.110}, {1.40, 0.105}, {1.48, 0.085}, {1.53, 0.070}};
    Tube torso;
    torso.start = {0.0, 0.83, 0.0};
    torso.end = {0.0, 1.53, 0.0};
    torso.front = Eigen::Vector3d::UnitZ();
    torso.radii = [](double t) {
      double y = 0.83 + 0.70 * t;
      return Eigen::Vector2d(smoothProfile(kHalfWidth, y), smoothProfile(kHalfDepth, y));
    };
    torso.offset = [](double) { return Eigen::Vector3d(0.0, 0.0, 0.015); };
    torso.cap_power = 6.0;
    torso.bones = {"JOPelvis1",       "JOBack1",          "JOBack2",         "JOBack3",
                   "JONeck1",         "JOLeftClavicle1",  "JORightClavicle1", "JOLeftScapula1",
                   "JORightScapula1", "JOLeftUpperArm1",  "JORightUpperArm1", "JOLeftUpLeg1",
                   "JORightUpLeg1"};
    tubes.push_back(torso);
  }
  {
    Tube neck;
    neck.start = {0.0, 1.42, 0.0};
    neck.end = {0.0, 1.64, 0.0};
    neck.front = Eigen::Vector3d::UnitZ();
    neck.radii = [](double) { return Eigen::Vector2d(0.055, 0.06); };
    neck.cap_power = 6.0;
    neck.bones = {"JOBack3", "JONeck1", "JOHead1"};
    tubes.push_back(neck);
  }
  {
    // The top pole is the top of the head: exactly kSampleHeight.
    Tube head;
    head.start = {0.0, 1.565, 0.02};
    head.end = {0.0, kSampleHeight, 0.02};
    head.front = Eigen::Vector3d::UnitZ();
    head.radii = [](double) { return Eigen::Vector2d(0.078, 0.10); };
    head.cap_power = 2.0;
    head.bones = {"JONeck1", "JOHead1"};
    tubes.push_back(head);
  }
  return tubes;
}

std::vector<Tube> leftTubes() {
  std::vector<Tube> tubes;
  Eigen::Vector3d front = Eigen::Vector3d::UnitZ();
  auto tube = [&](Eigen::Vector3d start, Eigen::Vector3d end, Eigen::Vector3d tube_front,
                  std::function<Eigen::Vector2d(double)> radii, double cap_power, std::vector<std::string> bones,
                  std::function<Eigen::Vector3d(double)> offset = nullptr) {
    Tube t;
    t.start = start;
    t.end = end;
    t.front = tube_front;
    t.radii = std::move(radii);
    t.offset = std::move(offset);
    t.cap_power = cap_power;
    t.bones = std::move(bones);
    tubes.push_back(t);
  };
  // Arm in a T-pose along +X; side axis is -Y, so radii are (vertical, front-back).
  tube({0.13, 1.42, 0.0}, {0.50, 1.42, 0.0}, front,
       [](double t) { return taper({0.050, 0.052}, {0.040, 0.042}, t, 0.08); }, 4.0,
       {"JOLeftUpperArm1", "LeftUpperArm1Twist0", "JOLeftLowerArm1"});
  tube({0.46, 1.42, 0.0}, {0.76, 1.42, 0.0}, front,
       [](double t) { return taper({0.040, 0.045}, {0.026, 0.032}, t, 0.10); }, 4.0,
       {"LeftUpperArm1Twist0", "JOLeftLowerArm1", "LeftLowerArm1Twist0", "JOLeftHand1"});
  // Hand: flat, palm down.
  tube({0.73, 1.42, 0.0}, {0.93, 1.42, 0.0}, front,
       [](double t) { return taper({0.017, 0.042}, {0.012, 0.038}, t, 0.10); }, 3.0,
       {"LeftLowerArm1Twist0", "JOLeftHand1"});
  // Leg pointing down; side axis is -X, radii (side, front).
  tube({0.09, 1.00, 0.01}, {0.09, 0.46, 0.015}, front,
       [](double t) { return taper({0.085, 0.085}, {0.055, 0.058}, t, 0.03); }, 4.0, {"JOLeftUpLeg1", "JOLeftLeg1"});
  tube({0.09, 0.54, 0.015}, {0.09, 0.06, -0.005}, front,
       [](double t) { return taper({0.055, 0.058}, {0.032, 0.035}, t, 0.10); }, 4.0,
       {"JOLeftUpLeg1", "JOLeftLeg1", "JOLeftFoot1"},
       // The calf bulges backwards.
       [](double t) { return Eigen::Vector3d(0.0, 0.0, -0.012 * std::sin(kPi * t)); });
  // Foot from heel to toe tip along +Z, its sole later set exactly on y = 0.
  tube({0.09, 0.035, -0.06}, {0.09, 0.035, 0.20}, Eigen::Vector3d::UnitY(),
       [](double t) { return taper({0.040, 0.035}, {0.045, 0.018}, t, 0.05); }, 3.0,
       {"JOLeftLeg1", "JOLeftFoot1", "JOLeftToe1"});
  return tubes;
}

// The spacing between vertices that brings the body closest to the wanted vertex count.
double spacingForTarget(const std::vector<Tube>& central, const std::vector<Tube>& left, int target) {
  auto count = [&](double spacing) {
    long total = 0;
    for (const Tube& t : central) total += tubeVertexCount(ringCountsFor(t, spacing));
    for (const Tube& t : left) total += 2L * tubeVertexCount(ringCountsFor(t, spacing));
    return total;
  };
  double fine = 1e-4, coarse = 1.0;  // count(fine) > target >= count(coarse)
  for (int i = 0; i < 60; ++i) {
    double middle = std::sqrt(fine * coarse);
    (count(middle) > target ? fine : coarse) = middle;
  }
  return std::abs(count(fine) - target) < std::abs(count(coarse) - target) ? fine : coarse;
}

// Inverse-distance weights over the piece's bones: (radius / distance)^4, 4 largest kept.
void skinPiece(const MeshPiece& piece, const std::vector<BoneSegment>& segments, const CanonicalSkeleton& skeleton,
               SampleMesh* mesh) {
  struct Influence {
    int joint;
    double weight;
  };
  for (const Eigen::Vector3d& p : piece.positions) {
    std::vector<Influence> influences;
    for (int bone : piece.bones) {
      const BoneSegment& segment = segments[bone];
      double d = std::max(distanceToSegment(p, segment) / segment.radius, 0.05);
      influences.push_back({bone, 1.0 / (d * d * d * d)});
    }
    // Ties are broken by the left/right pair, not by joint index, so that a vertex and its mirror
    // image get the same weights in the same order (and identical float sums).
    auto pair_key = [&](int joint) { return std::min(joint, skeleton.mirror[joint]); };
    std::sort(influences.begin(), influences.end(), [&](const Influence& a, const Influence& b) {
      if (a.weight != b.weight) return a.weight > b.weight;
      if (pair_key(a.joint) != pair_key(b.joint)) return pair_key(a.joint) < pair_key(b.joint);
      return a.joint < b.joint;
    });
    // A tie across the cut (a midline vertex equally near both clavicles) drops both twins rather
    // than favouring one side.
    if (influences.size() > 4) {
      double cut = influences[3].weight;
      bool tie = influences[4].weight == cut;
      influences.resize(4);
      if (tie) influences.erase(std::remove_if(influences.begin(), influences.end(),
                                               [&](const Influence& i) { return i.weight == cut; }),
                                influences.end());
    }
    assert(!influences.empty());
    double total = 0.0;
    for (const Influence& i : influences) total += i.weight;
    influences.erase(std::remove_if(influences.begin() + 1, influences.end(),
                                    [&](const Influence& i) { return i.weight < kMinWeight * total; }),
                     influences.end());
    total = 0.0;
    for (const Influence& i : influences) total += i.weight;
    std::array<int, 4> joints = {0, 0, 0, 0};
    std::array<float, 4> weights = {0.0f, 0.0f, 0.0f, 0.0f};
    float rest = 0.0f;
    for (size_t k = 1; k < influences.size(); ++k) {
      joints[k] = influences[k].joint;
      weights[k] = static_cast<float>(influences[k].weight / total);
      rest += weights[k];
    }
    // The largest weight takes what the others leave, so the floats add up to 1.
    joints[0] = influences[0].joint;
    weights[0] = 1.0f - rest;
    mesh->joints.push_back(joints);
    mesh->weights.push_back(weights);
  }
}

void appendPiece(const MeshPiece& piece, SampleMesh* mesh) {
  int base = static_cast<int>(mesh->positions.size());
  for (const Eigen::Vector3d& p : piece.positions) mesh->positions.push_back(p);
  for (const auto& t : piece.triangles) mesh->triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

void computeNormals(SampleMesh* mesh) {
  mesh->normals.assign(mesh->positions.size(), Eigen::Vector3d::Zero());
  for (const auto& t : mesh->triangles) {
    // Unnormalised face normals weight each face by its area.
    Eigen::Vector3d n = (mesh->positions[t[1]] - mesh->positions[t[0]]).cross(mesh->positions[t[2]] - mesh->positions[t[0]]);
    for (int corner : t) mesh->normals[corner] += n;
  }
  for (Eigen::Vector3d& n : mesh->normals) n.normalize();
}

}  // namespace

SampleMesh buildSampleMesh(const CanonicalSkeleton& skeleton, int target_vertices) {
  std::vector<Tube> central = centralTubes();
  std::vector<Tube> left = leftTubes();
  double spacing = spacingForTarget(central, left, target_vertices);
  std::vector<BoneSegment> segments = buildBoneSegments(skeleton);
  auto bonesOf = [&](const Tube& tube) {
    std::vector<int> bones;
    for (const std::string& name : tube.bones) bones.push_back(skeleton.at(name));
    return bones;
  };
  std::vector<MeshPiece> pieces;
  for (const Tube& tube : central) {
    pieces.push_back(buildTube(tube, ringCountsFor(tube, spacing)));
    pieces.back().bones = bonesOf(tube);
  }
  for (const Tube& tube : left) {
    MeshPiece piece = buildTube(tube, ringCountsFor(tube, spacing));
    piece.bones = bonesOf(tube);
    // Feet stand exactly on y = 0.
    if (tube.bones.back() == "JOLeftToe1") {
      double sole = piece.positions[0].y();
      for (const Eigen::Vector3d& p : piece.positions) sole = std::min(sole, p.y());
      for (Eigen::Vector3d& p : piece.positions) p.y() -= sole;
    }
    MeshPiece twin = mirrorPiece(piece, skeleton);
    pieces.push_back(std::move(piece));
    pieces.push_back(std::move(twin));
  }
  SampleMesh mesh;
  for (const MeshPiece& piece : pieces) {
    appendPiece(piece, &mesh);
    skinPiece(piece, segments, skeleton, &mesh);
  }
  computeNormals(&mesh);
  return mesh;
}

}  // namespace rigbake::sample_internal
