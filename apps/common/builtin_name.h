// How the executables read the name of a built-in thing on the command line
// (FLAG's and MOSS' worlds): matched without regard to case, and from then
// on spelled as the program lists it, in lower case, so that "CORRIDOR",
// "Corridor" and "corridor" name one world and print as "corridor".
// Header-only, so that application libraries use it without the CLI library.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace hamal::apps {

inline std::string lowerCase(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The entry of `names` (lower case) that `given` spells, or "" when none.
inline std::string builtinName(const std::string& given, const std::vector<std::string>& names) {
  const std::string lower = lowerCase(given);
  for (const std::string& n : names)
    if (n == lower) return n;
  return "";
}

}  // namespace hamal::apps
