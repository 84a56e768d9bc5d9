// The muscle rig in runtime/ (runtime/muscle_rig.h): MuscleRigJob evaluates the muscles four at a
// time in SIMD lanes, reads the twist from the joints' frames and the response curves as sums of
// clamped segments (docs/runtime.md). These tests hold it to a straightforward evaluation of the same
// equations, muscle by muscle, in the form they had before (quaternions for the twist, a search for the
// curve segment), on real characters' clips and on random rigs and poses, and check that the job
// refuses a rig prepareMuscleRig() has not prepared.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "anatomy/placement.h"
#include "anatomy_fixture.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "runtime/muscle_rig.h"
#include "runtime/muscle_rig_convert.h"

namespace rigbake {
namespace runtime_muscle_rig_test {

// runtime/muscle_rig.cpp's MuscleRigJob::Run as it was before it moved to lanes (commit 2ab786d), one
// muscle at a time, kept apart from its namespace and the names Vec3 and Quat (so that nothing here
// is found for the runtime's): the reference the job must reproduce within rounding. Not to be updated
// when the equations change on purpose; change both then, and the docs.
namespace reference {

template <typename Real>
struct V3 {
  Real x, y, z;
};
template <typename Real>
V3<Real> operator+(V3<Real> a, V3<Real> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename Real>
V3<Real> operator-(V3<Real> a, V3<Real> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename Real>
V3<Real> operator*(Real s, V3<Real> a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename Real>
Real dot(V3<Real> a, V3<Real> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename Real>
V3<Real> cross(V3<Real> a, V3<Real> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Real>
Real length(V3<Real> a) { return std::sqrt(dot(a, a)); }
template <typename Real>
V3<Real> normalized(V3<Real> a) {
  const Real n = length(a);
  return n > Real(0) ? (Real(1) / n) * a : a;
}
template <typename Real>
V3<Real> load(const Real* p) { return {p[0], p[1], p[2]}; }
template <typename Real>
V3<Real> transformPoint(const Real* m, V3<Real> p) {
  return {m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12], m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
          m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]};
}
template <typename Real>
V3<Real> transformDirection(const Real* m, V3<Real> d) {
  return {m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z, m[2] * d.x + m[6] * d.y + m[10] * d.z};
}
template <typename Real>
void storeFrame(V3<Real> x, V3<Real> y, V3<Real> z, V3<Real> position, Real* out) {
  const Real values[16] = {x.x, x.y, x.z, 0, y.x, y.y, y.z, 0, z.x, z.y, z.z, 0, position.x, position.y, position.z, 1};
  for (int k = 0; k < 16; ++k) out[k] = values[k];
}
template <typename Real>
struct Q {
  Real x, y, z, w;
};
template <typename Real>
Q<Real> multiply(Q<Real> a, Q<Real> b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
template <typename Real>
Q<Real> conjugate(Q<Real> q) { return {-q.x, -q.y, -q.z, q.w}; }
template <typename Real>
Q<Real> rotationOf(const Real* m) {
  const V3<Real> x = normalized(V3<Real>{m[0], m[1], m[2]});
  const V3<Real> y0 = {m[4], m[5], m[6]};
  const V3<Real> y = normalized(y0 - dot(y0, x) * x);
  const V3<Real> z = cross(x, y);
  const Real trace = x.x + y.y + z.z;
  Q<Real> q;
  if (trace > Real(0)) {
    const Real s = std::sqrt(trace + Real(1)) * Real(2);
    q = {(y.z - z.y) / s, (z.x - x.z) / s, (x.y - y.x) / s, Real(0.25) * s};
  } else if (x.x > y.y && x.x > z.z) {
    const Real s = std::sqrt(Real(1) + x.x - y.y - z.z) * Real(2);
    q = {Real(0.25) * s, (y.x + x.y) / s, (z.x + x.z) / s, (y.z - z.y) / s};
  } else if (y.y > z.z) {
    const Real s = std::sqrt(Real(1) + y.y - x.x - z.z) * Real(2);
    q = {(y.x + x.y) / s, Real(0.25) * s, (z.y + y.z) / s, (z.x - x.z) / s};
  } else {
    const Real s = std::sqrt(Real(1) + z.z - x.x - y.y) * Real(2);
    q = {(z.x + x.z) / s, (z.y + y.z) / s, Real(0.25) * s, (x.y - y.x) / s};
  }
  return q;
}
template <typename Real>
Real clampValue(Real v, Real lo, Real hi) { return v < lo ? lo : (v > hi ? hi : v); }
template <typename Real>
void addCurve(const runtime::ResponseKey<Real>* keys, int count, Real at, runtime::ResponseKey<Real>* sum) {
  if (count <= 0) return;
  runtime::ResponseKey<Real> value = keys[0];
  if (at >= keys[count - 1].at) {
    value = keys[count - 1];
  } else if (at > keys[0].at) {
    int k = 1;
    while (keys[k].at < at) ++k;
    const runtime::ResponseKey<Real>& a = keys[k - 1];
    const runtime::ResponseKey<Real>& b = keys[k];
    const Real span = b.at - a.at;
    const Real t = span > Real(0) ? (at - a.at) / span : Real(1);
    value.up = a.up + t * (b.up - a.up);
    value.side = a.side + t * (b.side - a.side);
    value.scale = a.scale + t * (b.scale - a.scale);
  }
  sum->up += value.up;
  sum->side += value.side;
  sum->scale += value.scale - Real(1);
}

template <typename Real>
struct Evaluation {
  std::vector<Real> skinned, helpers;
  std::vector<runtime::MuscleDrivers<Real>> drivers;
};

template <typename Real>
Evaluation<Real> evaluate(const runtime::MuscleRig<Real>& rig, const Real* joints) {
  Evaluation<Real> out;
  out.skinned.resize(16 * rig.muscles.size());
  out.helpers.resize(48 * rig.muscles.size());
  for (size_t m = 0; m < rig.muscles.size(); ++m) {
    const runtime::RigMuscle<Real>& muscle = rig.muscles[m];
    const Real* origin_joint = joints + 16 * muscle.origin_joint;
    const Real* insertion_joint = joints + 16 * muscle.insertion_joint;
    const V3<Real> origin = transformPoint(origin_joint, load(muscle.origin_local));
    const V3<Real> insertion = transformPoint(insertion_joint, load(muscle.insertion_local));
    runtime::MuscleDrivers<Real> drivers;
    drivers.ratio = length(insertion - origin) / muscle.rest_length;
    drivers.clamped_ratio = clampValue(drivers.ratio, muscle.compression, muscle.stretch);
    const Real* b = muscle.insertion_bind_in_origin;
    const Q<Real> q0 = {b[0], b[1], b[2], b[3]};
    const Q<Real> delta = multiply(multiply(conjugate(rotationOf(origin_joint)), rotationOf(insertion_joint)), conjugate(q0));
    const Real* a = muscle.twist_axis_local;
    Real twist = Real(2) * std::atan2(delta.x * a[0] + delta.y * a[1] + delta.z * a[2], delta.w);
    const Real pi = Real(3.14159265358979323846);
    if (twist > pi) twist -= Real(2) * pi;
    if (twist <= -pi) twist += Real(2) * pi;
    drivers.twist = twist;
    out.drivers.push_back(drivers);

    // Helpers.
    const V3<Real> carried_fibre = normalized(transformDirection(origin_joint, load(muscle.fibre_local)));
    const V3<Real> carried_up_raw = normalized(transformDirection(origin_joint, load(muscle.up_local)));
    const V3<Real> carried_up = normalized(carried_up_raw - dot(carried_up_raw, carried_fibre) * carried_fibre);
    const V3<Real> segment = insertion - origin;
    const Real current = length(segment);
    const V3<Real> fibre = current > Real(1e-6) * muscle.rest_length ? (Real(1) / current) * segment : carried_fibre;
    const Real cosine = dot(carried_fibre, fibre);
    V3<Real> swung = carried_up;
    if (Real(1) + cosine >= Real(1e-12)) {
      const V3<Real> k = cross(carried_fibre, fibre);
      swung = cosine * carried_up + cross(k, carried_up) + (dot(k, carried_up) / (Real(1) + cosine)) * k;
    }
    const V3<Real> up = normalized(swung - dot(swung, fibre) * fibre);
    const V3<Real> side = cross(fibre, up);
    const V3<Real> driver =
        origin + (muscle.driver_fraction * current) * fibre + muscle.driver_offset[0] * up + muscle.driver_offset[1] * side;
    Real* helpers = out.helpers.data() + 48 * m;
    storeFrame(fibre, up, side, origin, helpers);
    storeFrame(Real(-1) * fibre, up, Real(-1) * side, insertion, helpers + 16);
    storeFrame(fibre, up, side, driver, helpers + 32);

    // The skinned joint.
    runtime::ResponseKey<Real> response;
    response.at = 0;
    addCurve(rig.keys.data() + muscle.ratio_key_begin, muscle.ratio_key_count, drivers.clamped_ratio, &response);
    addCurve(rig.keys.data() + muscle.twist_key_begin, muscle.twist_key_count, drivers.twist, &response);
    Real local[16];
    const Real* k = muscle.skinned_in_carrier;
    for (int c = 0; c < 16; ++c) local[c] = k[c];
    for (int r = 0; r < 3; ++r) local[12 + r] += k[4 + r] * response.up + k[8 + r] * response.side;
    for (int r = 0; r < 3; ++r) {
      local[4 + r] *= response.scale;
      local[8 + r] *= response.scale;
    }
    const Real* w = joints + 16 * muscle.carrier_joint;
    Real* o = out.skinned.data() + 16 * m;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 3; ++r) {
        o[c * 4 + r] = w[r] * local[c * 4] + w[4 + r] * local[c * 4 + 1] + w[8 + r] * local[c * 4 + 2] + (c == 3 ? w[12 + r] : Real(0));
      }
      o[c * 4 + 3] = c == 3 ? Real(1) : Real(0);
    }
  }
  return out;
}

}  // namespace reference

bool verboseRun() { return std::getenv("RIGBAKE_TEST_VERBOSE") != nullptr; }


// The largest gap between the job and the reference over frames of joint matrices, |a - b| /
// max(1, |b|) for the matrices and radians (or ratio) for the drivers. Also checks that the skinned
// matrices do not depend on whether helpers and drivers are asked for.
struct Gap {
  double skinned = 0, helpers = 0, ratio = 0, twist = 0;
  size_t frames = 0;
};

double relative(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

// The difference of two angles in (-pi, pi], across the wrap (a twist of pi - e and one of -pi + e
// are 2e apart).
double angleGap(double a, double b) {
  const double two_pi = 2.0 * 3.14159265358979323846;
  double d = std::fmod(std::abs(a - b), two_pi);
  return std::min(d, two_pi - d);
}

template <typename Real>
void addGap(const runtime::MuscleRig<Real>& rig, const Real* joints, Gap* gap) {
  const size_t muscles = rig.muscles.size();
  std::vector<Real> skinned(16 * muscles, Real(-7)), alone(16 * muscles, Real(-7)), helpers(48 * muscles, Real(-7));
  std::vector<runtime::MuscleDrivers<Real>> drivers(muscles);
  runtime::MuscleRigJob<Real> job;
  job.rig = &rig;
  job.joint_matrices = runtime::Span<const Real>(joints, 16 * static_cast<size_t>(rig.joint_count));
  job.skinned_matrices = runtime::Span<Real>(alone);
  REQUIRE(job.Run());
  job.skinned_matrices = runtime::Span<Real>(skinned);
  job.helper_matrices = runtime::Span<Real>(helpers);
  job.drivers = runtime::Span<runtime::MuscleDrivers<Real>>(drivers);
  REQUIRE(job.Run());
  // The twist of a muscle whose twist keys are rest keys is read only for the drivers, and then does
  // not reach the skinned matrix: asking for drivers and helpers changes no skinned number.
  REQUIRE(alone == skinned);
  const reference::Evaluation<Real> expected = reference::evaluate(rig, joints);
  for (size_t i = 0; i < skinned.size(); ++i) gap->skinned = std::max(gap->skinned, relative(skinned[i], expected.skinned[i]));
  for (size_t i = 0; i < helpers.size(); ++i) gap->helpers = std::max(gap->helpers, relative(helpers[i], expected.helpers[i]));
  for (size_t m = 0; m < muscles; ++m) {
    gap->ratio = std::max({gap->ratio, relative(drivers[m].ratio, expected.drivers[m].ratio),
                           relative(drivers[m].clamped_ratio, expected.drivers[m].clamped_ratio)});
    gap->twist = std::max(gap->twist, angleGap(drivers[m].twist, expected.drivers[m].twist));
  }
  ++gap->frames;
}

// Every muscle's twist keys replaced by a curve that moves (so that the skinned-only path evaluates
// the twist too) on every other muscle, and by rest keys on the rest.
void giveTwistResponses(runtime::MuscleRig<double>* rig) {
  for (size_t m = 0; m < rig->muscles.size(); ++m) {
    runtime::RigMuscle<double>& muscle = rig->muscles[m];
    muscle.twist_key_begin = static_cast<int>(rig->keys.size());
    muscle.twist_key_count = 3;
    const double moves = m % 2 == 0 ? 1.0 : 0.0;
    rig->keys.push_back({-1.5, 0.02 * moves, -0.01 * moves, 1.0 + 0.3 * moves});
    rig->keys.push_back({0.0, 0.0, 0.0, 1.0});
    rig->keys.push_back({1.5, 0.015 * moves, 0.004 * moves, 1.0 + 0.2 * moves});
  }
}

struct CharacterGaps {
  Gap as_double, as_float;
};

CharacterGaps characterGaps(const std::string& path) {
  test::Resolved r = test::resolveShipped(path);
  const Skeleton& skeleton = r.character.skeleton;
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  runtime::MuscleRig<double> source = buildMuscleRig(muscles, skeleton);
  giveTwistResponses(&source);
  const runtime::MuscleRig<double> as_double = runtime::convertMuscleRig<double>(source);
  const runtime::MuscleRig<float> as_float = runtime::convertMuscleRig<float>(source);
  CharacterGaps gaps;
  for (const Clip& clip : r.character.clips) {
    for (double t : sampleTimes(clip, 0.0)) {
      const std::vector<double> joints = jointMatrices(sampleClip(skeleton, clip, t));
      const std::vector<float> float_joints(joints.begin(), joints.end());
      addGap(as_double, joints.data(), &gaps.as_double);
      addGap(as_float, float_joints.data(), &gaps.as_float);
    }
  }
  return gaps;
}

void printGap(const char* what, const Gap& g) {
  std::printf("runtime muscle rig vs reference, %s: %zu frames, skinned %.2e, helpers %.2e, ratio %.2e, twist %.2e rad\n", what,
              g.frames, g.skinned, g.helpers, g.ratio, g.twist);
}

TEST_CASE("runtime muscle rig: the job equals the muscle-by-muscle reference within rounding on every clip of real characters") {
  std::vector<std::string> paths = {test::sampleGlbPath()};
  for (const char* asset : {"CesiumMan.glb", "Quaternius_Cyberpunk_Character.glb"}) {
    if (std::find(test::sharedAssetNames().begin(), test::sharedAssetNames().end(), asset) == test::sharedAssetNames().end()) continue;
    const std::string path = test::requireAsset(asset);
    if (!path.empty()) paths.push_back(path);
  }
  for (const std::string& path : paths) {
    INFO(path);
    const CharacterGaps gaps = characterGaps(path);
    CHECK(gaps.as_double.frames > 0);
    // Double: the same numbers up to rounding (measured 1e-15 and below).
    CHECK(gaps.as_double.skinned < 1e-12);
    CHECK(gaps.as_double.helpers < 1e-12);
    CHECK(gaps.as_double.ratio < 1e-12);
    CHECK(gaps.as_double.twist < 1e-12);
    // Float: within float's rounding of the reference's own float evaluation (measured 3e-7 and below
    // for the matrices).
    CHECK(gaps.as_float.skinned < 1e-6);
    CHECK(gaps.as_float.helpers < 1e-6);
    CHECK(gaps.as_float.ratio < 1e-6);
    CHECK(gaps.as_float.twist < 3e-6);  // 1.8e-6 on Cyberpunk, where both floats are 1.2e-6 from double
    if (verboseRun()) {
      printGap((path + ", double").c_str(), gaps.as_double);
      printGap((path + ", float").c_str(), gaps.as_float);
    }
  }
}

// A random rig on random joints: every joint matrix a rotation with a non-uniform scale and a shear
// (where the orthonormal frame differs from the rotation), curves of 0 to 5 keys, rest-key twist
// curves, carriers that are the origin, the insertion or another joint, muscle counts no multiple of
// the lane count, and poses that turn each joint up to 0.9 rad from its bind, so that no
// origin-insertion pair swings near 180 degrees, where the twist is not defined.
struct RandomRig {
  runtime::MuscleRig<double> rig;
  std::vector<std::vector<double>> frames;
};

std::vector<double> randomRotation(std::mt19937& random, double max_angle) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double x, y, z, n;
  do {
    x = unit(random), y = unit(random), z = unit(random);
    n = std::sqrt(x * x + y * y + z * z);
  } while (n < 0.1 || n > 1.0);
  const double angle = max_angle * std::uniform_real_distribution<double>(0.0, 1.0)(random);
  const double s = std::sin(angle / 2) / n, w = std::cos(angle / 2);
  x *= s, y *= s, z *= s;
  return {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w), 2 * (x * y - z * w), 1 - 2 * (x * x + z * z),
          2 * (y * z + x * w),     2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
}

// a * b for column-major 3x3 matrices.
std::vector<double> product3(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> out(9, 0.0);
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) out[3 * c + r] += a[3 * k + r] * b[3 * c + k];
    }
  }
  return out;
}

RandomRig randomRig(unsigned seed, int joints, int muscles, int frames) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto vector3 = [&](double scale) { return std::vector<double>{scale * unit(random), scale * unit(random), scale * unit(random)}; };
  RandomRig out;
  out.rig.joint_count = joints;
  std::vector<std::vector<double>> binds, shapes, positions;
  for (int j = 0; j < joints; ++j) {
    binds.push_back(randomRotation(random, 1.4));  // two binds differ by at most 2.8 rad
    // A non-uniform scale with a shear, applied in the joint's own frame.
    std::vector<double> shape = {0.85 + 0.3 * (unit(random) + 1) / 2, 0.1 * unit(random), 0.05 * unit(random), 0.1 * unit(random),
                                 0.85 + 0.3 * (unit(random) + 1) / 2, 0.05 * unit(random), 0.0, 0.0, 0.85 + 0.3 * (unit(random) + 1) / 2};
    shapes.push_back(shape);
    positions.push_back(vector3(1.0));
  }
  for (int f = 0; f < frames; ++f) {
    std::vector<double> matrices(16 * joints, 0.0);
    for (int j = 0; j < joints; ++j) {
      const std::vector<double> linear = product3(product3(binds[j], randomRotation(random, 0.9)), shapes[j]);
      double* m = matrices.data() + 16 * j;
      for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) m[4 * c + r] = linear[3 * c + r];
      }
      const std::vector<double> moved = vector3(0.05);
      for (int r = 0; r < 3; ++r) m[12 + r] = positions[j][r] + moved[r];
      m[15] = 1.0;
    }
    out.frames.push_back(matrices);
  }
  std::uniform_int_distribution<int> joint(0, joints - 1);
  for (int i = 0; i < muscles; ++i) {
    runtime::RigMuscle<double> m;
    // Carriers as rigs have them: mostly the origin or the insertion joint, sometimes another; and now
    // and then a muscle whose origin and insertion ride one joint (then carrier, too).
    m.origin_joint = joint(random);
    const int shape = std::uniform_int_distribution<int>(0, 5)(random);
    do {
      m.insertion_joint = joint(random);
    } while (shape != 0 && m.insertion_joint == m.origin_joint);
    if (shape == 0) m.insertion_joint = m.origin_joint;
    m.carrier_joint = shape <= 2 ? m.origin_joint : (shape == 3 ? m.insertion_joint : joint(random));
    const std::vector<double> o = vector3(0.2), in = vector3(0.2), fibre = vector3(1.0), up = vector3(1.0), axis = vector3(1.0);
    const double axis_length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (int k = 0; k < 3; ++k) {
      m.origin_local[k] = o[k];
      m.insertion_local[k] = in[k];
      m.fibre_local[k] = fibre[k];
      m.up_local[k] = up[k];
      m.twist_axis_local[k] = axis[k] / axis_length;
    }
    // The bind rotation of the insertion in the origin: the two joints' bind rotations' relative one.
    const std::vector<double>& a = binds[m.origin_joint];
    const std::vector<double>& b = binds[m.insertion_joint];
    const std::vector<double> at = {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]};
    const std::vector<double> r = product3(at, b);
    const double w = std::sqrt(std::max(0.0, 1.0 + r[0] + r[4] + r[8])) / 2;
    REQUIRE(w > 0.15);
    m.insertion_bind_in_origin[0] = (r[5] - r[7]) / (4 * w);
    m.insertion_bind_in_origin[1] = (r[6] - r[2]) / (4 * w);
    m.insertion_bind_in_origin[2] = (r[1] - r[3]) / (4 * w);
    m.insertion_bind_in_origin[3] = w;
    m.rest_length = 0.5 + (unit(random) + 1) / 2;
    m.compression = 0.6;
    m.stretch = 1.4;
    m.driver_fraction = 0.5;
    m.driver_offset[0] = 0.02 * unit(random);
    m.driver_offset[1] = 0.02 * unit(random);
    const std::vector<double> k_rotation = randomRotation(random, 3.1);
    for (int c = 0; c < 3; ++c) {
      for (int row = 0; row < 3; ++row) m.skinned_in_carrier[4 * c + row] = k_rotation[3 * c + row];
      m.skinned_in_carrier[4 * c + 3] = 0.0;
    }
    const std::vector<double> k_position = vector3(0.3);
    for (int row = 0; row < 3; ++row) m.skinned_in_carrier[12 + row] = k_position[row];
    m.skinned_in_carrier[15] = 1.0;
    // Curves: 0 to 5 ratio keys around 1, 0 to 5 twist keys over (-2, 2) rad, every third twist curve
    // of rest keys.
    for (int curve = 0; curve < 2; ++curve) {
      const int count = std::uniform_int_distribution<int>(0, 5)(random);
      const int begin = static_cast<int>(out.rig.keys.size());
      const bool rest = curve == 1 && i % 3 == 0;
      for (int k = 0; k < count; ++k) {
        const double at = curve == 0 ? 0.6 + 0.8 * (k + 0.5 * (unit(random) + 1) / 2) / std::max(1, count)
                                     : -2.0 + 4.0 * (k + 0.5 * (unit(random) + 1) / 2) / std::max(1, count);
        out.rig.keys.push_back({at, rest ? 0.0 : 0.03 * unit(random), rest ? 0.0 : 0.03 * unit(random),
                                rest ? 1.0 : 1.0 + 0.5 * unit(random)});
      }
      (curve == 0 ? m.ratio_key_begin : m.twist_key_begin) = begin;
      (curve == 0 ? m.ratio_key_count : m.twist_key_count) = count;
    }
    out.rig.muscles.push_back(m);
  }
  REQUIRE(std::string(runtime::rigProblem(out.rig)).empty());
  return out;
}

