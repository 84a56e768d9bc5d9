#include "pipeline/leg_coverage.h"

#include <Eigen/Geometry>
#include <vector>

#include "pipeline/muscle_weights.h"
#include "pipeline/pose.h"

namespace rigbake {

LegCoverage legCoverage(const Character& character, const LandmarkSet& landmarks, const MuscleSet& muscles) {
  LegCoverage coverage;
  const Skeleton& skeleton = character.skeleton;
  std::vector<int> leg_joints;
  for (const char* name : {"upper_leg_l", "upper_leg_r", "lower_leg_l", "lower_leg_r"}) {
    if (!landmarks.has(name)) continue;
    const Landmark& landmark = landmarks.get(name);
    if (landmark.resolved && !landmark.from_joint.empty() && landmark.joint >= 0) leg_joints.push_back(landmark.joint);
  }
  coverage.legs = leg_joints.size() == 4;
  if (!coverage.legs) return coverage;
  std::vector<char> is_leg(skeleton.size(), 0);
  for (int joint : leg_joints) is_leg[joint] = 1;
  const std::vector<int>& parents = spannedHierarchy(muscles, skeleton);
  for (const MusclePart& part : muscles.parts)
    for (int joint : spannedJoints(parents, part)) coverage.covered = coverage.covered || is_leg[joint];
  const Pose rest = restPose(skeleton);
  for (const Clip& clip : character.clips) {
    for (double time : sampleTimes(clip, 0.0)) {
      const Pose pose = sampleClip(skeleton, clip, time);
      for (int joint : leg_joints) {
        const double turn = Eigen::AngleAxisd(pose.local[joint].rotation * rest.local[joint].rotation.inverse()).angle() * 180.0 / M_PI;
        if (turn > coverage.largest_turn_deg) {
          coverage.largest_turn_deg = turn;
          coverage.clip = clip.name;
          coverage.joint = skeleton.names[joint];
        }
      }
    }
  }
  return coverage;
}

}  // namespace rigbake
