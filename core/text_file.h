// readTextFile: how hamal's readers take a text input whole (graphs, floor
// plans, worlds, false-edge lists), so each says the same thing about input
// that is not a text file: a path that does not exist or is a directory, a
// read error with its reason (never taken for an empty file), and a line
// longer than kMaxLineBytes ("file:line: ..."), which bounds the memory a
// file without line breaks (/dev/zero, a binary) can take.
#pragma once

#include <cstddef>
#include <istream>
#include <string>

namespace hamal {

// 16 MiB: far beyond any line of a dataset, small enough to hold.
constexpr std::size_t kMaxLineBytes = std::size_t{1} << 24;

// The whole content of `path`; `what` names the file in messages ("the floor
// plan"). Throws hamal::Error "path: reason" or "path:line: reason".
std::string readTextFile(const std::string& path, const std::string& what = "");

// The same for a stream, named `name` in messages.
std::string readTextStream(std::istream& in, const std::string& name);

}  // namespace hamal