TEST_CASE("runtime muscle rig: the job equals the muscle-by-muscle reference on random rigs with scaled, sheared joints") {
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    INFO("seed " << seed);
    const RandomRig random = randomRig(seed, 9, 5 * seed + 2, 40);
    const runtime::MuscleRig<double> as_double = runtime::convertMuscleRig<double>(random.rig);
    const runtime::MuscleRig<float> as_float = runtime::convertMuscleRig<float>(random.rig);
    Gap gap_double, gap_float;
    for (const std::vector<double>& frame : random.frames) {
      const std::vector<float> float_frame(frame.begin(), frame.end());
      addGap(as_double, frame.data(), &gap_double);
      addGap(as_float, float_frame.data(), &gap_float);
    }
    CHECK(gap_double.skinned < 1e-12);
    CHECK(gap_double.helpers < 1e-12);
    CHECK(gap_double.ratio < 1e-12);
    CHECK(gap_double.twist < 1e-12);
    CHECK(gap_float.skinned < 1e-5);
    CHECK(gap_float.helpers < 1e-5);
    CHECK(gap_float.ratio < 1e-6);
    CHECK(gap_float.twist < 1e-5);
    if (verboseRun()) {
      printGap(("random rig " + std::to_string(seed) + ", double").c_str(), gap_double);
      printGap(("random rig " + std::to_string(seed) + ", float").c_str(), gap_float);
    }
  }
}

