// readTextFile: see text_file.h.
#include "core/text_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace hamal {

namespace {

// Appends `data` to `text`, failing once the line being read grows past
// kMaxLineBytes; `line_start` is where that line begins in `text`, `line`
// its number.
void append(std::string& text, const char* data, std::size_t n, std::size_t& line_start, int& line,
            const std::string& name) {
  const std::size_t old = text.size();
  text.append(data, n);
  for (std::size_t i = old; i < text.size(); ++i)
    if (text[i] == '\n') {
      line_start = i + 1;
      ++line;
    }
  if (text.size() - line_start > kMaxLineBytes)
    throw Error(name + ":" + std::to_string(line) + ": a line longer than " +
                std::to_string(kMaxLineBytes >> 20) + " MiB: not a text file of this format");
}

}  // namespace

std::string readTextFile(const std::string& path, const std::string& what) {
  const std::string suffix = what.empty() ? "" : " " + what;
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) throw Error(path + ": file does not exist");
    throw Error(path + ": cannot open" + suffix + ": " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory, not a file");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(path + ": cannot open" + suffix + ": " + std::strerror(errno));
  std::string text;
  std::size_t line_start = 0;
  int line = 1;
  char buffer[1 << 16];
  try {
    for (;;) {
      const ssize_t n = ::read(fd, buffer, sizeof buffer);
      if (n == 0) break;
      if (n < 0) {
        if (errno == EINTR) continue;
        throw Error(path + ": read error: " + std::strerror(errno));
      }
      append(text, buffer, static_cast<std::size_t>(n), line_start, line, path);
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return text;
}

std::string readTextStream(std::istream& in, const std::string& name) {
  std::string text;
  std::size_t line_start = 0;
  int line = 1;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    append(text, buffer, static_cast<std::size_t>(in.gcount()), line_start, line, name);
  }
  if (in.bad()) throw Error(name + ": read error");
  return text;
}

}  // namespace hamal
