// One validation of a baked file as a job, shared by `rigbake validate` and the batch build: load and
// resolve the character (an unresolvable landmark is a finding, not a failure to report), read its
// muscle file, run every check; then write report.json, report.junit.xml and report.html.
#pragma once

#include <string>
#include <vector>

#include "app/character.h"
#include "pipeline/progress.h"
#include "pipeline/checks.h"

namespace rigbake::app {

// The Khronos check's skip reason when the request did not ask for it. It names no flag: the command
// line says how to ask (`rigbake validate` prints "pass --khronos" beside it); build never runs it.
inline constexpr const char* kKhronosNotRequested = "not requested";

struct ValidationRequest {
  std::string baked;          // the baked .glb / .gltf / .vrm
  std::string muscles;        // its muscle JSON, or empty to skip the muscle checks
  // The character the file was baked from, read as the bake read it; empty path: none, and the input
  // skinning is the file's weights handed back to the carriers (BakedQualityOptions::input).
  CharacterSource input;
  std::string preset = "gow_biped";  // preset for a positions-only muscle file: a name or a path
  std::string map;            // a naming map forced on the skeleton (CharacterSource::map); empty: detect
  ValidationConfig config;
  bool khronos = false;       // also run the Khronos glTF-Validator when it is installed
  std::string rom;            // ROM preset (name or path) whose clips are measured too, or empty
  std::string regions = "body";  // region preset for the deformation-quality figures (name or path)
  bool pictures = true;       // render the deformation pictures for report.html
  ProgressReport progress;    // told of each stage as it starts; may be empty
  NoteReport notes;           // told of the file's notes as it is loaded (app/character.h); may be empty
  int threads = 0;            // for the per-frame measures; 0: one per core (the reports are the same at any count)
};

// The file is parsed once, also when a landmark does not resolve (that becomes the landmark check's
// finding).
Report validateJob(const ValidationRequest& request, const Presets& presets);

// Renders all three reports first, then commits them as one OutputBatch, so a failure leaves none.
struct ReportPaths {
  std::string json, junit, html;
};
ReportPaths reportPathsIn(const std::string& directory);
// `threads` encode the pictures (0: one per core); the files are the same at any count.
void writeReports(const Report& report, const ReportPaths& paths, int threads = 0);

}  // namespace rigbake::app
