// Key: the name of one variable in a factor graph (thesis sec. 2.2.1).
//
// Files number poses and landmarks from one id space (g2o) or from two that
// overlap (victoria_park.txt uses one space, other files reuse ids), so a
// Key carries its kind next to its index: pose 5 and landmark 5 are
// different variables. The kind is a character, as in GTSAM's Symbol:
// 'x' for poses, 'l' for landmarks; plugins may use other letters.
#pragma once

#include <cstdint>
#include <functional>
#include <ostream>
#include <string>

namespace hamal {

class Key {
 public:
  static constexpr int kIndexBits = 56;
  static constexpr std::uint64_t kMaxIndex = (std::uint64_t{1} << kIndexBits) - 1;

  constexpr Key() = default;
  constexpr Key(char kind, std::uint64_t index)
      : value_((std::uint64_t(static_cast<unsigned char>(kind)) << kIndexBits) |
               (index & kMaxIndex)) {}

  constexpr char kind() const { return static_cast<char>(value_ >> kIndexBits); }
  constexpr std::uint64_t index() const { return value_ & kMaxIndex; }
  constexpr std::uint64_t raw() const { return value_; }

  std::string str() const { return std::string(1, kind()) + std::to_string(index()); }

  friend constexpr bool operator==(Key a, Key b) { return a.value_ == b.value_; }
  friend constexpr bool operator!=(Key a, Key b) { return a.value_ != b.value_; }
  // Orders by kind, then index: landmarks ('l') sort before poses ('x'), and
  // poses of one kind sort by index, which the thesis protocol relies on.
  friend constexpr bool operator<(Key a, Key b) { return a.value_ < b.value_; }
  friend std::ostream& operator<<(std::ostream& os, Key k) { return os << k.str(); }

 private:
  std::uint64_t value_ = 0;
};

constexpr char kPoseKind = 'x';
constexpr char kLandmarkKind = 'l';

// Shorthands, as GTSAM's X(i) and L(i).
constexpr Key X(std::uint64_t i) { return Key(kPoseKind, i); }
constexpr Key L(std::uint64_t i) { return Key(kLandmarkKind, i); }

}  // namespace hamal

template <>
struct std::hash<hamal::Key> {
  std::size_t operator()(hamal::Key k) const noexcept {
    return std::hash<std::uint64_t>()(k.raw());
  }
};
