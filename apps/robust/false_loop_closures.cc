// FalseLoopClosures: see false_loop_closures.h.
#include "apps/robust/false_loop_closures.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "apps/robust/seeded_random.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "factors/between_factor.h"

namespace hamal::apps {

namespace {
constexpr EnumNames<SpoilPolicy, 4> kSpoilPolicies = {{{SpoilPolicy::kRandom, "random"},
                                                       {SpoilPolicy::kLocal, "local"},
                                                       {SpoilPolicy::kRandomGroup, "random-group"},
                                                       {SpoilPolicy::kLocalGroup, "local-group"}}};
}  // namespace

SpoilPolicy parseSpoilPolicy(const std::string& name) {
  return parseEnum(kSpoilPolicies, name, "spoiling policy");
}

const char* spoilPolicyName(SpoilPolicy policy) { return enumName(kSpoilPolicies, policy); }

namespace {

bool isLocal(SpoilPolicy p) { return p == SpoilPolicy::kLocal || p == SpoilPolicy::kLocalGroup; }
bool isGrouped(SpoilPolicy p) {
  return p == SpoilPolicy::kRandomGroup || p == SpoilPolicy::kLocalGroup;
}

// The poses by rank and the pairs (by rank) that some factor already joins.
struct PoseTable {
  std::vector<std::uint64_t> ids;            // sorted
  std::unordered_set<std::uint64_t> joined;  // code(i, j), i < j ranks

