// Values: see values.h.
#include "core/values.h"

#include <algorithm>

#include "core/error.h"

namespace hamal {

int dimension(VariableType type) { return type == VariableType::kPose2 ? 3 : 2; }

const char* typeName(VariableType type) {
  return type == VariableType::kPose2 ? "Pose2" : "Point2";
}

namespace {
Values::Entry poseEntry(const Pose2& p) { return {VariableType::kPose2, {p.x, p.y, p.theta}}; }
Values::Entry pointEntry(const Point2& p) { return {VariableType::kPoint2, {p.x(), p.y(), 0.0}}; }
}  // namespace

void Values::insert(Key key, const Pose2& pose) { insertEntry(key, poseEntry(pose)); }
void Values::insert(Key key, const Point2& point) { insertEntry(key, pointEntry(point)); }
void Values::insertEntry(Key key, const Entry& entry) {
  if (!map_.emplace(key, entry).second) throw Error("variable " + key.str() + " already exists");
}
void Values::set(Key key, const Pose2& pose) { setEntry(key, poseEntry(pose)); }
void Values::set(Key key, const Point2& point) { setEntry(key, pointEntry(point)); }
void Values::setEntry(Key key, const Entry& entry) { map_[key] = entry; }

const Values::Entry& Values::entry(Key key) const {
  auto it = map_.find(key);
  if (it == map_.end()) throw Error("variable " + key.str() + " does not exist");
  return it->second;
}

Pose2 Values::pose(Key key) const {
  const Entry& e = entry(key);
  if (e.type != VariableType::kPose2) throw Error("variable " + key.str() + " is not a Pose2");
  return {e.data[0], e.data[1], e.data[2]};
}

Point2 Values::point(Key key) const {
  const Entry& e = entry(key);
  if (e.type != VariableType::kPoint2) throw Error("variable " + key.str() + " is not a Point2");
  return {e.data[0], e.data[1]};
}

double* Values::data(Key key) { return const_cast<Entry&>(entry(key)).data.data(); }
const double* Values::data(Key key) const { return entry(key).data.data(); }

void Values::retract(Key key, const double* delta) {
  Entry& e = const_cast<Entry&>(entry(key));
  const int d = dimension(e.type);
  for (int i = 0; i < d; ++i) e.data[i] += delta[i];
  if (e.type == VariableType::kPose2) e.data[2] = wrapAngle(e.data[2]);
}

void Values::normalizeAngles() {
  for (auto& [key, e] : map_)
    if (e.type == VariableType::kPose2) e.data[2] = wrapAngle(e.data[2]);
}

std::vector<Key> Values::keys() const {
  std::vector<Key> out;
  out.reserve(map_.size());
  for (const auto& kv : map_) out.push_back(kv.first);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace hamal
