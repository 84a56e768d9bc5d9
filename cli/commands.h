// One file per subcommand; each adds itself to the app and runs through the shared error handling
// in main.cpp. The CLI only parses flags and calls the stages.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace rigbake::cli {

// A subcommand's run function; main.cpp calls it inside the single catch of rigbake::Error.
using Runner = std::function<int()>;

void addSampleCommand(CLI::App& app, Runner* runner);
void addLandmarksCommand(CLI::App& app, Runner* runner);
void addPlaceCommand(CLI::App& app, Runner* runner);
void addBakeCommand(CLI::App& app, Runner* runner);
void addErrorsCommand(CLI::App& app, Runner* runner);
void addValidateCommand(CLI::App& app, Runner* runner);
void addRetargetCommand(CLI::App& app, Runner* runner);
void addBuildCommand(CLI::App& app, Runner* runner);
void addRomCommand(CLI::App& app, Runner* runner);
void addViewCommand(CLI::App& app, Runner* runner);

}  // namespace rigbake::cli
