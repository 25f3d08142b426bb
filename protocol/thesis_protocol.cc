// ThesisProtocol: see thesis_protocol.h.
#include "protocol/thesis_protocol.h"

#include <algorithm>
#include <limits>
#include <unordered_map>

#include "core/error.h"
#include "core/variable_prediction.h"
#include "factors/prior_factor.h"

namespace hamal {

namespace {
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

std::string describe(const Factor& f) {
  std::string s = f.tag();
  for (Key k : f.keys()) s += " " + k.str();
  return s;
}
}  // namespace

ThesisProtocol::ThesisProtocol(const Graph& graph) : ThesisProtocol(graph, Options()) {}

ThesisProtocol::ThesisProtocol(const Graph& graph, Options options) {
  std::vector<Key> poses;
  for (Key k : graph.keys())
    if (k.kind() == kPoseKind) poses.push_back(k);  // keys() is sorted by index
  if (poses.empty())
    throw Error(graph.source +
                ": the graph has no pose, so the thesis protocol has nothing to step");

  std::unordered_map<Key, std::size_t> step_of;
  plan_.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    plan_[i].pose = poses[i];
    step_of[poses[i]] = i;
  }

  // A factor completes at the step of its newest pose; a landmark enters
  // with the earliest factor that also touches a pose.
  std::vector<std::size_t> factor_step(graph.factors.size(), kNone);
  std::unordered_map<Key, std::pair<std::size_t, const Factor*>> landmark_first;
  for (std::size_t f = 0; f < graph.factors.size(); ++f) {
    const Factor& factor = *graph.factors[f];
    std::size_t s = kNone;
    for (Key k : factor.keys())
      if (k.kind() == kPoseKind) s = (s == kNone) ? step_of.at(k) : std::max(s, step_of.at(k));
    factor_step[f] = s;
    if (s == kNone) continue;
    for (Key k : factor.keys()) {
      if (k.kind() == kPoseKind) continue;
      auto it = landmark_first.find(k);
      if (it == landmark_first.end() || s < it->second.first) landmark_first[k] = {s, &factor};
    }
  }
  for (std::size_t f = 0; f < graph.factors.size(); ++f) {
    if (factor_step[f] != kNone) continue;
    std::size_t s = 0;
    for (Key k : graph.factors[f]->keys()) {
      auto it = landmark_first.find(k);
      if (it == landmark_first.end())
        throw Error(graph.source + ": variable " + k.str() +
                    " is connected to no pose, so the thesis protocol cannot initialise it (" +
                    describe(*graph.factors[f]) + ")");
      s = std::max(s, it->second.first);
    }
    factor_step[f] = s;
  }
  for (std::size_t f = 0; f < graph.factors.size(); ++f)
    plan_[factor_step[f]].factors.push_back(graph.factors[f]);
  // Landmarks in key order within a step, so steps do not depend on hashing.
  std::vector<Key> landmarks;
  for (const auto& kv : landmark_first) landmarks.push_back(kv.first);
  std::sort(landmarks.begin(), landmarks.end());
  for (Key k : landmarks) {
    const auto& [s, factor] = landmark_first.at(k);
    plan_[s].landmarks.emplace_back(k, factor);
  }

  fixed_ = graph.fixed;
  bool fixes_a_pose = false;
  for (Key k : fixed_) {
    if (graph.initial.contains(k)) fixed_values_.insertEntry(k, graph.initial.entry(k));
    fixes_a_pose |= k.kind() == kPoseKind;
  }

  // Pose i is initialised from the odometry edge to pose i-1, or failing
  // that from the first factor that ties it to an earlier pose.
  for (std::size_t i = 1; i < plan_.size(); ++i) {
    const Key cur = plan_[i].pose, prev = plan_[i - 1].pose;
    const Factor* odometry = nullptr;
    const Factor* fallback = nullptr;
    for (const auto& f : plan_[i].factors) {
      const auto& keys = f->keys();
      if (keys.size() != 2 || std::find(keys.begin(), keys.end(), cur) == keys.end()) continue;
      const Key other = keys[0] == cur ? keys[1] : keys[0];
      if (other == prev) {
        odometry = f.get();
        break;
      }
      if (!fallback && other.kind() == kPoseKind && other != cur) fallback = f.get();
    }
    plan_[i].initialiser = odometry ? odometry : fallback;
    if (!plan_[i].initialiser && !fixed_values_.contains(cur))
      throw Error(graph.source + ": pose " + cur.str() +
                  " has no factor to an earlier pose, so the thesis protocol cannot initialise it");
  }

  const Key first = plan_[0].pose;
  first_pose_ = graph.initial.contains(first) ? graph.initial.pose(first) : Pose2();
  if (options.add_prior && !fixes_a_pose)
    prior_ = std::make_shared<PriorFactor>(first, first_pose_,
                                           Eigen::Matrix3d(options.prior_information.asDiagonal()));
}

void ThesisProtocol::fill(std::size_t i, const Values& estimate, Step* out) const {
  const Plan& plan = plan_.at(i);
  out->index = i;
  // The guesses of this step see the estimate and the step's own new values.
  auto known = [&](const Factor& f, Key unknown) {
    Values v;
    for (Key k : f.keys()) {
      if (k == unknown || v.contains(k)) continue;
      if (out->new_values.contains(k))
        v.insertEntry(k, out->new_values.entry(k));
      else if (estimate.contains(k))
        v.insertEntry(k, estimate.entry(k));
    }
    return v;
  };
  auto guess = [&](const Factor& f, Key unknown) {
    Values::Entry e;
    if (!predictVariable(f, unknown, known(f, unknown), &e))
      throw Error("thesis protocol: " + describe(f) + " cannot initialise " + unknown.str() +
                  " (missing neighbour, or the factor kind cannot predict)");
    out->new_values.insertEntry(unknown, e);
  };

  // A fixed variable enters at the graph's value, which is what it is held at.
  auto add = [&](Key k, const Factor* from) {
    if (fixed_values_.contains(k))
      out->new_values.insertEntry(k, fixed_values_.entry(k));
    else if (from)
      guess(*from, k);
    else
      out->new_values.insert(k, first_pose_);
    if (fixed_.count(k)) out->fixed.push_back(k);
  };
  add(plan.pose, plan.initialiser);
  for (const auto& [landmark, factor] : plan.landmarks) add(landmark, factor);
  if (i == 0 && prior_) out->new_factors.push_back(prior_);
  out->new_factors.insert(out->new_factors.end(), plan.factors.begin(), plan.factors.end());
}

Step ThesisProtocol::step(std::size_t i, const Values& estimate) const {
  Step s;
  fill(i, estimate, &s);
  return s;
}

Values ThesisProtocol::initialValues() const {
  Values v;
  for (std::size_t i = 0; i < plan_.size(); ++i) {
    Step s = step(i, v);
    for (const auto& [key, entry] : s.new_values) v.insertEntry(key, entry);
  }
  return v;
}

Step ThesisProtocol::batch() const {
  Step all;
  for (std::size_t i = 0; i < plan_.size(); ++i) {
    Step s = step(i, all.new_values);
    for (const auto& [key, entry] : s.new_values) all.new_values.insertEntry(key, entry);
    all.new_factors.insert(all.new_factors.end(), s.new_factors.begin(), s.new_factors.end());
    all.fixed.insert(all.fixed.end(), s.fixed.begin(), s.fixed.end());
  }
  return all;
}

}  // namespace hamal
