// EnumNames (core/enum_names.h): a name is written as its first entry, read
// through its aliases too, and an unknown name is refused listing them all;
// the tables in use keep the names files and command lines have.
#include "core/enum_names.h"

#include <gtest/gtest.h>

#include "core/backend.h"
#include "core/graph_io.h"

namespace hamal {
namespace {

enum class Colour { kRed, kGreen, kBlue };
constexpr EnumNames<Colour, 4> kColours = {{{Colour::kRed, "red"},
                                            {Colour::kGreen, "green"},
                                            {Colour::kGreen, "lime"},
                                            {Colour::kBlue, "blue"}}};

TEST(EnumNames, WritesTheFirstNameAndReadsAliases) {
  EXPECT_STREQ(enumName(kColours, Colour::kGreen), "green");
  EXPECT_EQ(parseEnum(kColours, "lime", "colour"), Colour::kGreen);
  EXPECT_EQ(parseEnum(kColours, "blue", "colour"), Colour::kBlue);
  for (Colour c : {Colour::kRed, Colour::kGreen, Colour::kBlue})
    EXPECT_EQ(parseEnum(kColours, enumName(kColours, c), "colour"), c);
  EXPECT_EQ(enumNameVector(kColours), (std::vector<std::string>{"red", "green", "lime", "blue"}));
}

TEST(EnumNames, RefusesAnUnknownNameListingTheKnownOnes) {
  try {
    parseEnum(kColours, "Red", "colour");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown colour 'Red'; expected red, green, lime or blue");
  }
}

TEST(EnumNames, TheCoreTablesKeepTheirNames) {
  EXPECT_STREQ(toString(UpdateKind::kNone), "none");
  EXPECT_STREQ(toString(UpdateKind::kIncremental), "incremental");
  EXPECT_STREQ(toString(UpdateKind::kBatch), "batch");
  EXPECT_STREQ(toString(Status::kOk), "ok");
  EXPECT_STREQ(toString(Status::kNumericalFailure), "numerical_failure");
  EXPECT_STREQ(toString(Status::kNotConverged), "not_converged");
  EXPECT_STREQ(toString(Status::kUncertain), "uncertain");
  for (Format f : {Format::kAuto, Format::kG2o, Format::kToro, Format::kGtsam})
    EXPECT_EQ(parseFormat(formatName(f)), f);
}

}  // namespace
}  // namespace hamal
