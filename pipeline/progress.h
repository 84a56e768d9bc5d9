// What a long stage tells its caller as it goes, for a command line to show. Pipeline functions never
// print: they call the report they are given, on the thread that called them, between steps (never
// from a worker thread), and what it does cannot change any result.
#pragma once

#include <functional>

namespace rigbake {

struct ProgressStep {
  const char* stage = "";  // what is being done, lower case, e.g. "fitting the muscles' response"
  int done = 0;            // steps of the stage finished ...
  int total = 0;           // ... out of this many; 0: the stage has no count (it has just started)
};

using ProgressReport = std::function<void(const ProgressStep&)>;

// Calls `report` when there is one.
inline void reportProgress(const ProgressReport& report, const char* stage, int done = 0, int total = 0) {
  if (report) report(ProgressStep{stage, done, total});
}

}  // namespace rigbake
