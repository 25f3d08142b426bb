// libFuzzer target: the verifier of resumable results folders
// (apps/common/resumable_results.h) on arbitrary config.txt and rows.csv.
// The bytes up to the first 0xff are config.txt (absent when the input
// starts with 0xfe), the rest rows.csv (absent without a 0xff). Opening the
// folder either fails with a hamal::Error whose message names a file of the
// folder and fits a terminal, or keeps rows of the header's width, after
// which rows.csv ends with a line break and a second opening keeps the same
// rows. Any other exception, a crash or a sanitizer report is a bug.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "apps/common/resumable_results.h"
#include "core/error.h"

namespace {

namespace fs = std::filesystem;

const char kConfig[] = "seed 1\nsizes 1-3\n";
const char kHeader[] = "world,method,C,value";

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "results_folder_fuzz: %s\n", what.c_str());
  std::abort();
}

const std::string& folder() {
  static const std::string* dir = [] {
    std::string d = (fs::temp_directory_path() / "hamal_results_fuzz_XXXXXX").string();
    if (!::mkdtemp(d.data())) bug("cannot make a scratch folder");
    return new std::string(d);
  }();
  return *dir;
}

void checkMessage(const std::string& message) {
  for (unsigned char c : message)
    if (c < 0x20 || c >= 0x7f) bug("an error message holds a raw control byte: " + message);
  if (message.size() > 4000)
    bug("an error message of " + std::to_string(message.size()) + " bytes");
  if (message.rfind(folder() + "/", 0) != 0)
    bug("an error message that names no file of the folder: " + message);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const std::string dir = folder();
  fs::remove(dir + "/config.txt");
  fs::remove(dir + "/rows.csv");
  const std::size_t split = bytes.find('\xff');
  if (bytes.empty() || bytes[0] != '\xfe')
    std::ofstream(dir + "/config.txt", std::ios::binary) << bytes.substr(0, split);
  if (split != std::string::npos)
    std::ofstream(dir + "/rows.csv", std::ios::binary) << bytes.substr(split + 1);
  std::size_t kept = 0;
  try {
    hamal::apps::ResumableResults results(dir, kConfig, kHeader);
    kept = results.rows().size();
    for (const hamal::apps::ResultRow& row : results.rows()) {
      if (row.fields.size() != 4) bug("a row of another width was kept");
      try {
        results.integer(row, 2);
      } catch (const hamal::Error& e) {
        checkMessage(e.what());
      }
    }
  } catch (const hamal::Error& e) {
    checkMessage(e.what());
    return 0;
  } catch (const std::exception& e) {
    bug(std::string("the verifier threw something other than hamal::Error: ") + e.what());
  }
  std::ifstream in(dir + "/rows.csv", std::ios::binary);
  const std::string rows((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (rows.empty() || rows.back() != '\n') bug("rows.csv does not end with a line break");
  try {
    hamal::apps::ResumableResults again(dir, kConfig, kHeader);
    if (again.rows().size() != kept) bug("a second opening keeps other rows");
  } catch (const hamal::Error& e) {
    bug(std::string("a verified folder is refused on a second opening: ") + e.what());
  }
  return 0;
}
