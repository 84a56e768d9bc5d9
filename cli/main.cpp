// rigbake: rig build and bake pipeline for game characters. main only sets up the subcommands,
// runs the chosen one and turns a rigbake::Error into one line on stderr and its exit status.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

#include "core/error.h"
#include "cli/commands.h"
#include "cli/huge_pages.h"

int main(int argc, char** argv) {
  rigbake::cli::restartWithMallocTunables(argv);
  CLI::App app{
      "rigbake builds joint-based muscle rigs for skinned humanoid glTF/GLB/VRM characters and bakes them.\n"
      "Positions are in the scene's units (glTF: metres).\n\n"
      "Typical run:\n"
      "  rigbake sample -o mannequin.glb\n"
      "  rigbake landmarks mannequin.glb\n"
      "  rigbake place mannequin.glb -o muscles.json\n"
      "  rigbake bake mannequin.glb --muscles muscles.json --influences 10 -o baked.glb --stats stats.json\n",
      "rigbake"};
  app.set_version_flag("--version", RIGBAKE_VERSION);
  app.require_subcommand(1);
  rigbake::cli::Runner runner;
  rigbake::cli::addSampleCommand(app, &runner);
  rigbake::cli::addLandmarksCommand(app, &runner);
  rigbake::cli::addPlaceCommand(app, &runner);
  rigbake::cli::addBakeCommand(app, &runner);
  rigbake::cli::addErrorsCommand(app, &runner);
  rigbake::cli::addValidateCommand(app, &runner);
  rigbake::cli::addRetargetCommand(app, &runner);
  rigbake::cli::addBuildCommand(app, &runner);
  rigbake::cli::addRomCommand(app, &runner);
  rigbake::cli::addViewCommand(app, &runner);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << rigbake::printableLine(std::string("USAGE: ") + e.what() + " (see rigbake --help)") << "\n";
    return static_cast<int>(rigbake::ExitCode::kUsage);
  }
  try {
    const int status = runner ? runner() : 0;
    // What --json printed may still sit in stdio's buffer: a stdout that cannot take it (/dev/full, a
    // closed pipe) is a failed run, not exit 0 with the figures lost.
    errno = 0;
    const int flushed = std::fflush(stdout), reason = errno;
    if (flushed != 0 || std::ferror(stdout))
      rigbake::fail(rigbake::errc::IO_WRITE_FAILED, "-", std::string("cannot write to standard output: ") +
                                                (reason != 0 ? std::strerror(reason) : "an earlier write failed"));
    return status;
  } catch (const rigbake::Error& e) {
    std::cerr << e.what() << "\n";
    return static_cast<int>(e.exitCode());
  } catch (const std::exception& e) {
    std::cerr << rigbake::printableLine(std::string("INTERNAL: ") + e.what()) << "\n";
    return static_cast<int>(rigbake::ExitCode::kInternal);
  }
}
