// See command.h.
#include "testing/command.h"

#include <sys/wait.h>

#include <cstdio>

namespace hamal::testing {

CommandResult runCommand(const std::string& command_line) {
  CommandResult out;
  const std::string command = command_line + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.output.append(buffer, n);
  const int status = pclose(pipe);
  if (WIFEXITED(status)) out.status = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) out.signal = WTERMSIG(status);
  // The shell reports a signal-killed child as 128 + signal.
  if (out.status > 128) out.signal = out.status - 128;
  return out;
}

}  // namespace hamal::testing
