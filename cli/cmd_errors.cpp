// `rigbake errors`: the table of stable error codes and exit statuses (also in docs/errors.md).
#include <iostream>

#include "core/error.h"
#include "cli/commands.h"

namespace rigbake::cli {

void addErrorsCommand(CLI::App& app, Runner* runner) {
  CLI::App* command = app.add_subcommand("errors", "List every error code rigbake can report, with its exit status");
  command->callback([runner]() {
    *runner = []() {
      for (const ErrorCode& info : kErrorCodes)
        std::cout << info.name << "\t" << static_cast<int>(info.exit) << "\t" << info.meaning << "\n";
      return 0;
    };
  });
}

}  // namespace rigbake::cli
