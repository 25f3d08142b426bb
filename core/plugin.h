// Plugins: shared libraries that add factor kinds and back-ends at run time,
// with no rebuild of hamal (plugins/example/README.md shows one).
//
// A plugin uses only hamal's public headers and defines its entry point with
// the macro below:
//
//   #include "core/plugin.h"
//   HAMAL_PLUGIN(registry) {
//     registry->addFactor({"g2o", "EDGE_SE2_CAUCHY", "between with a Cauchy loss", &parse});
//   }
//
// The macro exports two C functions: hamal_plugin_abi(), checked against the
// loader's HAMAL_PLUGIN_ABI before anything else, and
// hamal_plugin_register(Registry*). An explicit entry point instead of
// static-registration macros keeps plugins working in static builds and
// leaves no registration to the order of static initialisers (g2o's issues
// #4, #58, #830).
//
// A plugin registers into an empty staging registry that is merged in one
// go, so a plugin with a duplicate name adds nothing at all.
#pragma once

#include <string>
#include <vector>

#include "core/registry.h"

#define HAMAL_PLUGIN_ABI 1

#define HAMAL_PLUGIN(registry)                                                  \
  extern "C" __attribute__((visibility("default"))) int hamal_plugin_abi() {    \
    return HAMAL_PLUGIN_ABI;                                                    \
  }                                                                             \
  extern "C" __attribute__((visibility("default"))) void hamal_plugin_register( \
      ::hamal::Registry* registry)

namespace hamal {

// Loads the shared library at `path` into `registry`. Throws hamal::Error
// naming the path and the reason (dlopen's message, a missing entry point,
// an ABI mismatch, a duplicate name, an exception from the plugin).
void loadPlugin(const std::string& path, Registry& registry);

// Loads every lib*.so in the directories of the ':'-separated variable
// `env_var` (HAMAL_PLUGIN_PATH by default), in sorted order. Returns the
// paths loaded; the first failure throws.
std::vector<std::string> loadPluginsFromPath(Registry& registry,
                                             const char* env_var = "HAMAL_PLUGIN_PATH");

}  // namespace hamal
