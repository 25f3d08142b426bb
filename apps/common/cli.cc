// Command-line plumbing of the hamal executables: see cli.h.
#include "apps/common/cli.h"

#include <gflags/gflags.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <deque>
#include <filesystem>
#include <iostream>
#include <set>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/output_file.h"
#include "core/plugin.h"

// Defined by gflags (gflags_reporting.cc), not declared in its header.
DECLARE_bool(help);
DECLARE_bool(helpfull);

DEFINE_string(plugin, "",
              "plugin shared library to load (repeatable, or comma separated; an empty entry "
              "is an error); in the ':'-separated directories of HAMAL_PLUGIN_PATH every file "
              "named lib*.so is loaded too, and other files are skipped");
DEFINE_bool(list_factors, false, "list the registered factor kinds (with plugins) and exit");
DEFINE_bool(list_backends, false, "list the registered back-ends and their options and exit");

namespace hamal::apps {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\n");
  return s.substr(b, e - b + 1);
}

}  // namespace

bool printListings(const Registry& registry) {
  if (FLAGS_list_factors) std::cout << registry.describeFactors();
  if (FLAGS_list_backends) std::cout << registry.describeBackends();
  return FLAGS_list_factors || FLAGS_list_backends;
}

BetweenResidual parseResidual(const std::string& name) {
  if (name == "thesis") return BetweenResidual::kThesis;
  if (name == "measurement" || name == "measurement-frame")
    return BetweenResidual::kMeasurementFrame;
  throw Error("--residual must be thesis or measurement, not '" + name + "'");
}

namespace {

std::vector<std::pair<std::string, std::string>>& aliasTable() {
  static std::vector<std::pair<std::string, std::string>> table;
  return table;
}

// The name of a flag argument ("--a_b=1" -> "a_b", "-x" -> "x"), "" for a
// positional one.
std::string flagName(const char* arg) {
  if (arg[0] != '-' || arg[1] == '\0') return "";
  const char* name = arg + (arg[1] == '-' ? 2 : 1);
  const char* end = std::strchr(name, '=');
  return end ? std::string(name, end) : std::string(name);
}

}  // namespace

FlagAlias::FlagAlias(const char* old_name, const char* new_name) {
  aliasTable().emplace_back(old_name, new_name);
}

void applyFlagAliases(int argc, char** argv) {
  static std::deque<std::string> storage;  // argv's rewritten entries live here
  static std::set<std::string> warned;
  normalizeFlagNames(argc, argv);
  for (const auto& [old_name, new_name] : aliasTable()) {
    bool old_given = false, new_given = false;
    for (int i = 1; i < argc; ++i) {
      if (std::strcmp(argv[i], "--") == 0) break;
      const std::string name = flagName(argv[i]);
      if (name == new_name) new_given = true;
      if (name != old_name) continue;
      old_given = true;
      const std::string arg = argv[i];
      const std::size_t dashes = arg[1] == '-' ? 2 : 1;
      storage.push_back(arg.substr(0, dashes) + new_name + arg.substr(dashes + old_name.size()));
      argv[i] = storage.back().data();
    }
    if (old_given && new_given)
      throw Error("--" + old_name + " is an old spelling of --" + new_name + "; give --" +
                  new_name + " only");
    if (old_given && warned.insert(old_name).second)
      std::cerr << std::filesystem::path(argv[0]).filename().string() << ": --" << old_name
                << " is an old spelling; use --" << new_name << std::endl;
  }
}

void normalizeFlagNames(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    char* arg = argv[i];
    if (std::strcmp(arg, "--") == 0) break;  // the rest is positional
    if (arg[0] != '-') continue;
    char* name = arg + (arg[1] == '-' ? 2 : 1);
    for (char* c = name; *c && *c != '='; ++c)
      if (*c == '-') *c = '_';
  }
}

std::vector<std::string> repeatedFlag(int argc, char** argv, const std::string& name) {
  applyFlagAliases(argc, argv);
  std::vector<std::string> values;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    for (const std::string prefix : {"--", "-"}) {
      const std::string flag = prefix + name;
      if (arg == flag && i + 1 < argc) {
        values.push_back(argv[++i]);
        break;
      }
      if (arg.compare(0, flag.size() + 1, flag + "=") == 0) {
        values.push_back(arg.substr(flag.size() + 1));
        break;
      }
    }
  }
  return values;
}

std::vector<std::string> splitList(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto next = text.find(separator, pos);
    const std::string piece =
        trim(text.substr(pos, next == std::string::npos ? std::string::npos : next - pos));
    if (!piece.empty()) out.push_back(piece);
    if (next == std::string::npos) break;
    pos = next + 1;
  }
  return out;
}

std::vector<std::string> splitBackendSpecs(const std::string& text, const Registry& registry) {
  std::vector<std::string> specs;
  // An option continues the spec before it only within one ';' entry: after
  // ";;" (an empty entry is dropped) it would join the wrong back-end.
  for (const std::string& group : splitList(text, ';')) {
    bool first_of_group = true;
    for (const std::string& piece : splitList(group, ',')) {
      const bool option_of_previous =
          piece.find('=') != std::string::npos && piece.find(':') == std::string::npos;
      if (option_of_previous) {
        if (specs.empty() || first_of_group)
          throw Error("back-end list '" + text + "': '" + piece +
                      "' is an option without a back-end name before it");
        specs.back() += "," + piece;
      } else if (piece == "all") {
        for (const BackendInfo* info : registry.backends()) specs.push_back(info->name);
      } else {
        specs.push_back(piece);
      }
      first_of_group = false;
    }
  }
  return specs;
}

