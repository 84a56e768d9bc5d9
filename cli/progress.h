// A long command's progress on stderr, for people watching it: the stage it is in, the fit's pass,
// the seconds so far. With --progress auto (the default) only when stderr is a terminal, on one line
// rewritten in place and erased when the command ends, so logs and pipes see only the results;
// always: also into a log or pipe, one line per step; never: nothing. Never on stdout (--json's).
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <string>

#include "pipeline/progress.h"

namespace rigbake::cli {

// --progress auto|always|never on `command`.
void addProgressOption(CLI::App* command, std::string* mode);

class ProgressLine {
 public:
  // `command`: how the lines begin ("rigbake bake"); `mode`: auto, always or never.
  ProgressLine(std::string command, const std::string& mode);
  ~ProgressLine();  // erases a line shown in place, also when the command fails (before its error)
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void show(const ProgressStep& step);
  void show(const char* stage) { show(ProgressStep{stage, 0, 0}); }
  // Erases a line shown in place (before the command prints its results).
  void clear();
  // A report for the pipeline that shows each step here; empty when nothing is shown.
  ProgressReport report();

 private:
  std::string command_;
  bool enabled_ = false;
  bool in_place_ = false;  // a terminal: rewrite one line
  bool line_shown_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace rigbake::cli
