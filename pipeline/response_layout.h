// The layout of the response fit's unknowns (pipeline/response_fit.h): which keys each fitted muscle
// kind has, where on its drivers they sit, what a key does at amplitude 1, the talk's amplitudes (the
// fit's prior and start), the bounds, and the MuscleResponse curves a set of amplitudes makes. Internal
// to the fit; no surface or pose work here (that is pipeline/fit_surfaces.h).
//
// The talk's response has a shape: at full compression the preset's bulge vector and the
// volume-preserving across-fibre scale 1 / sqrt(compression); when stretched to r the thinning
// 1 / sqrt(r). The fit keeps those shapes and solves, per muscle kind (a part name: left and right
// share it, mirrored), the amplitudes of its keys: compression keys where the poses compress it, one
// stretch key at the longest ratio they reach, and twist keys. Amplitude 1 is the talk's response;
// linear set-driven keys in between, rest = no response.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "anatomy/muscle_set.h"
#include "pipeline/hinge_least_squares.h"
#include "runtime/muscle_rig.h"

namespace rigbake {

struct ResponseFitOptions;

// Per kind: full compression, full stretch, a quarter turn of twist either way, and kBetweenKeys keys
// between rest and the deepest compression the poses reach. The skin's volume loss is not linear in
// the length ratio (a bent elbow loses little at first, then more), so one straight segment from rest
// to full compression bulges too early (measured: ElbowFlexion +0.07 % at 0.43 s, where plain
// skinning has lost only 0.13 %); keys where the poses are let the fitted curve follow it. The same
// keys on the stretch side were tried and made every clip worse (the fit's six steps then end far
// from the optimum: ElbowFlexion -0.53 %, ArmRaise +1.16 %), so a stretched muscle keeps one key.
constexpr int kBetweenKeys = 3;
// Twist, likewise: plain skinning's loss grows like 1 - cos(twist), so each way gets a key at half the
// largest twist the poses reach besides the one at a quarter turn.
// A corrective (anatomy/muscle_set.h PartKind) also gets kBetweenKeys keys between rest and the longest
// stretch: its offset follows plain skinning's web as a raised arm's armpit opens, which grows like a
// muscle's loss does, and it has no twist keys.
enum ResponseKeyIndex {
  kCompressed = 0,
  kStretched = 1,
  kTwistPositive = 2,
  kTwistNegative = 3,
  kHalfTwistPositive = 4,
  kHalfTwistNegative = 5,
  kFirstCompressing = 6,
  kFirstStretching = kFirstCompressing + kBetweenKeys
};
constexpr int kKeys = kFirstStretching + kBetweenKeys;

inline bool isTwistKey(int key) { return key >= kTwistPositive && key <= kHalfTwistNegative; }
inline bool isStretchKey(int key) { return key == kStretched || key >= kFirstStretching; }

// One kind's keys on one driver (length ratio, or twist in quarter turns of its own side's twist: the
// right side's runs the other way), ascending, rest (key -1) included.
struct DriverKeys {
  std::vector<double> at;
  std::vector<int> key;
  void add(double a, int k) {
    at.push_back(a);
    key.push_back(k);
  }
};

// A part's own-side twist in quarter turns, clamped to one.
double sideTwist(const MusclePart& part, const runtime::MuscleDrivers<double>& drivers);

// A key's response at amplitude 1: offsets along up and side (metres) and scale - 1.
struct KeyShape {
  double up = 0.0, side = 0.0, scale = 0.0;
};

// `stretched_at`: the ratio of the kind's stretch key (the volume-preserving thinning is read there).
// A corrective's every key is its offset (the preset's bulge vector), either way; it does not scale.
KeyShape keyShape(const MusclePart& part, int key, double stretched_at);

// Key weights of one part at its drivers (the linear set-driven keys' hat functions).
void keyWeights(const MusclePart& part, const DriverKeys& ratio, const DriverKeys& twist,
                const runtime::MuscleDrivers<double>& drivers, double weights[kKeys]);

// The fit's unknowns: kKeys amplitudes per kind, kind after kind.
struct ResponseLayout {
  std::vector<int> kind;         // per muscle: its kind, -1 when it is not fitted
  int kinds = 0;
  std::vector<char> corrective;  // per kind
  std::vector<DriverKeys> ratio_keys, twist_keys;  // per kind
  std::vector<double> stretched_at;                // per kind: the stretch key's ratio (1 without one)
  int unknowns() const { return kinds * kKeys; }
};

// Kinds (one per fitted part name, in part order) and their keys, placed where `pose_drivers` (each
// pose's drivers, per muscle) take the parts.
ResponseLayout layoutResponses(const MuscleSet& muscles, const std::vector<char>& fit,
                               const std::vector<std::vector<runtime::MuscleDrivers<double>>>& pose_drivers);

// The talk's amplitudes, the prior and the start: its straight segment from rest to full compression
// passes a key at ratio r at (1 - r) / (1 - compression) of the full key; a stretched muscle does
// nothing, nor does a corrective until the volumes ask for it.
Eigen::VectorXd talkAmplitudes(const ResponseLayout& layout, const MuscleSet& muscles);

// How far the poses drive each key (its largest hat weight), a stretch key's in the talk's full-stretch
// thinning: the prior's scale.
std::vector<double> keyReach(const ResponseLayout& layout, const MuscleSet& muscles,
                             const std::vector<std::vector<runtime::MuscleDrivers<double>>>& pose_drivers);

// The amplitudes' bounds (ResponseFitOptions); `talk` from talkAmplitudes().
HingeBounds amplitudeBounds(const ResponseLayout& layout, const Eigen::VectorXd& talk, const ResponseFitOptions& options);

// Every fitted part's response curves at `amplitudes`, marked fitted.
void applyAmplitudes(const ResponseLayout& layout, const Eigen::VectorXd& amplitudes, MuscleSet* muscles);

}  // namespace rigbake
