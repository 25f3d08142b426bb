// Options: the key=value settings of a back-end, checked against what the
// back-end declares, so that "aprilsam:delta_t=0.01,nl_t=100" means the same
// from the command line, a sweep file or a plugin, and a misspelt key is an
// error that lists the known ones instead of a silent default.
//
// Names follow one rule across back-ends: a stopping tolerance is
// <quantity>_tolerance with Ceres' quantities (function_tolerance: the
// relative decrease of the cost; parameter_tolerance: the relative step;
// gradient_tolerance), spelled out, never _tol. A renamed option keeps its
// old name for a release (old_names): it is read as the new one and a line on
// stderr names the new one.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hamal {

struct OptionSpec {
  std::string name;
  std::string default_value;
  std::string help;                         // meaning, unit, and the thesis symbol if it has one
  std::vector<std::string> old_names = {};  // accepted for a release, with a warning
};

class Options {
 public:
  Options() = default;
  // Throws hamal::Error naming `owner` when `given` holds a key that `specs`
  // does not declare (the message lists the declared keys).
  Options(std::string owner, const std::vector<OptionSpec>& specs,
          const std::map<std::string, std::string>& given);

  // Typed access; throws hamal::Error when the value does not parse
  // ("aprilsam: option nl_t=abc is not an integer") or the key is undeclared.
  double getDouble(const std::string& name) const;
  long getInt(const std::string& name) const;
  bool getBool(const std::string& name) const;  // true/false/1/0/yes/no
  const std::string& getString(const std::string& name) const;
  // For enumerations: throws unless the value is one of `allowed`.
  const std::string& getChoice(const std::string& name,
                               const std::vector<std::string>& allowed) const;

  // Every declared key with its value (defaults filled in).
  const std::map<std::string, std::string>& values() const { return values_; }
  // "k=v,k=v", sorted by key: the exact configuration, for result files.
  std::string str() const;
  const std::string& owner() const { return owner_; }

 private:
  std::string owner_;
  std::map<std::string, std::string> values_;
};

// A back-end named with its options: "name" or "name:k=v,k=v".
struct BackendSpec {
  std::string name;
  std::map<std::string, std::string> options;

  // Throws hamal::Error on a malformed spec ("aprilsam:delta_t" has no '=').
  static BackendSpec parse(const std::string& text);
  std::string str() const;
};

}  // namespace hamal
