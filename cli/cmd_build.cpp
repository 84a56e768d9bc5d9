// `rigbake build manifest.json`: many characters in one run, in parallel, incrementally, with a
// summary for CI; or `--emit-ninja` to let Ninja schedule single-character runs.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/error.h"
#include "app/build_job.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "formats/atomic_file.h"
#include "formats/build_manifest.h"
#include "formats/json_text.h"
#include "formats/report_junit.h"

namespace rigbake::cli {
namespace {

using app::JobOutcome;
using app::JobStatus;
using app::failedJob;
using app::jobStatusName;

struct BuildCommandOptions {
  std::string manifest;
  int jobs = 0;
  std::string emit_ninja;
  bool emit_ninja_given = false;  // --emit-ninja '' must not mean "build"
  std::string shard;
  std::string character;
  bool summary_only = false;
  bool force = false;
  bool json = false;
  std::string progress = "auto";
  PresetOptions presets;
};

// The summary lists the characters in manifest order with no timings, so it is the same whatever -j.
void writeSummary(const BuildManifest& manifest, const std::vector<JobOutcome>& outcomes) {
  nlohmann::json characters = nlohmann::json::array();
  int failed = 0, built = 0, up_to_date = 0;
  std::string cases;
  for (const JobOutcome& outcome : outcomes) {
    failed += outcome.status == JobStatus::kFailed;
    built += outcome.status == JobStatus::kBuilt;
    up_to_date += outcome.status == JobStatus::kUpToDate;
    characters.push_back({{"name", outcome.name},
                          {"status", jobStatusName(outcome.status)},
                          {"error", outcome.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(outcome.error)},
                          {"checks_failed", outcome.checks_failed}});
    cases += "  <testcase classname=\"rigbake.build\" name=\"" + xmlEscape(outcome.name) + "\">";
    if (outcome.status == JobStatus::kFailed) cases += "<failure message=\"" + xmlEscape(outcome.error) + "\"/>";
    cases += "</testcase>\n";
  }
  nlohmann::json summary = {{"manifest", fileNameOf(manifest.file)},
                            {"characters", characters},
                            {"counts", {{"total", outcomes.size()}, {"built", built}, {"up_to_date", up_to_date}, {"failed", failed}}}};
  writeFileAtomically(manifest.out + "/summary.json", jsonText(summary) + "\n");
  writeFileAtomically(manifest.out + "/summary.junit.xml",
                      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"rigbake build\" tests=\"" +
                          std::to_string(outcomes.size()) + "\" failures=\"" + std::to_string(failed) +
                          "\" errors=\"0\" skipped=\"0\">\n" + cases + "</testsuite>\n");
}

// A character whose muscles_from source failed fails too; its line has a code like every failure.
JobOutcome sourceFailed(const BuildManifest& manifest, const BuildCharacter& character) {
  const Error error(errc::BUILD_SOURCE_FAILED, manifest.file + "#" + character.pointer + "/muscles_from",
                    "muscles_from character '" + character.muscles_from + "' failed");
  return failedJob(character, error.what());
}

int run(const BuildCommandOptions& options) {
  const std::string presets_dir = presetsDirectory(options.presets);
  if (options.emit_ninja_given && options.emit_ninja.empty()) fail(errc::USAGE, "--emit-ninja", "names no file (an empty path)");
  // Each character's naming map is the manifest's to give: a flag for all would not be in the stamps.
  if (!options.presets.map.empty())
    fail(errc::USAGE, "--map", "build takes the naming map from the manifest (\"map\", docs/build.md), not from a flag");
  if (options.emit_ninja_given) checkOutputPath(options.emit_ninja);
  BuildManifest manifest = readBuildManifest(options.manifest, presets_dir);
  if (options.emit_ninja_given) {
    // The rules run this rigbake again, one character (--character) or the summary (--summary-only) each.
    const std::string manifest_path = std::filesystem::absolute(options.manifest).string();
    const std::string build =
        shellWord(std::filesystem::canonical("/proc/self/exe").string()) + " build " + shellWord(manifest_path);
    const NinjaCommands commands = {"rigbake build --emit-ninja", build + " --character $name", build + " --summary-only"};
    writeFileAtomically(options.emit_ninja, ninjaFile(manifest, manifest_path, commands));
    std::cerr << "wrote " << options.emit_ninja << ": " << manifest.characters.size() << " character edges\n";
    return 0;
  }
  int shard_index = 0, shard_count = 1;
  if (!options.shard.empty()) {
    size_t slash = options.shard.find('/');
    try {
      shard_index = std::stoi(options.shard.substr(0, slash));
      shard_count = std::stoi(options.shard.substr(slash + 1));
    } catch (const std::exception&) {
      shard_count = 0;
    }
    if (slash == std::string::npos || shard_count < 1 || shard_index < 0 || shard_index >= shard_count)
      fail(errc::USAGE, "--shard", "must be I/N with 0 <= I < N, e.g. 0/4 (got '" + options.shard + "')");
  }
  std::vector<int> selected;
  for (int index : buildOrder(manifest)) {
    const BuildCharacter& c = manifest.characters[index];
    if (!options.character.empty() && c.name != options.character) continue;
    if (!inShard(manifest, index, shard_index, shard_count) && options.character.empty()) continue;
    selected.push_back(index);
  }
  if (!options.character.empty() && selected.empty())
    fail(errc::USAGE, "--character", "no character named '" + options.character + "' in " + options.manifest);

  // One build at a time per output folder: two with different options interleaved their outputs. The
  // edges of an --emit-ninja graph (--character) write disjoint folders, so they share the lock; a whole
  // build, a shard or the summary takes it alone.
  createDirectories(manifest.out);
  const bool exclusive = options.character.empty();
  FolderLock lock;
  if (!lock.tryLock(manifest.out, exclusive))
    fail(errc::BUILD_OUTPUT_LOCKED, manifest.out, "another rigbake build is writing into this folder (it holds " +
                                                  manifest.out + "/.rigbake-lock); wait for it to finish");
  // Temporary files of runs killed before their renames; only now, with no other build writing here.
  if (exclusive) {
    std::vector<std::string> outputs = {manifest.out + "/summary.json", manifest.out + "/summary.junit.xml"};
    for (const BuildCharacter& character : manifest.characters) {
      const CharacterOutputs out = characterOutputs(manifest, character);
      for (const std::string& path : out.files()) outputs.push_back(path);
      outputs.push_back(out.stamp);
    }
    removeTemporaryLeftovers(outputs);
  }

  if (options.summary_only) {
    std::vector<JobOutcome> outcomes;
    for (size_t i = 0; i < manifest.characters.size(); ++i) outcomes.push_back(app::readJobOutcome(manifest, manifest.characters[i]));
    writeSummary(manifest, outcomes);
    return 0;
  }

  const app::Presets shared = app::loadPresets(presets_dir);
  const int jobs = options.jobs > 0 ? options.jobs : std::max(1u, std::thread::hardware_concurrency());
  // The cores the characters running at once leave each bake (its outputs are the same at any count).
  const int workers = std::max(1, std::min<int>(jobs, static_cast<int>(selected.size())));
  const int bake_threads = std::max(1, static_cast<int>(std::max(1u, std::thread::hardware_concurrency())) / workers);
  // A character waits for its muscles_from source; a failed source fails its dependents.
  std::vector<JobOutcome> outcomes(manifest.characters.size());
  std::vector<int> state(manifest.characters.size(), 0);  // 0 waiting, 1 running, 2 finished
  std::mutex mutex;
  std::condition_variable changed;
  size_t finished = 0;
  // On a terminal, one line under the finished characters' lines: how many are done and which run.
  ProgressLine progress("rigbake build", options.progress);
  auto showRunning = [&]() {  // with the mutex held
    std::string running;
    for (int index : selected)
      if (state[index] == 1) running += (running.empty() ? "" : ", ") + manifest.characters[index].name;
    const std::string line = std::to_string(finished) + " of " + std::to_string(selected.size()) + " characters done" +
                             (running.empty() ? "" : "; building " + running);
    progress.show(line.c_str());
  };
  auto next = [&]() -> int {
    for (int index : selected) {
      if (state[index] != 0) continue;
      const std::string& from = manifest.characters[index].muscles_from;
      if (from.empty()) return index;
      for (int source : selected) {
        if (manifest.characters[source].name == from && state[source] == 2) return index;
      }
      bool source_selected = false;
      for (int source : selected) source_selected |= manifest.characters[source].name == from;
      if (!source_selected) return index;  // --character: the source was built by an earlier run
    }
    return -1;
  };
  auto worker = [&]() {
    std::unique_lock<std::mutex> lock(mutex);
    while (finished < selected.size()) {
      int index = next();
      if (index < 0) {
        changed.wait(lock);
        continue;
      }
      state[index] = 1;
      const BuildCharacter& character = manifest.characters[index];
      const JobOutcome* source = nullptr;
      for (int s : selected) {
        if (manifest.characters[s].name == character.muscles_from) source = &outcomes[s];
      }
      bool source_failed = source && source->status == JobStatus::kFailed;
      showRunning();
      lock.unlock();
      auto start = std::chrono::steady_clock::now();
      JobOutcome outcome = source_failed ? sourceFailed(manifest, character)
                                         : app::runCharacterJob(manifest, character, shared, options.force, bake_threads);
      double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      lock.lock();
      outcomes[index] = outcome;
      state[index] = 2;
      ++finished;
      progress.clear();
      std::cerr << "[" << finished << "/" << selected.size() << "] " << character.name << ": "
                << jobStatusName(outcome.status) << std::fixed << std::setprecision(2) << " (" << seconds << " s)"
                << (outcome.error.empty() ? "" : " " + outcome.error) << "\n";
      if (finished < selected.size()) showRunning();
      changed.notify_all();
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::min<int>(jobs, static_cast<int>(selected.size())); ++t) threads.emplace_back(worker);
  for (std::thread& thread : threads) thread.join();
  progress.clear();

  std::vector<JobOutcome> ordered;
  for (size_t i = 0; i < manifest.characters.size(); ++i) {
    if (state[i] == 2) ordered.push_back(outcomes[i]);
  }
  if (options.character.empty()) writeSummary(manifest, ordered);
  int failures = 0;
  for (const JobOutcome& outcome : ordered) {
    if (outcome.status != JobStatus::kFailed) continue;
    ++failures;
    std::cerr << "FAILED " << outcome.name << ": " << outcome.error << "\n";
  }
  if (options.json) {
    nlohmann::json result = nlohmann::json::array();
    for (const JobOutcome& outcome : ordered)
      result.push_back({{"name", outcome.name}, {"status", jobStatusName(outcome.status)}, {"error", outcome.error}});
    std::cout << jsonText(result) << "\n";
  }
  if (failures > 0)
    fail(errc::BUILD_FAILED, options.manifest, std::to_string(failures) + " of " + std::to_string(ordered.size()) + " characters failed (listed above and in summary.json)");
  return 0;
}

}  // namespace

void addBuildCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<BuildCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "build",
      "Build many characters from a manifest (docs/build.md): place or retarget muscles, bake, validate, and write "
      "OUT/NAME/{NAME.glb, muscles.json, report.json, report.junit.xml, report.html} plus OUT/summary.json and "
      "summary.junit.xml. Runs in parallel, skips characters whose inputs did not change (content hashes), goes on past "
      "failures and names them all at the end (exit 4).");
  command->add_option("manifest", options->manifest, "Build manifest (JSON)")->required();
  command->add_option("-j,--jobs", options->jobs, "Characters built at once (default: one per core)")->check(CLI::NonNegativeNumber);
  CLI::Option* emit_ninja =
      command->add_option("--emit-ninja", options->emit_ninja, "Write a Ninja file with one edge per character instead of building");
  command->add_option("--shard", options->shard, "Build only slice I of N (e.g. 0/4) for CI matrix jobs; deterministic");
  command->add_option("--character", options->character, "Build only this character (what the Ninja edges run)");
  command->add_flag("--summary-only", options->summary_only, "Only gather the characters' results into the summary");
  command->add_flag("--force", options->force, "Rebuild even characters whose inputs did not change");
  addPresetOptions(command, &options->presets);
  command->add_flag("--json", options->json, "Print each character's status as JSON on stdout");
  addProgressOption(command, &options->progress);
  command->callback([runner, options, emit_ninja]() {
    options->emit_ninja_given = emit_ninja->count() > 0;
    *runner = [options]() { return run(*options); };
  });
}

}  // namespace rigbake::cli
