// The names of the bake's options as flags and manifests spell them. Apart from pipeline/bake.cpp so
// that a reader of those names (formats/build_manifest.cpp, and the fuzz target that runs it, fuzz/)
// does not link the whole bake.
#include <string>

#include "pipeline/bake.h"

namespace rigbake {

const char* responseModeName(ResponseMode mode) {
  switch (mode) {
    case ResponseMode::kAuto: return "auto";
    case ResponseMode::kFit: return "fit";
    case ResponseMode::kKeep: return "keep";
  }
  return "auto";
}

bool parseResponseMode(const std::string& name, ResponseMode* mode) {
  for (ResponseMode candidate : {ResponseMode::kAuto, ResponseMode::kFit, ResponseMode::kKeep}) {
    if (name == responseModeName(candidate)) {
      *mode = candidate;
      return true;
    }
  }
  return false;
}

const char* muscleMotionName(MuscleMotion motion) {
  switch (motion) {
    case MuscleMotion::kRuntime: return "runtime";
    case MuscleMotion::kSampled: return "sampled";
    case MuscleMotion::kBoth: return "both";
  }
  return "runtime";
}

bool parseMuscleMotion(const std::string& name, MuscleMotion* motion) {
  for (MuscleMotion candidate : {MuscleMotion::kRuntime, MuscleMotion::kSampled, MuscleMotion::kBoth}) {
    if (name == muscleMotionName(candidate)) {
      *motion = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace rigbake
