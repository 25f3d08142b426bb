// The layering rule: core/ holds the contracts (Factor, Backend, Step,
// StepSource, Registry, ...) and nothing in it may include factors/,
// backends/ or apps/, and nothing in backends/ includes factors/ or apps/,
// so that a factor kind, a back-end or an application can be added,
// replaced or loaded as a plugin without the layers below knowing it. The
// installed libraries above libhamal (protocol/, conformance/) include
// nothing from apps/, which is not installed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace hamal {
namespace {

namespace fs = std::filesystem;

// "file:line: #include ..." for every include of a layer above core/ in the
// .h and .cc files of `dir`.
std::vector<std::string> upwardIncludes(const fs::path& dir) {
  static const std::regex include(R"(^\s*#\s*include\s*["<](factors|backends|apps)/)");
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".h" && ext != ".cc")) continue;
    std::ifstream in(entry.path());
    std::string line;
    for (int number = 1; std::getline(in, line); ++number)
      if (std::regex_search(line, include))
        found.push_back(entry.path().string() + ":" + std::to_string(number) + ": " + line);
  }
  return found;
}

TEST(Layering, CoreIncludesNoFactorBackendOrApplication) {
  const fs::path core = fs::path(HAMAL_SOURCE_DIR) / "core";
  ASSERT_TRUE(fs::is_directory(core)) << core;
  for (const std::string& violation : upwardIncludes(core)) ADD_FAILURE() << violation;
}

// A back-end asks factors through core/ (Factor's virtuals), so a plugin's
// factor takes part like a built-in one: nothing in backends/ includes
// factors/ or apps/, except builtins.cc, which registers the built-in
// factors beside the built-in back-ends.
TEST(Layering, BackendsIncludeNoFactorOrApplication) {
  const fs::path backends = fs::path(HAMAL_SOURCE_DIR) / "backends";
  ASSERT_TRUE(fs::is_directory(backends)) << backends;
  const std::regex allowed(R"(backends/builtins\.cc:\d+: #include "factors/register_factors\.h")");
  const std::regex upward(R"(:\d+: \s*#\s*include\s*["<](factors|apps)/)");
  for (const std::string& found : upwardIncludes(backends))
    if (std::regex_search(found, upward) && !std::regex_search(found, allowed))
      ADD_FAILURE() << found;
}

// protocol/ and conformance/ are installed and used by the plugins and
// Python: an include of apps/ would tie them to what is not installed.
TEST(Layering, InstalledLibrariesIncludeNoApplication) {
  const std::regex application(R"(:\d+: \s*#\s*include\s*["<]apps/)");
  for (const char* folder : {"protocol", "conformance"}) {
    const fs::path dir = fs::path(HAMAL_SOURCE_DIR) / folder;
    ASSERT_TRUE(fs::is_directory(dir)) << dir;
    for (const std::string& found : upwardIncludes(dir))
      if (std::regex_search(found, application)) ADD_FAILURE() << found;
  }
}

// The scan itself finds what it looks for (so a green run above means
// something): quoted and angled includes, with spaces, in .h and .cc files.
TEST(Layering, TheScanFindsUpwardIncludes) {
  const fs::path dir = fs::temp_directory_path() / ("hamal_layering_" + std::to_string(::getpid()));
  fs::create_directories(dir / "sub");
  std::ofstream(dir / "a.h") << "#include \"core/factor.h\"\n#include \"factors/prior_factor.h\"\n";
  std::ofstream(dir / "sub" / "b.cc")
      << "// apps/ in a comment is fine\n#  include <backends/x.h>\n";
  std::ofstream(dir / "c.txt") << "#include \"apps/bench/bench_runner.h\"\n";
  const auto found = upwardIncludes(dir);
  fs::remove_all(dir);
  ASSERT_EQ(found.size(), 2u);
}

}  // namespace
}  // namespace hamal
