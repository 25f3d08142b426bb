// Options and BackendSpec: unknown keys are errors that list the known ones.
#include "core/options.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace hamal {
namespace {

const std::vector<OptionSpec> kSpecs = {{"delta_t", "0.01", "relinearise threshold"},
                                        {"nl_t", "100", "node count"},
                                        {"mode", "auto", "auto or periodic"}};

TEST(BackendSpec, ParsesNameAndOptions) {
  const BackendSpec s = BackendSpec::parse("aprilsam:delta_t=0.5, nl_t=7");
  EXPECT_EQ(s.name, "aprilsam");
  EXPECT_EQ(s.options.at("delta_t"), "0.5");
  EXPECT_EQ(s.options.at("nl_t"), "7");
  EXPECT_EQ(BackendSpec::parse("ceres").options.size(), 0u);
  EXPECT_EQ(s.str(), "aprilsam:delta_t=0.5,nl_t=7");
}

TEST(BackendSpec, RejectsMalformed) {
  EXPECT_THROW(BackendSpec::parse("aprilsam:delta_t"), Error);
  EXPECT_THROW(BackendSpec::parse(":a=1"), Error);
  EXPECT_THROW(BackendSpec::parse("x:a=1,a=2"), Error);
}

TEST(Options, DefaultsAndTypedAccess) {
  Options o("aprilsam", kSpecs, {{"nl_t", "42"}});
  EXPECT_DOUBLE_EQ(o.getDouble("delta_t"), 0.01);
  EXPECT_EQ(o.getInt("nl_t"), 42);
  EXPECT_EQ(o.getChoice("mode", {"auto", "periodic"}), "auto");
  EXPECT_EQ(o.str(), "delta_t=0.01,mode=auto,nl_t=42");
}

TEST(Options, UnknownKeyListsKnownKeys) {
  try {
    Options("aprilsam", kSpecs, {{"delta", "1"}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "aprilsam: unknown option 'delta'; known options: delta_t, nl_t, mode");
  }
}

TEST(Options, BadValuesNameTheOption) {
  Options o("aprilsam", kSpecs, {{"nl_t", "abc"}, {"mode", "sometimes"}});
  try {
    o.getInt("nl_t");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "aprilsam: option nl_t=abc is not an integer");
  }
  EXPECT_THROW(o.getChoice("mode", {"auto", "periodic"}), Error);
  EXPECT_THROW(o.getDouble("nl_t"), Error);
}

// A renamed option: its old name is read as the new one for a release, with
// a line on stderr that names the new one; both names at once are an error.
TEST(Options, OldNamesAreReadAsTheNewOneAndSaySo) {
  const std::vector<OptionSpec> specs = {
      {"function_tolerance", "1e-6", "relative cost decrease", {"rel_tolerance"}}};
  ::testing::internal::CaptureStderr();
  const Options old("cholesky", specs, {{"rel_tolerance", "1e-9"}});
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_DOUBLE_EQ(old.getDouble("function_tolerance"), 1e-9);
  EXPECT_EQ(old.str(), "function_tolerance=1e-9");
  EXPECT_NE(said.find("cholesky: option 'rel_tolerance' is an old name; use 'function_tolerance'"),
            std::string::npos)
      << said;
  ::testing::internal::CaptureStderr();
  const Options now("cholesky", specs, {{"function_tolerance", "1e-9"}});
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  try {
    Options("cholesky", specs, {{"rel_tolerance", "1"}, {"function_tolerance", "2"}});
    FAIL() << "both names were accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("give 'function_tolerance' only"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hamal
