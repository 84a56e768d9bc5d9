// rigbake runtime: a muscle rig in another precision. A rig read or built in double (as rigbake bakes
// with) is what an engine evaluates in float; converting keeps every index and casts every number,
// then prepares the result (prepareMuscleRig) so that a job accepts it. Header only, no dependency.
#pragma once

#include "runtime/muscle_rig.h"

namespace rigbake::runtime {

template <typename To, typename From>
MuscleRig<To> convertMuscleRig(const MuscleRig<From>& rig) {
  MuscleRig<To> out;
  out.joint_count = rig.joint_count;
  for (const RigMuscle<From>& m : rig.muscles) {
    RigMuscle<To> r;
    r.origin_joint = m.origin_joint;
    r.insertion_joint = m.insertion_joint;
    r.carrier_joint = m.carrier_joint;
    for (int k = 0; k < 3; ++k) {
      r.origin_local[k] = static_cast<To>(m.origin_local[k]);
      r.insertion_local[k] = static_cast<To>(m.insertion_local[k]);
      r.fibre_local[k] = static_cast<To>(m.fibre_local[k]);
      r.up_local[k] = static_cast<To>(m.up_local[k]);
      r.twist_axis_local[k] = static_cast<To>(m.twist_axis_local[k]);
    }
    for (int k = 0; k < 4; ++k) r.insertion_bind_in_origin[k] = static_cast<To>(m.insertion_bind_in_origin[k]);
    for (int k = 0; k < 2; ++k) r.driver_offset[k] = static_cast<To>(m.driver_offset[k]);
    for (int k = 0; k < 16; ++k) r.skinned_in_carrier[k] = static_cast<To>(m.skinned_in_carrier[k]);
    r.rest_length = static_cast<To>(m.rest_length);
    r.compression = static_cast<To>(m.compression);
    r.stretch = static_cast<To>(m.stretch);
    r.driver_fraction = static_cast<To>(m.driver_fraction);
    r.ratio_key_begin = m.ratio_key_begin;
    r.ratio_key_count = m.ratio_key_count;
    r.twist_key_begin = m.twist_key_begin;
    r.twist_key_count = m.twist_key_count;
    out.muscles.push_back(r);
  }
  for (const ResponseKey<From>& k : rig.keys)
    out.keys.push_back({static_cast<To>(k.at), static_cast<To>(k.up), static_cast<To>(k.side), static_cast<To>(k.scale)});
  prepareMuscleRig(&out);
  return out;
}

}  // namespace rigbake::runtime
