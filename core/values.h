// Values: the state of a factor graph, one entry per variable (thesis
// sec. 2.2.2: the x of the least-squares problem).
//
// Each entry stores its parameters contiguously, so a back-end can hand
// `data(key)` to ceres::Problem as a parameter block; the pointer stays valid
// until the entry is erased (entries are nodes of an unordered_map, which
// rehashing does not move). Back-ends never assume a dimension: they ask
// `dim(key)` and move a variable with `retract`, which knows which component
// is an angle.
#pragma once

#include <array>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/key.h"
#include "core/pose2.h"

namespace hamal {

enum class VariableType { kPose2, kPoint2 };

// Dimension of a variable type's tangent space (= its parameter count here).
int dimension(VariableType type);
const char* typeName(VariableType type);

class Values {
 public:
  struct Entry {
    VariableType type;
    std::array<double, 3> data;
  };

  void insert(Key key, const Pose2& pose);
  void insert(Key key, const Point2& point);
  // Copies an entry of any type (used to move guesses between Values).
  void insertEntry(Key key, const Entry& entry);
  // Insert or overwrite.
  void set(Key key, const Pose2& pose);
  void set(Key key, const Point2& point);
  void setEntry(Key key, const Entry& entry);
  void erase(Key key) { map_.erase(key); }

  bool contains(Key key) const { return map_.count(key) != 0; }
  std::size_t size() const { return map_.size(); }
  bool empty() const { return map_.empty(); }

  // Throw hamal::Error when the key is missing or of another type.
  Pose2 pose(Key key) const;
  Point2 point(Key key) const;
  const Entry& entry(Key key) const;
  VariableType type(Key key) const { return entry(key).type; }
  int dim(Key key) const { return dimension(entry(key).type); }
  double* data(Key key);
  const double* data(Key key) const;

  // x <- x boxplus delta (plain addition, angles wrapped to (-pi, pi]).
  void retract(Key key, const double* delta);
  // Wraps every pose's angle; Ceres leaves them unwrapped while it iterates.
  void normalizeAngles();

  // Every key, sorted (kind, then index): deterministic for writers and tests.
  std::vector<Key> keys() const;

  auto begin() const { return map_.begin(); }
  auto end() const { return map_.end(); }

 private:
  std::unordered_map<Key, Entry> map_;
};

}  // namespace hamal