// One muscle between two joints, the insertion turned about the fibre by `angle` from its bind: the
// twist driver reads the angle, in (-pi, pi], across the whole turn.
TEST_CASE("runtime muscle rig: the twist driver reads a pure twist across the whole turn, pi included") {
  runtime::MuscleRig<double> rig;
  rig.joint_count = 2;
  runtime::RigMuscle<double> m;
  m.origin_joint = 0;
  m.insertion_joint = 1;
  m.carrier_joint = 0;
  m.rest_length = 2.0;
  const double s = std::sqrt(1.0 / 3.0);
  m.twist_axis_local[0] = s, m.twist_axis_local[1] = s, m.twist_axis_local[2] = -s;
  rig.muscles.push_back(m);
  runtime::prepareMuscleRig(&rig);
  const double pi = 3.14159265358979323846;
  for (double angle : {0.0, 0.3, -0.3, 2.0, -2.0, 3.1, -3.1, pi - 1e-9, -(pi - 1e-9), pi}) {
    INFO("angle " << angle);
    // Joint 1's frame is the rotation by `angle` about the axis (Rodrigues).
    const double c = std::cos(angle), sn = std::sin(angle), t = 1 - c;
    const double x = s, y = s, z = -s;
    std::vector<double> joints = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,
                                  t * x * x + c, t * x * y + sn * z, t * x * z - sn * y, 0,
                                  t * x * y - sn * z, t * y * y + c, t * y * z + sn * x, 0,
                                  t * x * z + sn * y, t * y * z - sn * x, t * z * z + c, 0, 2, 0, 0, 1};
    std::vector<double> skinned(16);
    std::vector<runtime::MuscleDrivers<double>> drivers(1);
    runtime::MuscleRigJob<double> job;
    job.rig = &rig;
    job.joint_matrices = joints;
    job.skinned_matrices = skinned;
    job.drivers = drivers;
    REQUIRE(job.Run());
    CHECK(drivers[0].twist > -pi);
    CHECK(drivers[0].twist <= pi);
    CHECK(angleGap(drivers[0].twist, angle) < 1e-12);
    CHECK(drivers[0].ratio == Approx(1.0));  // the joints' origins 2 apart, the rest length
  }
}

