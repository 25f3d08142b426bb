// MossSelection: see moss_selection.h (thesis Alg. 5.1).
#include "apps/moss/moss_selection.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>

#include "apps/moss/parallel_for.h"
#include "core/error.h"
#include "core/output_file.h"

namespace hamal::moss {

namespace {

struct ClimbState {
  int step = 0;
  Selection current;
  double error = 0.0;
  std::mt19937_64 rng;
};

std::string checkpointPath(const MossConfig& config, int c, int t) {
  return config.checkpoint_dir + "/moss_C" + std::to_string(c) + "_t" + std::to_string(t) + "_s" +
         std::to_string(config.seed) + ".climb";
}

// In place at once, not with the run's other outputs (OutputBatch): a
// checkpoint is for a run that is killed before its end.
void writeState(const std::string& path, const ClimbState& s) {
  writeOutputFileNow(path, [&](std::ostream& out) {
    out.precision(17);
    out << s.step << ' ' << s.error << '\n';
    for (char x : s.current) out << (x ? '1' : '0');
    out << '\n' << s.rng << '\n';
  });
}

// A checkpoint of this climb: of the map's m nodes, C selected (one of
// another C, e.g. copied or renamed, would resume a climb of another size).
bool readState(const std::string& path, std::size_t m, int c, ClimbState* s) {
  std::ifstream in(path);
  if (!in) return false;
  std::string bits;
  if (!(in >> s->step >> s->error >> bits >> s->rng) || bits.size() != m || s->step < 0 ||
      bits.find_first_not_of("01") != std::string::npos)
    throw Error(path + ": a damaged climb checkpoint (delete it to restart this climb)");
  const auto selected = std::count(bits.begin(), bits.end(), '1');
  if (selected != c)
    throw Error(path + ": a checkpoint of a climb with C = " + std::to_string(selected) +
                " nodes, not C = " + std::to_string(c) + " (delete it to restart this climb)");
  s->current.assign(m, 0);
  for (std::size_t j = 0; j < m; ++j) s->current[j] = bits[j] == '1';
  return true;
}

}  // namespace

MossResult mossSelect(Localizer& training, int c, const MossConfig& config) {
  const std::size_t m = training.mapSize();
  checkMapSize(c, m, "MOSS");
  if (config.climbs < 1) throw Error("MOSS: T (hill climbs) must be at least 1");
  if (config.steps < 1) throw Error("MOSS: K (steps per climb) must be at least 1");
  if (!config.checkpoint_dir.empty()) std::filesystem::create_directories(config.checkpoint_dir);

  std::vector<ClimbState> finals(config.climbs);
  std::atomic<std::uint64_t> evaluations{0}, localized{0}, considered{0};
  std::mutex progress_mutex;
  double best_so_far = 1e300;

  const auto climb = [&](int t) {
    ClimbState s;
    const std::string path = config.checkpoint_dir.empty() ? "" : checkpointPath(config, c, t);
    std::unique_ptr<SwapEvaluator> evaluator;
    if (path.empty() || !readState(path, m, c, &s)) {
      std::seed_seq seq{static_cast<std::uint32_t>(config.seed),
                        static_cast<std::uint32_t>(config.seed >> 32),
                        static_cast<std::uint32_t>(c), static_cast<std::uint32_t>(t)};
      s.rng.seed(seq);
      // Line 2: C nodes drawn uniformly.
      std::vector<int> all(m);
      for (std::size_t j = 0; j < m; ++j) all[j] = static_cast<int>(j);
      std::shuffle(all.begin(), all.end(), s.rng);
      s.current.assign(m, 0);
      for (int k = 0; k < c; ++k) s.current[all[k]] = 1;
      if (config.reuse) {
        evaluator = std::make_unique<SwapEvaluator>(training, s.current);
        s.error = evaluator->error();
      } else {
        s.error = training.error(s.current);
      }
      ++evaluations;
      localized += training.trials();
      considered += training.trials();
    } else if (config.reuse && s.step < config.steps) {
      evaluator = std::make_unique<SwapEvaluator>(training, s.current);
    }
    while (s.step < config.steps && static_cast<std::size_t>(c) < m) {
      // Line 4: one node in, one node out.
      const std::vector<int> in = selectedNodes(s.current);
      std::vector<int> out;
      for (std::size_t j = 0; j < m; ++j)
        if (!s.current[j]) out.push_back(static_cast<int>(j));
      const int drop = in[std::uniform_int_distribution<std::size_t>(0, in.size() - 1)(s.rng)];
      const int add = out[std::uniform_int_distribution<std::size_t>(0, out.size() - 1)(s.rng)];
      if (evaluator) {  // lines 5-7
        const std::uint64_t before = evaluator->trialsLocalized();
        if (evaluator->trySwap(drop, add)) {
          s.current = evaluator->current();
          s.error = evaluator->error();
        }
        localized += evaluator->trialsLocalized() - before;
      } else {
        Selection candidate = s.current;
        candidate[drop] = 0;
        candidate[add] = 1;
        const double e = training.error(candidate);  // line 5
        localized += training.trials();
        if (e < s.error) {  // lines 6-7
          s.current = std::move(candidate);
          s.error = e;
        }
      }
      considered += training.trials();
      ++evaluations;
      ++s.step;
      if (!path.empty() && (s.step % config.checkpoint_every == 0 || s.step == config.steps))
        writeState(path, s);
      if (config.progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        best_so_far = std::min(best_so_far, s.error);
        config.progress(t, s.step, s.error, best_so_far);
      }
    }
    if (!path.empty()) writeState(path, s);
    finals[t] = std::move(s);
  };

  if (config.only_climb >= config.climbs)
    throw Error("MOSS: climb " + std::to_string(config.only_climb) +
                " of T = " + std::to_string(config.climbs) + " climbs (0 to T-1)");
  if (config.only_climb >= 0)
    climb(config.only_climb);
  else
    parallelFor(config.threads, config.climbs, climb);

  MossResult r;
  r.evaluations = evaluations;
  r.trials_localized = localized;
  r.trials_considered = considered;
  int best = std::max(0, config.only_climb);
  for (int t = 0; t < config.climbs; ++t) {
    if (config.only_climb >= 0 && t != config.only_climb) continue;
    r.climb_errors.push_back(finals[t].error);
    if (finals[t].error < finals[best].error) best = t;  // line 8
  }
  r.best = finals[best].current;
  r.best_error = finals[best].error;
  return r;
}

}  // namespace hamal::moss
