// OutputFile: see output_file.h.
#include "core/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <streambuf>
#include <vector>

#include "core/error.h"

namespace hamal {

// A stream buffer over a file descriptor that keeps the first error of
// write(2), so that the reason (ENOSPC, EFBIG, EPIPE) reaches the message.
class OutputFile::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd), data_(1 << 16) {
    setp(data_.data(), data_.data() + data_.size());
  }
  ~Buffer() override {
    if (fd_ >= 0) ::close(fd_);
  }
  int error() const { return error_; }
  // Writes what is buffered and closes; false (error() says why) on failure.
  bool close() {
    const bool flushed = flush();
    if (fd_ >= 0 && ::close(fd_) != 0 && error_ == 0) error_ = errno;
    fd_ = -1;
    return flushed && error_ == 0;
  }
  int fd() const { return fd_; }

 protected:
  int_type overflow(int_type c) override {
    if (!flush()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return flush() ? 0 : -1; }

 private:
  bool flush() {
    if (error_ != 0) return false;
    const char* p = pbase();
    std::size_t left = static_cast<std::size_t>(pptr() - pbase());
    while (left > 0) {
      const ssize_t n = ::write(fd_, p, left);
      if (n < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      p += n;
      left -= static_cast<std::size_t>(n);
    }
    setp(data_.data(), data_.data() + data_.size());
    return true;
  }

  int fd_;
  int error_ = 0;
  std::vector<char> data_;
};

namespace {

// The process' umask, read without changing it (umask(2) cannot only read,
// and setting it back races with other threads creating files).
mode_t currentUmask() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "Umask:") {
      std::string value;
      status >> value;
      return static_cast<mode_t>(std::strtoul(value.c_str(), nullptr, 8));
    }
    status.ignore(1 << 20, '\n');
  }
  return 022;
}

// The open batch, if any (OutputBatch's constructor and destructor set it).
OutputBatch* g_batch = nullptr;
std::mutex g_batch_mutex;

std::string directoryOf(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

}  // namespace

bool isSpecialFile(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

OutputFile::OutputFile(const std::string& path) : path_(path), target_(path) {
  if (path.empty()) throw Error("an output path is empty");
  struct stat st;
  int fd = -1;
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory, not a file");
    if (!S_ISREG(st.st_mode)) {
      // A device, a FIFO: written in place, never replaced.
      in_place_ = true;
      fd = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
      if (fd < 0) throw Error(path + ": cannot open for writing: " + std::strerror(errno));
    } else {
      mode_ = st.st_mode & 07777;
      struct stat link;
      if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
        char resolved[PATH_MAX];
        if (::realpath(path.c_str(), resolved) == nullptr)
          throw Error(path + ": cannot resolve the link: " + std::strerror(errno));
        target_ = resolved;
      }
    }
  } else if (errno == ENOENT) {
    mode_ = 0666 & ~currentUmask();
  } else {
    throw Error(path + ": " + std::strerror(errno));
  }
  if (!in_place_) {
    std::string name = target_ + ".tmp.XXXXXX";
    fd = ::mkstemp(name.data());
    if (fd < 0)
      throw Error(path + ": cannot open a temporary file in " + directoryOf(target_) + ": " +
                  std::strerror(errno));
    tmp_ = name;
  }
  buffer_ = std::make_unique<Buffer>(fd);
  stream_ = std::make_unique<std::ostream>(buffer_.get());
}

OutputFile::~OutputFile() {
  if (committed_) return;
  stream_.reset();
  buffer_.reset();
  if (!tmp_.empty()) ::unlink(tmp_.c_str());
}

std::ostream& OutputFile::stream() { return *stream_; }

int OutputFile::writeError() const { return buffer_ ? buffer_->error() : 0; }

void OutputFile::commit() { finish(false); }

void OutputFile::commitNow() { finish(true); }

void OutputFile::finish(bool now) {
  if (committed_) return;
  const auto fail = [&](const std::string& what, int error) {
    stream_.reset();
    buffer_.reset();
    if (!tmp_.empty()) ::unlink(tmp_.c_str());
    committed_ = true;
    throw Error(path_ + ": " + what + (error ? std::string(": ") + std::strerror(error) : ""));
  };
  stream_->flush();
  if (!tmp_.empty() && ::fchmod(buffer_->fd(), static_cast<mode_t>(mode_)) != 0)
    fail("cannot set the mode of " + tmp_, errno);
  if (!buffer_->close()) fail("writing failed", buffer_->error());
  if (stream_->bad()) fail("writing failed", 0);
  if (!tmp_.empty()) {
    std::lock_guard<std::mutex> lock(g_batch_mutex);
    if (!now && g_batch != nullptr) {
      std::lock_guard<std::mutex> staged(g_batch->mutex_);
      g_batch->staged_.push_back({path_, target_, tmp_});
    } else if (std::rename(tmp_.c_str(), target_.c_str()) != 0) {
      fail("cannot rename " + tmp_ + " to it", errno);
    }
  }
  committed_ = true;
  stream_.reset();
  buffer_.reset();
}

OutputBatch::OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  if (g_batch != nullptr) throw Error("an OutputBatch is already open");
  g_batch = this;
}

OutputBatch::~OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  if (g_batch == this) g_batch = nullptr;
  for (const Staged& s : staged_) ::unlink(s.tmp.c_str());
}

void OutputBatch::commit() {
  {
    std::lock_guard<std::mutex> lock(g_batch_mutex);
    if (g_batch == this) g_batch = nullptr;  // later outputs are put in place at once
  }
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Staged> staged;
  staged.swap(staged_);
  for (std::size_t i = 0; i < staged.size(); ++i) {
    if (std::rename(staged[i].tmp.c_str(), staged[i].target.c_str()) == 0) continue;
    const int error = errno;
    for (std::size_t j = i; j < staged.size(); ++j) ::unlink(staged[j].tmp.c_str());
    throw Error(staged[i].path + ": cannot rename " + staged[i].tmp +
                " to it: " + std::strerror(error));
  }
}

namespace {

void writeWhole(const std::string& path, const std::function<void(std::ostream&)>& write,
                bool now) {
  OutputFile file(path);
  try {
    write(file.stream());
  } catch (const Error& e) {
    // A writer that saw its stream fail says so; the buffer knows why.
    file.stream().flush();
    if (file.writeError() != 0)
      throw Error(path + ": writing failed: " + std::strerror(file.writeError()));
    const std::string what = e.what();
    if (what.rfind(path + ":", 0) == 0) throw;
    throw Error(path + ": " + what);
  }
  if (now)
    file.commitNow();
  else
    file.commit();
}

}  // namespace

void writeOutputFile(const std::string& path, const std::function<void(std::ostream&)>& write) {
  writeWhole(path, write, false);
}

void writeOutputFileNow(const std::string& path, const std::function<void(std::ostream&)>& write) {
  writeWhole(path, write, true);
}

}  // namespace hamal
