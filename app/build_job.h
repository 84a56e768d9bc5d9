// One character of a batch build (`rigbake build`, docs/build.md): bake it (app/bake_job.h: muscles
// placed, read or retargeted), write its outputs, validate them (app/validate_job.h), stamp them.
#pragma once

#include <string>
#include <vector>

#include "app/character.h"
#include "pipeline/build_plan.h"

namespace rigbake::app {

enum class JobStatus { kBuilt, kUpToDate, kFailed };
const char* jobStatusName(JobStatus status);

struct JobOutcome {
  std::string name;
  JobStatus status = JobStatus::kFailed;
  std::string error;      // the one-line error of a failed character
  int checks_failed = 0;  // validation checks of error severity that failed
};

// Never throws for a character's own problems: they become a failed outcome, so the build goes on.
// `presets`: read once (app/character.h) and shared, read-only, by every job.
// `bake_threads`: BakeOptions::threads of the character's bake (the outputs do not depend on it).
JobOutcome runCharacterJob(const BuildManifest& manifest, const BuildCharacter& character, const Presets& presets,
                           bool force, int bake_threads = 1);
JobOutcome failedJob(const BuildCharacter& character, const std::string& error);
// The outcome a previous run stored beside the character's outputs (for --summary-only).
JobOutcome readJobOutcome(const BuildManifest& manifest, const BuildCharacter& character);

}  // namespace rigbake::app
