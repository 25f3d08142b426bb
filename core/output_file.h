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
//
// A run's outputs together are all or none (OutputBatch): while a batch is
// open, commit() checks the temporary whole but leaves the rename to the
// batch, which renames every staged file only after the run succeeded.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

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
  // "path: reason" on any failure (then nothing is put in place). While an
  // OutputBatch is open the temporary is handed to it instead, and put in
  // place by OutputBatch::commit().
  void commit();
  // commit(), putting the file in place at once even while a batch is open:
  // for a file that later writes of the run depend on (a results folder's
  // record of parameters, which must be there before its first row).
  void commitNow();
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
  void finish(bool now);
  unsigned mode_ = 0;
  std::unique_ptr<Buffer> buffer_;
  std::unique_ptr<std::ostream> stream_;
};

// Opens `path`, lets `write` fill it, commits.
void writeOutputFile(const std::string& path, const std::function<void(std::ostream&)>& write);
// The same, with commitNow().
void writeOutputFileNow(const std::string& path, const std::function<void(std::ostream&)>& write);

// The outputs of one run, all or none. While a batch is open (one per
// process; apps/common/cli.h runMain opens it around a tool's work), every
// OutputFile::commit() leaves its checked, complete temporary beside its
// path; commit() renames them all, in the order they were committed, so a
// file committed last (hamal_spoil's false-edge list) is in place only when
// the ones before it are. A batch destroyed without commit() (the run threw)
// removes every staged temporary: no output of a failed run is put in
// place. A device or FIFO cannot wait: it is written as the run goes.
class OutputBatch {
 public:
  OutputBatch();  // throws Error when a batch is already open
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  // Renames every staged file over its path; Error "path: reason" when one
  // cannot be (the ones not yet renamed are removed).
  void commit();

 private:
  friend class OutputFile;
  struct Staged {
    std::string path, target, tmp;
  };
  std::mutex mutex_;  // files may be committed from several threads
  std::vector<Staged> staged_;
};

// True when `path` exists and is neither a regular file nor a directory (it
// would be written in place).
bool isSpecialFile(const std::string& path);

}  // namespace hamal
