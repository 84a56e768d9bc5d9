// Skeleton evaluation and animation sampling.
// glTF 2.0 specification, Appendix C "Animation Sampler Interpolation Modes": the key interval
// t_k <= t < t_{k+1}, the lerp (1 - u) v_k + u v_{k+1}, the slerp with a = acos|v_k . v_{k+1}| and the
// sign s of that dot product (shortest path), and the cubic Hermite spline
//   p(u) = (2u^3 - 3u^2 + 1) v_k + t_d (u^3 - 2u^2 + u) b_k + (-2u^3 + 3u^2) v_{k+1} + t_d (u^3 - u^2) a_{k+1}
// with t_d = t_{k+1} - t_k, b_k the out-tangent of key k and a_{k+1} the in-tangent of key k+1; a
// rotation spline's result is normalized. Section "Animations": before the first key the first value
// holds and after the last key the last value.
#include "pipeline/pose.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <Eigen/SVD>

namespace rigbake {

namespace {

// Below this angle slerp's sin(a) in the denominator loses all precision; the spec allows a lerp there.
constexpr double kSlerpMinAngle = 1e-10;

struct KeySpan {
  int key = 0;           // the key at or before the sampled time
  double u = 0.0;        // fraction of the way to key + 1, in [0, 1)
  double interval = 0.0;  // t_{key+1} - t_key; 0 when the sample is clamped to one key
};

KeySpan locate(const std::vector<double>& times, double time) {
  assert(!times.empty());
  const int count = static_cast<int>(times.size());
  if (count == 1 || time <= times.front()) return {0, 0.0, 0.0};
  if (time >= times.back()) return {count - 1, 0.0, 0.0};
  // upper_bound skips keys that share a time, so the interval found is never empty.
  const int next = static_cast<int>(std::upper_bound(times.begin(), times.end(), time) - times.begin());
  const int key = next - 1;
  const double interval = times[next] - times[key];
  return {key, (time - times[key]) / interval, interval};
}

enum class KeySlot { kInTangent = 0, kValue = 1, kOutTangent = 2 };

// Reads `width` numbers of key `key` from a track laid out as glTF stores it.
Eigen::Vector4d keyValues(const Track& track, int width, int key, KeySlot slot) {
  const bool cubic = track.interpolation == Interpolation::kCubicSpline;
  const size_t element = cubic ? static_cast<size_t>(key) * 3 + static_cast<size_t>(slot) : static_cast<size_t>(key);
  const size_t first = element * static_cast<size_t>(width);
  assert(first + static_cast<size_t>(width) <= track.values.size());
  Eigen::Vector4d out = Eigen::Vector4d::Zero();
  for (int c = 0; c < width; ++c) out[c] = track.values[first + c];
  return out;
}

// The raw component-wise sample: STEP, LINEAR as a lerp, or CUBICSPLINE. Rotations come here for STEP
// and CUBICSPLINE only; their LINEAR is a slerp.
Eigen::Vector4d sampleComponents(const Track& track, int width, double time) {
  const KeySpan span = locate(track.times, time);
  const Eigen::Vector4d v0 = keyValues(track, width, span.key, KeySlot::kValue);
  if (span.interval == 0.0 || track.interpolation == Interpolation::kStep) return v0;
  const Eigen::Vector4d v1 = keyValues(track, width, span.key + 1, KeySlot::kValue);
  const double u = span.u;
  if (track.interpolation == Interpolation::kLinear) return (1.0 - u) * v0 + u * v1;
  const Eigen::Vector4d out_tangent = keyValues(track, width, span.key, KeySlot::kOutTangent);
  const Eigen::Vector4d in_tangent = keyValues(track, width, span.key + 1, KeySlot::kInTangent);
  const double u2 = u * u;
  const double u3 = u2 * u;
  const double td = span.interval;
  return (2.0 * u3 - 3.0 * u2 + 1.0) * v0 + td * (u3 - 2.0 * u2 + u) * out_tangent + (-2.0 * u3 + 3.0 * u2) * v1 +
         td * (u3 - u2) * in_tangent;
}

Eigen::Quaterniond quaternionOf(const Eigen::Vector4d& xyzw) {
  return Eigen::Quaterniond(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
}

// glTF's slerp: always along the shorter arc, whichever sign the file stored the keys with.
Eigen::Vector4d slerpShortest(const Eigen::Vector4d& q0, const Eigen::Vector4d& q1, double u) {
  const double dot = q0.dot(q1);
  const double sign = dot < 0.0 ? -1.0 : 1.0;
  const double angle = std::acos(std::min(1.0, std::abs(dot)));
  if (angle < kSlerpMinAngle) return ((1.0 - u) * q0 + sign * u * q1).normalized();
  const double sin_angle = std::sin(angle);
  return std::sin(angle * (1.0 - u)) / sin_angle * q0 + sign * std::sin(angle * u) / sin_angle * q1;
}

}  // namespace

Eigen::Vector3d sampleVectorTrack(const Track& track, double time) {
  assert(track.path != AnimatedPath::kRotation);
  return sampleComponents(track, 3, time).head<3>();
}

Eigen::Quaterniond sampleRotationTrack(const Track& track, double time) {
  assert(track.path == AnimatedPath::kRotation);
  if (track.interpolation != Interpolation::kLinear) {
    Eigen::Vector4d q = sampleComponents(track, 4, time);
    // A Hermite blend of unit quaternions is not unit; STEP keys are returned as stored.
    if (track.interpolation == Interpolation::kCubicSpline) q.normalize();
    return quaternionOf(q);
  }
  const KeySpan span = locate(track.times, time);
  const Eigen::Vector4d q0 = keyValues(track, 4, span.key, KeySlot::kValue);
  if (span.interval == 0.0) return quaternionOf(q0);
  const Eigen::Vector4d q1 = keyValues(track, 4, span.key + 1, KeySlot::kValue);
  return quaternionOf(slerpShortest(q0, q1, span.u));
}

Pose composePose(const Skeleton& skeleton, std::vector<Trs> local) {
  assert(static_cast<int>(local.size()) == skeleton.size());
  Pose pose;
  pose.local = std::move(local);
  pose.world.resize(pose.local.size());
  for (int j = 0; j < skeleton.size(); ++j) {
    const int parent = skeleton.parents[j];
    assert(parent < j);
    const Eigen::Affine3d& above = parent >= 0 ? pose.world[parent] : skeleton.root_parent_world[j];
    pose.world[j] = above * pose.local[j].matrix();
  }
  return pose;
}

Pose restPose(const Skeleton& skeleton) { return composePose(skeleton, skeleton.rest_local); }

Pose bindPose(const Skeleton& skeleton) {
  Pose pose;
  pose.world = skeleton.bind_world;
  pose.local.resize(skeleton.bind_world.size());
  for (int j = 0; j < skeleton.size(); ++j) {
    const int parent = skeleton.parents[j];
    const Eigen::Affine3d& above = parent >= 0 ? skeleton.bind_world[parent] : skeleton.root_parent_world[j];
    pose.local[j] = decomposeTrs(above.inverse() * skeleton.bind_world[j]);
  }
  return pose;
}

Pose sampleClip(const Skeleton& skeleton, const Clip& clip, double time) {
  std::vector<Trs> local = skeleton.rest_local;
  for (const Track& track : clip.tracks) {
    assert(track.joint >= 0 && track.joint < skeleton.size());
    if (track.times.empty()) continue;
    Trs& trs = local[track.joint];
    switch (track.path) {
      case AnimatedPath::kTranslation: trs.translation = sampleVectorTrack(track, time); break;
      case AnimatedPath::kRotation: trs.rotation = sampleRotationTrack(track, time); break;
      case AnimatedPath::kScale: trs.scale = sampleVectorTrack(track, time); break;
    }
  }
  return composePose(skeleton, std::move(local));
}

std::vector<double> sampleTimes(const Clip& clip, double fps) {
  std::vector<double> times;
  if (fps <= 0.0) {
    for (const Track& track : clip.tracks) times.insert(times.end(), track.times.begin(), track.times.end());
    std::sort(times.begin(), times.end());
    std::vector<double> merged;
    for (double t : times) {
      if (merged.empty() || t - merged.back() > kSampleTimeTolerance) merged.push_back(t);
    }
    return merged;
  }
  // k / fps rather than a running sum, so the sample times do not drift over long clips.
  for (int k = 0;; ++k) {
    const double t = k / fps;
    if (t >= clip.duration - kSampleTimeTolerance) break;
    times.push_back(t);
  }
  times.push_back(std::max(0.0, clip.duration));
  return times;
}

Eigen::Affine3d skinMatrix(const Pose& pose, const Skeleton& skeleton, int joint) {
  assert(joint >= 0 && joint < skeleton.size());
  return pose.world[joint] * skeleton.bind_world[joint].inverse();
}

Trs decomposeTrs(const Eigen::Affine3d& transform) {
  const Eigen::Matrix3d linear = transform.linear();
  Trs trs;
  trs.translation = transform.translation();
  Eigen::Matrix3d directions;
  for (int k = 0; k < 3; ++k) {
    const double length = linear.col(k).norm();
    assert(length > 0.0);
    directions.col(k) = linear.col(k) / length;
  }
  // A mirrored frame cannot be a rotation; glTF expresses it as a negative scale.
  const double x_sign = directions.determinant() < 0.0 ? -1.0 : 1.0;
  directions.col(0) *= x_sign;
  // The closest rotation to the axis directions (polar decomposition); it is those directions when
  // they are orthogonal, and otherwise spreads the shear a TRS cannot hold evenly over the axes.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(directions, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  for (int k = 0; k < 3; ++k) trs.scale[k] = rotation.col(k).dot(linear.col(k));
  trs.rotation = Eigen::Quaterniond(rotation).normalized();
  return trs;
}

}  // namespace rigbake
