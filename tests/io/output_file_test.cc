// OutputFile (core/output_file.h): a file is the old content or the whole new
// one, two writers of one path never share a temporary, a link keeps being a
// link, a new file gets the permissions the umask allows; a run's outputs
// (OutputBatch) are put in place together or not at all.
#include "core/output_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace hamal {
namespace {

namespace fs = std::filesystem;

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class OutputFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/hamal_output_file_XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return dir_ + "/" + name; }
  std::size_t entries() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {}));
  }
  std::string dir_;
};

TEST_F(OutputFileTest, TwoWritersOfOnePathDoNotShareATemporary) {
  const std::string path = file("out.txt");
  OutputFile a(path), b(path);
  a.stream() << std::string(100000, 'a');
  b.stream() << std::string(50000, 'b');
  EXPECT_EQ(entries(), 2u);  // two temporaries
  b.commit();
  a.commit();
  EXPECT_EQ(readAll(path), std::string(100000, 'a'));
  EXPECT_EQ(entries(), 1u);
}

TEST_F(OutputFileTest, WithoutCommitTheOldContentStays) {
  const std::string path = file("out.txt");
  std::ofstream(path) << "old\n";
  {
    OutputFile f(path);
    f.stream() << "new, unfinished";
  }
  EXPECT_EQ(readAll(path), "old\n");
  EXPECT_EQ(entries(), 1u);
  EXPECT_THROW(writeOutputFile(path,
                               [](std::ostream& out) {
                                 out << "half";
                                 throw Error("the writer gave up");
                               }),
               Error);
  EXPECT_EQ(readAll(path), "old\n");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(OutputFileTest, ALinkKeepsBeingALinkToTheNewContent) {
  std::ofstream(file("target.txt")) << "old\n";
  fs::create_symlink("target.txt", file("link.txt"));
  writeOutputFile(file("link.txt"), [](std::ostream& out) { out << "new\n"; });
  EXPECT_TRUE(fs::is_symlink(file("link.txt")));
  EXPECT_EQ(readAll(file("target.txt")), "new\n");
}

TEST_F(OutputFileTest, PermissionsFollowTheUmaskOrTheOldFile) {
  const mode_t old_umask = ::umask(027);
  writeOutputFile(file("new.txt"), [](std::ostream& out) { out << "x"; });
  ::umask(old_umask);
  EXPECT_EQ(fs::status(file("new.txt")).permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  std::ofstream(file("old.txt")) << "x";
  fs::permissions(file("old.txt"), fs::perms::owner_all);
  writeOutputFile(file("old.txt"), [](std::ostream& out) { out << "y"; });
  EXPECT_EQ(fs::status(file("old.txt")).permissions(), fs::perms::owner_all);
}

TEST_F(OutputFileTest, ADirectoryOrAMissingDirectoryIsAnErrorNamingThePath) {
  try {
    OutputFile f(dir_);
    FAIL() << "a directory was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), dir_ + ": is a directory, not a file");
  }
  const std::string missing = file("no/such.txt");
  try {
    OutputFile f(missing);
    FAIL() << "a missing directory was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), missing + ": cannot open a temporary file in " + file("no") +
                                         ": No such file or directory");
  }
}

TEST_F(OutputFileTest, ABatchPutsEveryOutputInPlaceOnlyAtItsCommit) {
  std::ofstream(file("a.txt")) << "old a\n";
  {
    OutputBatch batch;
    writeOutputFile(file("a.txt"), [](std::ostream& out) { out << "new a\n"; });
    writeOutputFile(file("b.txt"), [](std::ostream& out) { out << "new b\n"; });
    // Both complete beside their paths, neither in place yet.
    EXPECT_EQ(readAll(file("a.txt")), "old a\n");
    EXPECT_FALSE(fs::exists(file("b.txt")));
    EXPECT_EQ(entries(), 3u);
    batch.commit();
  }
  EXPECT_EQ(readAll(file("a.txt")), "new a\n");
  EXPECT_EQ(readAll(file("b.txt")), "new b\n");
  EXPECT_EQ(entries(), 2u);
}

TEST_F(OutputFileTest, ARunThatFailsLeavesEveryOutputAsItWas) {
  std::ofstream(file("a.txt")) << "old a\n";
  try {
    OutputBatch batch;
    writeOutputFile(file("a.txt"), [](std::ostream& out) { out << "new a\n"; });
    // The second output fails, as a full disk would: the first stays old.
    writeOutputFile(file("b.txt"), [](std::ostream& out) {
      out << "half";
      throw Error("the writer gave up");
    });
    batch.commit();
    FAIL() << "the failed write was not an error";
  } catch (const Error&) {
  }
  EXPECT_EQ(readAll(file("a.txt")), "old a\n");
  EXPECT_FALSE(fs::exists(file("b.txt")));
  EXPECT_EQ(entries(), 1u);  // no temporary left
  // /dev/full, written in place, fails the batch before anything is renamed.
  try {
    OutputBatch batch;
    writeOutputFile(file("a.txt"), [](std::ostream& out) { out << "new a\n"; });
    writeOutputFile("/dev/full", [](std::ostream& out) { out << "x"; });
    batch.commit();
    FAIL() << "/dev/full took a write";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full: writing failed"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(readAll(file("a.txt")), "old a\n");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(OutputFileTest, CommitNowIsInPlaceAtOnceWhileABatchIsOpen) {
  OutputBatch batch;
  writeOutputFileNow(file("config.txt"), [](std::ostream& out) { out << "n 1\n"; });
  EXPECT_EQ(readAll(file("config.txt")), "n 1\n");
  EXPECT_THROW(OutputBatch second, Error);  // one batch at a time
}

}  // namespace
}  // namespace hamal
