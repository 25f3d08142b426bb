// libFuzzer target: the world files of the applications on arbitrary bytes.
// The first byte picks the reader ('m' a MOSS world, apps/moss/world.h;
// anything else a FLAG floor plan, apps/flag/floor_plan.h); the rest is the
// file. Reading either fails with a hamal::Error whose message names the
// file and fits a terminal, or gives a world; a floor plan read is written
// and read back to the same text. Any other exception, a crash or a
// sanitizer report is a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "apps/flag/floor_plan.h"
#include "apps/moss/world.h"
#include "core/error.h"

namespace {

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "world_file_fuzz: %s\n", what.c_str());
  std::abort();
}

void checkMessage(const std::string& message, const std::string& file) {
  for (unsigned char c : message)
    if (c < 0x20 || c >= 0x7f) bug("an error message holds a raw control byte: " + message);
  if (message.size() > 4000)
    bug("an error message of " + std::to_string(message.size()) + " bytes");
  if (message.rfind(file, 0) != 0) bug("an error message that does not name the file: " + message);
}

std::string planText(const hamal::flag::FloorPlan& plan) {
  std::ostringstream os;
  hamal::flag::writeFloorPlan(os, plan);
  return os.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] == 'm') {
    try {
      hamal::moss::parseWorld(text, "fuzz.world");
    } catch (const hamal::Error& e) {
      checkMessage(e.what(), "fuzz.world");
    } catch (const std::exception& e) {
      bug(std::string("the world reader threw something other than hamal::Error: ") + e.what());
    }
    return 0;
  }
  hamal::flag::FloorPlan plan;
  try {
    std::istringstream in(text);
    plan = hamal::flag::readFloorPlan(in, "fuzz.plan", 0.0, 1);
  } catch (const hamal::Error& e) {
    checkMessage(e.what(), "fuzz.plan");
    return 0;
  } catch (const std::exception& e) {
    bug(std::string("the floor-plan reader threw something other than hamal::Error: ") + e.what());
  }
  const std::string first = planText(plan);
  hamal::flag::FloorPlan again;
  try {
    std::istringstream in(first);
    again = hamal::flag::readFloorPlan(in, "fuzz.plan", 0.0, 1);
  } catch (const hamal::Error& e) {
    bug(std::string("the written floor plan does not read back: ") + e.what() + "\n" + first);
  }
  if (planText(again) != first) bug("writing the plan read back gives other text:\n" + first);
  return 0;
}
