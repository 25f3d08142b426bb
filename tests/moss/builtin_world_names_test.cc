// The built-in worlds' names on the command line: matched in any case,
// spelled in lower case from then on (apps/common/builtin_name.h), so rows
// say "corridor" whichever way the user wrote it. FLAG's worlds follow the
// same rule (tests/flag has no binary of its own for one check, so it is here
// too).
#include <gtest/gtest.h>

#include "apps/common/builtin_name.h"
#include "apps/moss/trials.h"
#include "apps/moss/world.h"

namespace hamal::moss {
namespace {

TEST(BuiltinWorldNames, AnyCaseNamesOneWorldPrintedInLowerCase) {
  EXPECT_EQ(builtinWorldNames(), (std::vector<std::string>{"corridor", "square"}));
  for (const std::string name : {"corridor", "CORRIDOR", "Corridor"}) {
    EXPECT_EQ(builtinWorldText(name), builtinWorldText("corridor")) << name;
    EXPECT_EQ(loadWorld(name).name, "corridor") << name;
  }
  EXPECT_EQ(loadWorld("SQUARE").name, "square");
  EXPECT_EQ(builtinWorldText("corridors"), "");
  // The scenario defaults follow the world whatever its spelling.
  EXPECT_EQ(scenarioConfig("SQUARE").poses, scenarioConfig("square").poses);
  EXPECT_NE(scenarioConfig("square").poses, scenarioConfig("corridor").poses);
}

TEST(BuiltinWorldNames, TheRuleMatchesWholeNamesOnly) {
  const std::vector<std::string> names = {"office", "corridor"};
  EXPECT_EQ(apps::builtinName("OFFICE", names), "office");
  EXPECT_EQ(apps::builtinName("offic", names), "");
  EXPECT_EQ(apps::builtinName("office ", names), "");
  EXPECT_EQ(apps::lowerCase("CoRRidor"), "corridor");
}

}  // namespace
}  // namespace hamal::moss
