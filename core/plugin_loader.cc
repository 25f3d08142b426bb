// Plugin loader: implements core/plugin.h.
//
// The plugin registers into an empty staging Registry and the staging
// registry is merged in one go, so a plugin that fails half way (an
// exception, a duplicate name) leaves the caller's registry exactly as it
// was. Library handles are never closed: the registered std::functions point
// into the plugin's code for as long as the process runs.
#include <dirent.h>
#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "core/plugin.h"

namespace hamal {

namespace {

using AbiFunction = int (*)();
using RegisterFunction = void (*)(Registry*);

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
  throw Error("plugin " + path + ": " + reason);
}

std::string dlerrorText() {
  const char* e = dlerror();
  return e ? e : "unknown dlopen error";
}

bool isPluginFileName(const std::string& name) {
  const std::string prefix = "lib", suffix = ".so";
  return name.size() > prefix.size() + suffix.size() &&
         name.compare(0, prefix.size(), prefix) == 0 &&
         name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

void loadPlugin(const std::string& path, Registry& registry) {
  if (path.empty()) throw Error("plugin: empty path");
  dlerror();  // clear any stale message
  // RTLD_NOW: an unresolved symbol is reported here, not as a crash later.
  // RTLD_LOCAL: two plugins may use the same internal names.
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) fail(path, "cannot load: " + dlerrorText());

  dlerror();
  auto abi = reinterpret_cast<AbiFunction>(dlsym(handle, "hamal_plugin_abi"));
  auto reg = reinterpret_cast<RegisterFunction>(dlsym(handle, "hamal_plugin_register"));
  if (!reg) fail(path, "no hamal_plugin_register symbol: is this a hamal plugin?");
  if (!abi)
    fail(path, "no hamal_plugin_abi symbol: is this a hamal plugin (built with HAMAL_PLUGIN)?");
  const int plugin_abi = abi();
  if (plugin_abi != HAMAL_PLUGIN_ABI)
    fail(path, "ABI mismatch: the plugin was built for plugin ABI " + std::to_string(plugin_abi) +
                   ", this hamal has ABI " + std::to_string(HAMAL_PLUGIN_ABI) +
                   "; rebuild the plugin against these headers");

  Registry staging;
  try {
    reg(&staging);
  } catch (const std::exception& e) {
    fail(path, std::string("registration failed: ") + e.what());
  } catch (...) {
    fail(path, "registration failed with an exception that is not a std::exception");
  }
  try {
    registry.merge(staging);
  } catch (const Error& e) {
    fail(path, std::string("not loaded, nothing registered: ") + e.what());
  }
  // The handle stays open for the lifetime of the process (see the file comment).
}

std::vector<std::string> loadPluginsFromPath(Registry& registry, const char* env_var) {
  std::vector<std::string> loaded;
  const char* value = env_var ? std::getenv(env_var) : nullptr;
  if (!value || !*value) return loaded;
  std::stringstream dirs(value);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    DIR* d = opendir(dir.c_str());
    if (!d) throw Error(std::string(env_var) + ": cannot open plugin directory '" + dir + "'");
    std::vector<std::string> names;
    while (const dirent* entry = readdir(d))
      if (isPluginFileName(entry->d_name)) names.push_back(entry->d_name);
    closedir(d);
    std::sort(names.begin(), names.end());
    for (const auto& name : names) {
      const std::string path = dir + "/" + name;
      loadPlugin(path, registry);
      loaded.push_back(path);
    }
  }
  return loaded;
}

}  // namespace hamal
