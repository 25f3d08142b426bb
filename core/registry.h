// Registry: every factor kind and back-end hamal can make, by name (DESIGN.md,
// "The interfaces that matter"). Built-ins and plugins register the same way,
// so a researcher's back-end is picked by name exactly as `aprilsam` is.
//
// Factor kinds are registered per file format and tag (("g2o", "EDGE_SE2")):
// the same tag means different things in different formats (EDGE2 is TORO
// information in M3500.toro, covariance in w20000.txt).
//
// Back-ends are registered with their options declared; variants of one
// back-end ("aprilsam-periodic") are the same factory with other defaults.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/line_tokens.h"
#include "core/options.h"

namespace hamal {

struct BackendInfo {
  std::string name;
  std::string description;
  std::vector<OptionSpec> options;
  std::function<std::unique_ptr<Backend>(const Options&)> create;

  // The same back-end under another name with some defaults changed.
  BackendInfo variant(std::string variant_name, std::string variant_description,
                      const std::map<std::string, std::string>& defaults) const;
};

struct FactorInfo {
  std::string format;  // "g2o", "toro", "gtsam"
  std::string tag;     // the first field of the line
  std::string description;
  // Reads the fields after the tag; fails through tokens.fail(...).
  std::function<FactorPtr(LineTokens& tokens)> parse;
};

class Registry {
 public:
  // Throw hamal::Error on a name (or format and tag) that is already taken,
  // or an entry without a name or function.
  void addBackend(BackendInfo info);
  void addFactor(FactorInfo info);
  // Adds every entry of `other`, or none of them when one is a duplicate.
  void merge(const Registry& other);

  // From a spec "name:k=v,...". Throws hamal::Error for an unknown name (the
  // message lists the registered ones) or bad options.
  std::unique_ptr<Backend> makeBackend(const std::string& spec) const;
  std::unique_ptr<Backend> makeBackend(const BackendSpec& spec) const;
  // The options a spec resolves to (defaults filled in), for result files.
  Options resolveOptions(const BackendSpec& spec) const;

  const BackendInfo* findBackend(const std::string& name) const;
  const FactorInfo* findFactor(const std::string& format, const std::string& tag) const;
  // Parses a whole factor line, tag first, with the kind registered for
  // (tokens.format(), tag) and checks that it read every field. Fails on the
  // line for an unknown tag (naming the known ones) or a parse that returns
  // nothing. A parse function that wraps another factor's line calls it as
  //   tokens.registry()->parseFactor(tokens.rest("inner tag"))
  // so the inner line may be of any kind this registry holds, a plugin's too.
  FactorPtr parseFactor(LineTokens tokens) const;
  std::vector<const BackendInfo*> backends() const;  // sorted by name
  std::vector<const FactorInfo*> factors() const;    // sorted by format, tag

  // Human-readable listings for --list-backends / --list-factors.
  std::string describeBackends() const;
  std::string describeFactors() const;

 private:
  std::map<std::string, BackendInfo> backends_;
  std::map<std::pair<std::string, std::string>, FactorInfo> factors_;
};

}  // namespace hamal
