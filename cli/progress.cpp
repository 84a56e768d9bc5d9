#include "cli/progress.h"

#include <unistd.h>

#include <cstdio>

namespace rigbake::cli {

void addProgressOption(CLI::App* command, std::string* mode) {
  command->add_option("--progress", *mode,
                      "Show the stage and elapsed seconds on stderr: auto = when stderr is a terminal (one line, "
                      "erased at the end), always = also into logs and pipes (one line per step), never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
}

ProgressLine::ProgressLine(std::string command, const std::string& mode)
    : command_(std::move(command)), start_(std::chrono::steady_clock::now()) {
  const bool terminal = isatty(STDERR_FILENO) == 1;
  enabled_ = mode == "always" || (mode == "auto" && terminal);
  in_place_ = enabled_ && terminal;
}

ProgressLine::~ProgressLine() { clear(); }

void ProgressLine::clear() {
  if (in_place_ && line_shown_) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
  }
  line_shown_ = false;
}

void ProgressLine::show(const ProgressStep& step) {
  if (!enabled_) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  char count[48] = "";
  // The step under way: `done` are finished.
  if (step.total > 0) {
    const int under_way = step.done < step.total ? step.done + 1 : step.total;
    std::snprintf(count, sizeof(count), ", step %d of %d", under_way, step.total);
  }
  // In place: back to the line's start and clear it first (a shorter line would leave the old tail).
  std::fprintf(stderr, "%s%s: %s%s (%.1f s)%s", in_place_ ? "\r\033[K" : "", command_.c_str(), step.stage, count, seconds,
               in_place_ ? "" : "\n");
  std::fflush(stderr);
  line_shown_ = true;
}

ProgressReport ProgressLine::report() {
  if (!enabled_) return {};
  return [this](const ProgressStep& step) { show(step); };
}

}  // namespace rigbake::cli
