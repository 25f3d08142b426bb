// OutputFile: how every hamal tool writes what it is asked to write, so that
// an output is either the old content or the whole new one, never a torn
// file, and a path that names something other than a file is never replaced.
//
// A regular file (or a path that does not exist yet) is written to a
// temporary file of a unique name (mkstemp) in the same directory and renamed
// over the path at commit(): an interrupted or failed write leaves the old
// file untouched, and two writers of one path do not share a temporary. A
// symbolic link to a file has its target replaced, the link itself is kept.
// An existing path that is not a regular file (a character device such as
// /dev/null or /dev/stdout, a FIFO) is written in place, as a shell
// redirection would, and never renamed over. Every write error (ENOSPC on
// /dev/full, a file size limit, ...) is an Error naming the path and the
// reason.
#pragma once

#include <functional>
#include <memory>
#include <ostream>
#include <string>

namespace hamal {

class OutputFile {
 public:
  // Opens `path` for writing; throws Error "path: reason" (a directory, a
  // directory that does not exist or is not writable, ...).
  explicit OutputFile(const std::string& path);
  // Without commit(): the temporary is removed, the path keeps its old content.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream();
  // Flushes, checks every write, and puts the file in place; throws Error
  // "path: reason" on any failure (then nothing is put in place).
  void commit();
  const std::string& path() const { return path_; }
  // True when the path is written in place (it is not a regular file).
  bool inPlace() const { return in_place_; }
  // The errno of the first failed write, 0 while none failed.
  int writeError() const;

 private:
  class Buffer;
  std::string path_;    // as given, for messages
  std::string target_;  // what is renamed over (a symbolic link's target)
  std::string tmp_;     // the temporary; empty when written in place
  bool in_place_ = false;
  bool committed_ = false;
  unsigned mode_ = 0;
  std::unique_ptr<Buffer> buffer_;
  std::unique_ptr<std::ostream> stream_;
};

// Opens `path`, lets `write` fill it, commits.
void writeOutputFile(const std::string& path, const std::function<void(std::ostream&)>& write);

// True when `path` exists and is neither a regular file nor a directory (it
// would be written in place).
bool isSpecialFile(const std::string& path);

}  // namespace hamal