TEST_CASE("runtime muscle rig: the job refuses a rig prepareMuscleRig has not prepared, or has not since it changed") {
  const RandomRig random = randomRig(4, 5, 6, 1);
  runtime::MuscleRig<double> rig = random.rig;  // not prepared
  std::vector<double> skinned(16 * rig.muscles.size(), -7.0);
  runtime::MuscleRigJob<double> job;
  job.rig = &rig;
  job.joint_matrices = runtime::Span<const double>(random.frames[0]);
  job.skinned_matrices = skinned;
  CHECK_FALSE(job.Validate());
  CHECK_FALSE(job.Run());
  CHECK(std::all_of(skinned.begin(), skinned.end(), [](double v) { return v == -7.0; }));  // nothing written

  runtime::prepareMuscleRig(&rig);
  CHECK(job.Validate());
  CHECK(job.Run());
  CHECK(skinned[15] == 1.0);

  // A muscle added after preparing: refused until prepared again (its output would be missing).
  rig.muscles.push_back(rig.muscles.front());
  skinned.assign(16 * rig.muscles.size(), -7.0);
  job.skinned_matrices = skinned;
  CHECK_FALSE(job.Run());
  CHECK(skinned[0] == -7.0);
  runtime::prepareMuscleRig(&rig);
  CHECK(job.Run());
  const reference::Evaluation<double> expected = reference::evaluate(rig, random.frames[0].data());
  for (size_t i = 0; i < skinned.size(); ++i) CHECK(relative(skinned[i], expected.skinned[i]) < 1e-12);

  // The spans: too few joints, too small outputs.
  job.joint_matrices = runtime::Span<const double>(random.frames[0].data(), 16 * 4);
  CHECK_FALSE(job.Validate());
  job.joint_matrices = runtime::Span<const double>(random.frames[0]);
  std::vector<double> short_helpers(48 * rig.muscles.size() - 1);
  job.helper_matrices = short_helpers;
  CHECK_FALSE(job.Validate());
  job.helper_matrices = {};
  std::vector<runtime::MuscleDrivers<double>> short_drivers(rig.muscles.size() - 1);
  job.drivers = short_drivers;
  CHECK_FALSE(job.Validate());
  job.drivers = {};
  CHECK(job.Validate());

  // An empty rig needs no preparing.
  runtime::MuscleRig<double> empty;
  empty.joint_count = 5;
  runtime::MuscleRigJob<double> nothing;
  nothing.rig = &empty;
  nothing.joint_matrices = runtime::Span<const double>(random.frames[0]);
  CHECK(nothing.Run());
}

}  // namespace runtime_muscle_rig_test
}  // namespace rigbake
