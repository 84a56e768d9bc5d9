// One character of a batch build: load, muscles (placed, read or retargeted), bake, validate, write.
#pragma once

#include <string>
#include <vector>

#include "anatomy/presets.h"
#include "pipeline/build_plan.h"

namespace rigbake::cli {

enum class JobStatus { kBuilt, kUpToDate, kFailed };
const char* jobStatusName(JobStatus status);

struct JobOutcome {
  std::string name;
  JobStatus status = JobStatus::kFailed;
  std::string error;      // the one-line error of a failed character
  int checks_failed = 0;  // validation checks of error severity that failed
};

// Presets read once and shared, read-only, by every job.
struct SharedPresets {
  std::string directory;
  std::vector<NamingMap> maps;
  LandmarkRules rules;
  std::string regions;  // the body-region preset file for the deformation-quality figures
};
SharedPresets loadSharedPresets(const std::string& presets_dir);

// Never throws for a character's own problems: they become a failed outcome, so the build goes on.
// `bake_threads`: BakeOptions::threads of the character's bake (the outputs do not depend on it).
JobOutcome runCharacterJob(const BuildManifest& manifest, const BuildCharacter& character, const SharedPresets& presets,
                           bool force, int bake_threads = 1);
JobOutcome failedJob(const BuildCharacter& character, const std::string& error);
// The outcome a previous run stored beside the character's outputs (for --summary-only).
JobOutcome readJobOutcome(const BuildManifest& manifest, const BuildCharacter& character);

}  // namespace rigbake::cli
