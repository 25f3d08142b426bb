// Runs an executable the way a user would, for the tests that check what a
// program prints and how it exits (bad input, end-to-end runs).
#pragma once

#include <string>

namespace hamal::testing {

struct CommandResult {
  int status = -1;     // exit status; -1 when killed by a signal
  int signal = 0;      // the signal that ended it, if any
  std::string output;  // stdout and stderr, interleaved
};

// Runs `command_line` through the shell with stderr joined to stdout.
CommandResult runCommand(const std::string& command_line);

}  // namespace hamal::testing
