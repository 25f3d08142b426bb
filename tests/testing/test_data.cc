// Test data paths: see test_data.h.
#include "testing/test_data.h"

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

}  // namespace hamal::testing
