// Options: see options.h.
#include "core/options.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <set>

#include "core/error.h"

namespace hamal {

namespace {
std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}
// A spec is resolved more than once per run (checked, then made): one line
// per old name and process is enough.
void warnOnce(const std::string& line) {
  static std::mutex mutex;
  static std::set<std::string> said;
  const std::lock_guard<std::mutex> lock(mutex);
  if (said.insert(line).second) std::cerr << line << std::endl;
}
}  // namespace

Options::Options(std::string owner, const std::vector<OptionSpec>& specs,
                 const std::map<std::string, std::string>& given)
    : owner_(std::move(owner)) {
  for (const auto& s : specs) values_[s.name] = s.default_value;
  for (const auto& [given_key, value] : given) {
    std::string key = given_key;
    for (const auto& s : specs)
      for (const auto& old : s.old_names)
        if (old == given_key) {
          if (given.count(s.name))
            throw Error(owner_ + ": option '" + old + "' is an old name of '" + s.name +
                        "'; give '" + s.name + "' only");
          warnOnce(owner_ + ": option '" + old + "' is an old name; use '" + s.name + "'");
          key = s.name;
        }
    if (!values_.count(key)) {
      std::string known;
      for (const auto& s : specs) known += (known.empty() ? "" : ", ") + s.name;
      throw Error(owner_ + ": unknown option '" + key +
                  "'; known options: " + (known.empty() ? "(none)" : known));
    }
    values_[key] = value;
  }
}

const std::string& Options::getString(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) throw Error(owner_ + ": option '" + name + "' is not declared");
  return it->second;
}

double Options::getDouble(const std::string& name) const {
  const std::string& s = getString(name);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v))
    throw Error(owner_ + ": option " + name + "=" + s + " is not a finite number");
  return v;
}

long Options::getInt(const std::string& name) const {
  const std::string& s = getString(name);
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno == ERANGE)
    throw Error(owner_ + ": option " + name + "=" + s + " is not an integer");
  return v;
}

bool Options::getBool(const std::string& name) const {
  const std::string& s = getString(name);
  if (s == "true" || s == "1" || s == "yes" || s == "on") return true;
  if (s == "false" || s == "0" || s == "no" || s == "off") return false;
  throw Error(owner_ + ": option " + name + "=" + s + " is not a boolean (true/false)");
}

const std::string& Options::getChoice(const std::string& name,
                                      const std::vector<std::string>& allowed) const {
  const std::string& s = getString(name);
  std::string list;
  for (const auto& a : allowed) {
    if (a == s) return s;
    list += (list.empty() ? "" : ", ") + a;
  }
  throw Error(owner_ + ": option " + name + "=" + s + " is not one of: " + list);
}

std::string Options::str() const {
  std::string out;
  for (const auto& [k, v] : values_) out += (out.empty() ? "" : ",") + k + "=" + v;
  return out;
}

BackendSpec BackendSpec::parse(const std::string& text) {
  BackendSpec spec;
  const auto colon = text.find(':');
  spec.name = trim(text.substr(0, colon));
  if (spec.name.empty()) throw Error("back-end spec '" + text + "' has no name");
  if (colon == std::string::npos) return spec;
  std::string rest = text.substr(colon + 1);
  std::size_t pos = 0;
  while (pos <= rest.size()) {
    const auto comma = rest.find(',', pos);
    const std::string item =
        trim(rest.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    if (!item.empty()) {
      const auto eq = item.find('=');
      if (eq == std::string::npos || trim(item.substr(0, eq)).empty())
        throw Error("back-end spec '" + text + "': '" + item + "' is not key=value");
      const std::string key = trim(item.substr(0, eq));
      if (spec.options.count(key))
        throw Error("back-end spec '" + text + "': option '" + key + "' given twice");
      spec.options[key] = trim(item.substr(eq + 1));
    }
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return spec;
}

std::string BackendSpec::str() const {
  std::string out = name;
  char sep = ':';
  for (const auto& [k, v] : options) {
    out += sep + k + "=" + v;
    sep = ',';
  }
  return out;
}

}  // namespace hamal
