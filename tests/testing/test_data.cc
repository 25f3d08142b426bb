// Test data paths: see test_data.h.
#include "testing/test_data.h"

#include <cctype>
#include <cstdlib>
#include <fstream>

namespace hamal::testing {

std::string dataPath(const std::string& name) {
  const char* env = std::getenv("HAMAL_DATA_DIR");
  const std::string dir = env && *env ? env : HAMAL_DATA_DIR;
  const std::string path = dir + "/" + name;
  return std::ifstream(path).good() ? path : std::string();
}

std::string buildPath(const std::string& relative) {
  return std::string(HAMAL_BINARY_DIR) + "/" + relative;
}

std::string testName(const std::string& file) {
  std::string name = file;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

}  // namespace hamal::testing
