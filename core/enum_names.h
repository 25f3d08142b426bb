// EnumNames: an enum's names on the command line and in files, as one table
// per enum, so that reading and writing a value cannot disagree and every
// refusal reads alike: "unknown <what> 'x'; expected a, b or c".
//
// A table lists each value once under the name it is written with; further
// entries for the same value are aliases that are read but never written.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

namespace hamal {

template <class E, std::size_t N>
using EnumNames = std::array<std::pair<E, const char*>, N>;

// The name `value` is written with: its first entry in `names`.
template <class E, std::size_t N>
const char* enumName(const EnumNames<E, N>& names, E value) {
  for (const auto& [v, name] : names)
    if (v == value) return name;
  return "unknown";
}

// "a, b or c": every name of the table, aliases too.
template <class E, std::size_t N>
std::string enumNameList(const EnumNames<E, N>& names) {
  std::string list;
  for (std::size_t i = 0; i < N; ++i)
    list += (i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(names[i].second);
  return list;
}

// Every name, aliases too (for Options::getChoice).
template <class E, std::size_t N>
std::vector<std::string> enumNameVector(const EnumNames<E, N>& names) {
  std::vector<std::string> out;
  for (const auto& entry : names) out.push_back(entry.second);
  return out;
}

// The value named `name`; throws Error "unknown <what> 'name'; expected ...".
template <class E, std::size_t N>
E parseEnum(const EnumNames<E, N>& names, const std::string& name, const std::string& what) {
  for (const auto& [v, n] : names)
    if (name == n) return v;
  throw Error("unknown " + what + " '" + name + "'; expected " + enumNameList(names));
}

}  // namespace hamal