  std::uint64_t code(std::uint64_t i, std::uint64_t j) const { return i * ids.size() + j; }
};

PoseTable poseTable(const Graph& clean) {
  PoseTable t;
  for (Key k : clean.keys())
    if (k.kind() == kPoseKind) t.ids.push_back(k.index());  // keys() is sorted
  std::unordered_map<std::uint64_t, std::uint64_t> rank;
  for (std::size_t r = 0; r < t.ids.size(); ++r) rank[t.ids[r]] = r;
  for (const auto& f : clean.factors) {
    const auto& keys = f->keys();
    if (keys.size() != 2 || keys[0].kind() != kPoseKind || keys[1].kind() != kPoseKind) continue;
    std::uint64_t a = rank.at(keys[0].index()), b = rank.at(keys[1].index());
    if (a > b) std::swap(a, b);
    t.joined.insert(t.code(a, b));
  }
  return t;
}

void checkOptions(const Graph& clean, const SpoilOptions& o) {
  if (isGrouped(o.policy) && o.group_size < 1)
    throw Error(clean.source + ": spoiling: group_size must be at least 1");
  if (isLocal(o.policy) && o.local_window < 2)
    throw Error(clean.source + ": spoiling: local_window must be at least 2 (j - i >= 2)");
  if (!(o.sigma_xy >= 0) || !(o.sigma_theta >= 0))
    throw Error(clean.source + ": spoiling: the sigmas must be non-negative");
}

// Largest j - i a pair may have under the policy, for P poses.
std::uint64_t maxGap(const SpoilOptions& o, std::uint64_t poses) {
  return isLocal(o.policy) ? std::min<std::uint64_t>(o.local_window, poses - 1) : poses - 1;
}

std::uint64_t countFree(const PoseTable& t, const SpoilOptions& o) {
  const std::uint64_t P = t.ids.size();
  if (P < 3) return 0;
  const std::uint64_t gmax = maxGap(o, P);
  // Pairs with gap d in [2, gmax]: P - d of each.
  std::uint64_t all = 0;
  for (std::uint64_t d = 2; d <= gmax; ++d) all += P - d;
  std::uint64_t taken = 0;
  for (std::uint64_t c : t.joined) {
    const std::uint64_t i = c / P, j = c % P;
    if (j - i >= 2 && j - i <= gmax) ++taken;
  }
  return all - taken;
}

// Odometry joins poses next to each other in id order, which is not id + 1
// when landmarks take ids between them (Victoria Park): ranks, not ids.
const BetweenFactor* firstLoopClosure(const Graph& clean, const PoseTable& table) {
  const auto rank = [&](Key k) {
    return static_cast<std::uint64_t>(
        std::lower_bound(table.ids.begin(), table.ids.end(), k.index()) - table.ids.begin());
  };
  for (const auto& f : clean.factors) {
    const auto* b = dynamic_cast<const BetweenFactor*>(f.get());
    if (!b) continue;
    const std::uint64_t a = rank(b->keys()[0]), c = rank(b->keys()[1]);
    if ((a > c ? a - c : c - a) > 1) return b;
  }
  return nullptr;
}

}  // namespace

std::uint64_t freePosePairs(const Graph& clean, const SpoilOptions& options) {
  checkOptions(clean, options);
  return countFree(poseTable(clean), options);
}

SpoiledGraph spoilGraph(const Graph& clean, const SpoilOptions& options) {
  checkOptions(clean, options);
  PoseTable table = poseTable(clean);
  const std::uint64_t P = table.ids.size();
  SpoiledGraph out;
  out.graph = clean;
  if (options.outliers == 0) return out;
  if (P < 3) throw Error(clean.source + ": spoiling needs at least 3 poses");
  const BetweenFactor* model = firstLoopClosure(clean, table);
  if (!model)
    throw Error(clean.source +
                ": no loop closure between factor to take the false edges' information from");
  const std::uint64_t free = countFree(table, options);
  if (options.outliers > free)
    throw Error(clean.source + ": asked for " + std::to_string(options.outliers) +
                " false loop closures but policy " + spoilPolicyName(options.policy) +
                " has only " + std::to_string(free) + " free pose pairs");

  const std::uint64_t group = isGrouped(options.policy) ? options.group_size : 1;
  const std::uint64_t gmax = maxGap(options, P);
  SeededRandom random(options.seed);
  std::vector<std::pair<std::uint64_t, std::uint64_t>> candidates;  // enumerated starts
  std::uint64_t enumerated_length = 0;
  bool enumerating = false;
  std::size_t made = 0, groups = 0;

  // A start (i, j) with `length` edges (i+k, j+k) fits when every pair is in
  // range and free.
  auto fits = [&](std::uint64_t i, std::uint64_t j, std::uint64_t length) {
    if (j < i + 2 || j - i > gmax || j + length > P) return false;
    for (std::uint64_t k = 0; k < length; ++k)
      if (table.joined.count(table.code(i + k, j + k))) return false;
    return true;
  };
  // Draws bounded by a budget of failures in a row; past it the fitting
  // starts are listed (when that is affordable) and drawn from, so a nearly
  // full pair space ends in an answer or an error, never in a loop.
  constexpr std::uint64_t kFailuresBeforeListing = 2000;
  constexpr std::uint64_t kMaxListed = 20000000;
  constexpr std::uint64_t kMaxDraws = 200000000;
  std::uint64_t failures = 0, draws = 0;

  while (made < options.outliers) {
    const std::uint64_t length = std::min<std::uint64_t>(group, options.outliers - made);
    std::uint64_t i = 0, j = 0;
    bool found = false;
    if (!enumerating) {
      while (failures < kFailuresBeforeListing) {
        ++draws;
        const std::uint64_t span = P - length + 1;  // starts with room for the group
        if (isLocal(options.policy)) {
          i = random.below(span);
          j = i + 2 + random.below(gmax - 1);
        } else {
          i = random.below(span);
          j = random.below(span);
          if (i > j) std::swap(i, j);
        }
        if (fits(i, j, length)) {
          found = true;
          failures = 0;
          break;
        }
        ++failures;
      }
      if (!found) {
        std::uint64_t space = 0;
        for (std::uint64_t d = 2; d <= gmax && d < P; ++d) space += P - d;
        if (space > kMaxListed && draws < kMaxDraws) {
          failures = 0;  // too many starts to list: keep drawing, within kMaxDraws
          continue;
        }
        if (space > kMaxListed)
          throw Error(clean.source + ": gave up placing false loop closures after " +
                      std::to_string(draws) + " draws (" + std::to_string(made) + " of " +
                      std::to_string(options.outliers) + " placed)");
        enumerating = true;
      }
    }
    if (enumerating && !found) {
      if (enumerated_length != length) {
        candidates.clear();
        for (std::uint64_t a = 0; a < P; ++a)
          for (std::uint64_t b = a + 2; b <= a + gmax && b < P; ++b)
            if (fits(a, b, length)) candidates.emplace_back(a, b);
        enumerated_length = length;
      }
      // Starts taken since the listing are dropped as they are met.
      while (!candidates.empty()) {
        const std::size_t pick = random.below(candidates.size());
        const auto [a, b] = candidates[pick];
        if (fits(a, b, length)) {
          i = a;
          j = b;
          found = true;
          break;
        }
        candidates[pick] = candidates.back();
        candidates.pop_back();
      }
      if (!found)
        throw Error(clean.source + ": only " + std::to_string(made) + " of " +
                    std::to_string(options.outliers) + " false loop closures fit with policy " +
                    spoilPolicyName(options.policy) + ": no free pose pairs left for a group of " +
                    std::to_string(length));
    }
    const Pose2 z(random.normal() * options.sigma_xy, random.normal() * options.sigma_xy,
                  random.normal() * options.sigma_theta);
    for (std::uint64_t k = 0; k < length; ++k) {
      table.joined.insert(table.code(i + k, j + k));
      FalseEdge e;
      e.factor = out.graph.factors.size();
      e.from = table.ids[i + k];
      e.to = table.ids[j + k];
      e.group = groups;
      out.graph.add(std::make_shared<BetweenFactor>(X(e.from), X(e.to), z, model->information()));
      out.false_edges.push_back(e);
    }
    made += length;
    ++groups;
  }
  return out;
}

}  // namespace hamal::apps