void setUpRegistry(Registry& registry, const std::vector<std::string>& plugin_flags) {
  registerBuiltins(registry);
  for (const std::string& flag : plugin_flags) {
    // splitList drops empty pieces; here one is a typo (",,", a trailing ',').
    std::size_t entries = 1;
    for (char c : flag) entries += c == ',';
    const std::vector<std::string> paths = splitList(flag, ',');
    if (paths.size() != entries)
      throw Error("--plugin '" + flag + "' has an empty entry; give one path per entry");
    for (const std::string& path : paths) loadPlugin(path, registry);
  }
  loadPluginsFromPath(registry);
}

void checkOutputPath(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string what = "--" + flag + " " + path + ": ";
  if (fs::is_directory(path, ec)) throw Error(what + "is a directory, not a file");
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir, ec))
    throw Error(what + "directory " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw Error(what + "cannot write in directory " + dir.string() + ": " + std::strerror(errno));
  if (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0)
    throw Error(what + "cannot write: " + std::strerror(errno));
}

void checkOutputPaths(const std::vector<std::pair<std::string, std::string>>& outputs) {
  namespace fs = std::filesystem;
  for (const auto& [flag, path] : outputs) checkOutputPath(flag, path);
  const auto same = [](const std::string& a, const std::string& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
    return fs::weakly_canonical(fs::absolute(a), ec) == fs::weakly_canonical(fs::absolute(b), ec);
  };
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const std::string& a = outputs[j].second;
      const std::string& b = outputs[i].second;
      if (a.empty() || b.empty() || isSpecialFile(b) || !same(a, b)) continue;
      throw Error("--" + outputs[i].first + " " + b + " names the same file as --" +
                  outputs[j].first + " " + a + ": give each output a path of its own");
    }
}

void checkOutputPaths(const std::vector<std::pair<std::string, std::string>>& outputs,
                      const std::vector<std::pair<std::string, std::string>>& inputs) {
  checkOutputPaths(outputs);
  for (const auto& [out_flag, out_path] : outputs) {
    struct stat out;
    // Not there yet: not an input either. A device or FIFO is written in
    // place and never replaced (/dev/stdin and /dev/stdout may be one tty).
    if (out_path.empty() || ::stat(out_path.c_str(), &out) != 0 || !S_ISREG(out.st_mode)) continue;
    for (const auto& [in_flag, in_path] : inputs) {
      struct stat in;
      if (in_path.empty() || ::stat(in_path.c_str(), &in) != 0) continue;
      if (in.st_dev != out.st_dev || in.st_ino != out.st_ino) continue;
      throw Error("--" + out_flag + " " + out_path + " is the input " +
                  (in_flag.empty() ? std::string() : "--" + in_flag + " ") + in_path +
                  " (the same file): writing it would replace what this run reads; give the "
                  "output a path of its own");
    }
  }
}

namespace {

// gflags reads "-1" for an unsigned flag as 2^64 - 1 (strtoull's rule), so a
// negative count would silently become a huge one: refused, by name.
void rejectNegativeUnsigned(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--") break;
    if (arg.size() < 2 || arg[0] != '-') continue;
    arg.erase(0, arg[1] == '-' ? 2 : 1);
    const std::size_t eq = arg.find('=');
    const std::string name = arg.substr(0, eq);
    gflags::CommandLineFlagInfo info;
    if (!gflags::GetCommandLineFlagInfo(name.c_str(), &info)) continue;
    if (info.type != "uint32" && info.type != "uint64") continue;
    std::string value;
    if (eq != std::string::npos)
      value = arg.substr(eq + 1);
    else if (i + 1 < argc)
      value = argv[++i];
    const std::size_t first = value.find_first_not_of(" \t");
    if (first != std::string::npos && value[first] == '-')
      throw Error("--" + name + " " + value + ": must be a non-negative integer");
  }
}

}  // namespace

std::vector<std::string> parseCommandLine(int* argc, char*** argv, const std::string& usage) {
  applyFlagAliases(*argc, *argv);
  rejectNegativeUnsigned(*argc, *argv);
  gflags::SetUsageMessage(usage);
  gflags::SetVersionString("0.1.0");
  gflags::ParseCommandLineNonHelpFlags(argc, argv, /*remove_flags=*/true);
  if (FLAGS_help || FLAGS_helpfull) {
    // gflags' --help would also list every flag of glog and gflags itself;
    // --helpfull still does.
    if (FLAGS_helpfull) {
      gflags::HandleCommandLineHelpFlags();
      std::exit(0);
    }
    std::cout << gflags::ProgramInvocationShortName() << ": " << usage << "\n\n  Flags:\n";
    std::vector<gflags::CommandLineFlagInfo> flags;
    gflags::GetAllFlags(&flags);
    for (const auto& f : flags)
      if (f.filename.find("apps/") != std::string::npos ||
          f.filename.find("plugins/") != std::string::npos)
        std::cout << gflags::DescribeOneFlag(f);
    std::cout
        << "\n  Flag names may be written with '-' or '_' (--list-backends, --list_backends).\n"
           "  --helpfull lists the flags of the libraries too.\n";
    std::exit(0);
  }
  gflags::HandleCommandLineHelpFlags();  // --version, --helpon, ...
  std::vector<std::string> positional;
  for (int i = 1; i < *argc; ++i) positional.push_back((*argv)[i]);
  return positional;
}

int runMain(const char* program, const std::function<int()>& body) {
  try {
    OutputBatch outputs;
    const int status = body();
    outputs.commit();
    return status;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << std::endl;
  } catch (...) {
    std::cerr << program << ": error: unknown exception" << std::endl;
  }
  return 1;
}

}  // namespace hamal::apps
