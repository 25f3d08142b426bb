// Registry: see registry.h.
#include "core/registry.h"

#include <sstream>

#include "core/error.h"

namespace hamal {

BackendInfo BackendInfo::variant(std::string variant_name, std::string variant_description,
                                 const std::map<std::string, std::string>& defaults) const {
  BackendInfo v = *this;
  v.name = std::move(variant_name);
  v.description = std::move(variant_description);
  for (const auto& [key, value] : defaults) {
    bool found = false;
    for (auto& o : v.options)
      if (o.name == key) {
        o.default_value = value;
        found = true;
      }
    if (!found) throw Error("variant " + v.name + " of " + name + ": no option '" + key + "'");
  }
  return v;
}

void Registry::addBackend(BackendInfo info) {
  if (info.name.empty() || !info.create) throw Error("a back-end needs a name and a factory");
  if (info.name.find_first_of(":,= \t") != std::string::npos)
    throw Error("back-end name '" + info.name + "' may not contain ':', ',', '=' or spaces");
  if (backends_.count(info.name))
    throw Error("a back-end named '" + info.name + "' is already registered");
  std::string name = info.name;
  backends_.emplace(std::move(name), std::move(info));
}

void Registry::addFactor(FactorInfo info) {
  if (info.format.empty() || info.tag.empty() || !info.parse)
    throw Error("a factor kind needs a format, a tag and a parse function");
  if (info.tag.find_first_of(" \t") != std::string::npos)
    throw Error("factor tag '" + info.tag + "' may not contain white space");
  auto key = std::make_pair(info.format, info.tag);
  if (factors_.count(key))
    throw Error("a factor kind with tag '" + info.tag + "' is already registered for format " +
                info.format);
  factors_.emplace(std::move(key), std::move(info));
}

void Registry::merge(const Registry& other) {
  for (const auto& [name, info] : other.backends_)
    if (backends_.count(name)) throw Error("a back-end named '" + name + "' is already registered");
  for (const auto& [key, info] : other.factors_)
    if (factors_.count(key))
      throw Error("a factor kind with tag '" + key.second + "' is already registered for format " +
                  key.first);
  for (const auto& kv : other.backends_) backends_.insert(kv);
  for (const auto& kv : other.factors_) factors_.insert(kv);
}

const BackendInfo* Registry::findBackend(const std::string& name) const {
  auto it = backends_.find(name);
  return it == backends_.end() ? nullptr : &it->second;
}

const FactorInfo* Registry::findFactor(const std::string& format, const std::string& tag) const {
  auto it = factors_.find({format, tag});
  return it == factors_.end() ? nullptr : &it->second;
}

FactorPtr Registry::parseFactor(LineTokens tokens) const {
  const FactorInfo* info = findFactor(tokens.format(), tokens.tag());
  if (!info) {
    std::string known;
    for (const auto& [key, f] : factors_)
      if (key.first == tokens.format()) known += (known.empty() ? "" : ", ") + key.second;
    tokens.fail("unknown tag " + quoted(tokens.tag()) + " for format " + tokens.format() +
                "; known factor tags: " + (known.empty() ? "(none registered)" : known));
  }
  FactorPtr factor = info->parse(tokens);
  if (!factor) tokens.fail(tokens.tag() + ": the factor kind's parse function returned nothing");
  tokens.expectEnd();
  return factor;
}

Options Registry::resolveOptions(const BackendSpec& spec) const {
  const BackendInfo* info = findBackend(spec.name);
  if (!info) {
    std::string names;
    for (const auto& kv : backends_) names += (names.empty() ? "" : ", ") + kv.first;
    throw Error("unknown back-end '" + spec.name + "'; registered: " + names);
  }
  return Options(spec.name, info->options, spec.options);
}

std::unique_ptr<Backend> Registry::makeBackend(const BackendSpec& spec) const {
  Options options = resolveOptions(spec);
  return findBackend(spec.name)->create(options);
}

std::unique_ptr<Backend> Registry::makeBackend(const std::string& spec) const {
  return makeBackend(BackendSpec::parse(spec));
}

std::vector<const BackendInfo*> Registry::backends() const {
  std::vector<const BackendInfo*> out;
  for (const auto& kv : backends_) out.push_back(&kv.second);
  return out;
}

std::vector<const FactorInfo*> Registry::factors() const {
  std::vector<const FactorInfo*> out;
  for (const auto& kv : factors_) out.push_back(&kv.second);
  return out;
}

std::string Registry::describeBackends() const {
  std::ostringstream os;
  for (const auto& [name, info] : backends_) {
    os << name << "\n    " << info.description << "\n";
    for (const auto& o : info.options)
      os << "    " << o.name << "=" << o.default_value << "    " << o.help << "\n";
  }
  return os.str();
}

std::string Registry::describeFactors() const {
  std::ostringstream os;
  for (const auto& [key, info] : factors_)
    os << key.first << "\t" << key.second << "\t" << info.description << "\n";
  return os.str();
}

}  // namespace hamal
