// The one exception type of hamal: bad input, bad options, a plugin that
// will not load. Its message is complete and meant for the user as it is
// ("file:line: reason" for input files). Numerical failures inside a
// back-end are not exceptions: they are a Status in the UpdateResult.
#pragma once

#include <stdexcept>
#include <string>

namespace hamal {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace hamal
