// What the hamal executables share on the command line: the registry with
// built-ins and plugins, --list-factors / --list-backends (the executables
// list what is registered, as g2o_cli -listTypes does), repeatable flags
// that gflags keeps only the last of,
// back-end spec lists, the --help text, and the error convention
// ("hamal_x: error: <message>", exit status 1, no uncaught exception).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/registry.h"
#include "factors/between_factor.h"

namespace hamal::apps {

// An old spelling of a flag, kept for one release. Declared at file scope
// beside the flag it stands for,
//   HAMAL_FLAG_ALIAS(backends, backend);
// so that "--backends=x" (or "--backends x") is read as "--backend=x" and a
// line on stderr says "--backends is an old spelling; use --backend". Giving
// both spellings in one invocation is an Error.
struct FlagAlias {
  FlagAlias(const char* old_name, const char* new_name);
};
#define HAMAL_FLAG_ALIAS(old_name, new_name) \
  static const ::hamal::apps::FlagAlias hamal_flag_alias_##old_name(#old_name, #new_name)

// Rewrites every alias of argv as its current flag (warning once per alias);
// repeatedFlag and parseCommandLine call it, so a program need not. A second
// call finds nothing left to rewrite.
void applyFlagAliases(int argc, char** argv);

// Rewrites "--list-factors" as "--list_factors" (and any "--a-b[=v]"), so
// both spellings work with gflags, which knows only underscores.
void normalizeFlagNames(int argc, char** argv);

// Every value of a flag that may be repeated, in order: --name=v, --name v,
// -name=v, -name v. gflags itself keeps only the last one.
std::vector<std::string> repeatedFlag(int argc, char** argv, const std::string& name);

// Splits on `separator`, trims blanks, drops empty pieces.
std::vector<std::string> splitList(const std::string& text, char separator);

// Back-end specs from a list. Specs are separated by ';'. A ',' separates
// specs too, except inside one's options: a piece that has '=' but no ':' is
// an option of the spec before it ("ceres:max_iterations=50,every=2,cholesky"
// is two specs), which is unambiguous because back-end names may not hold
// '=' (registry.h); an option never opens a ';' entry. "all" stands for
// every registered back-end.
std::vector<std::string> splitBackendSpecs(const std::string& text, const Registry& registry);

// --plugin, --list-factors and --list-backends are defined once, in cli.cc,
// for every executable. printListings prints what the two --list flags ask
// for and returns true when it printed anything (the program then exits 0).
bool printListings(const Registry& registry);

// --residual: "thesis" | "measurement" (or "measurement-frame").
BetweenResidual parseResidual(const std::string& name);

// registerBuiltins, then the plugins given (each value may be a
// comma-separated list; an empty entry is an error), then HAMAL_PLUGIN_PATH's.
void setUpRegistry(Registry& registry, const std::vector<std::string>& plugin_flags);

// Checks, before any work, that `path` (given by --`flag`) can be written:
// not a directory, in a directory that exists and is writable. Empty: no
// output asked for, nothing to check.
void checkOutputPath(const std::string& flag, const std::string& path);

// checkOutputPath for every (flag, path) of one invocation, and refuses two
// flags naming one file, which would keep only the last one written. Paths
// that are devices or FIFOs (/dev/null, /dev/stdout) may be shared: each
// output is written there in turn.
void checkOutputPaths(const std::vector<std::pair<std::string, std::string>>& outputs);
// The same, and refuses an output that is one of the run's `inputs` (flag,
// path; an empty flag for a positional argument or a file found beside
// another, such as the false-edge list beside --data): the same file by
// device and inode, through any symbolic or hard link, would be replaced
// while (or before) it is read. Outputs that are devices or FIFOs are
// written in place and not compared.
void checkOutputPaths(const std::vector<std::pair<std::string, std::string>>& outputs,
                      const std::vector<std::pair<std::string, std::string>>& inputs);

// Parses the command line with gflags. --help prints `usage` and the
// program's own flags (not those of the libraries it links), then exits 0.
// An unsigned flag given a negative value is an Error naming it (gflags
// would take -1 as 2^64 - 1). Returns the positional arguments.
std::vector<std::string> parseCommandLine(int* argc, char*** argv, const std::string& usage);

// Runs `body`, turning any exception into "program: error: message" on
// stderr and exit status 1. The run's outputs are one OutputBatch
// (core/output_file.h): put in place together when `body` returns, none of
// them when it throws.
int runMain(const char* program, const std::function<int()>& body);

}  // namespace hamal::apps
