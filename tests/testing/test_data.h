// Where tests find the public datasets (../shared/data, or HAMAL_DATA_DIR in
// the environment) and the build's own files (plugins, executables).
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace hamal::testing {

// Full path of a dataset file; empty when it is not there.
std::string dataPath(const std::string& name);
// Full path of a file in the build tree (e.g. "plugins/libhamal_example_plugin.so").
std::string buildPath(const std::string& relative);
// A dataset file's name as a test parameter's name: "M3500.toro" -> "M3500_toro".
std::string testName(const std::string& file);

}  // namespace hamal::testing

// Skips the test, saying which file is missing, when a dataset is absent.
#define HAMAL_REQUIRE_DATA(var, name)                       \
  const std::string var = ::hamal::testing::dataPath(name); \
  if (var.empty())                                          \
  GTEST_SKIP() << "dataset " << (name) << " not found in "  \
               << "../shared/data (set HAMAL_DATA_DIR)"
