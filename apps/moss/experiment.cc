// Experiment: see experiment.h (thesis sec. 5.5).
#include "apps/moss/experiment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "apps/common/resumable_results.h"
#include "apps/moss/equidistant.h"
#include "apps/moss/parallel_for.h"
#include "apps/moss/sparse_scan_matching.h"
#include "core/error.h"
#include "core/output_file.h"

namespace hamal::moss {

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Mean and standard error of the per-trial test RMSEs.
void meanAndError(const std::vector<double>& v, double* se) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= v.size();
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  *se = v.size() > 1 ? std::sqrt(var / (v.size() - 1) / v.size()) : 0.0;
}

std::string configText(const ExperimentConfig& c, const TrialConfig& t) {
  std::ostringstream os;
  os << "world " << c.world << "\nseed " << c.seed << "\ntrain " << c.train << "\ntest " << c.test
     << "\nclimbs " << c.climbs << "\nsteps " << c.steps << "\nbackend " << c.localizer.backend
     << "\nmap_poses " << t.map_poses << "\nposes " << t.poses << "\nsigma_xy " << t.sigma_xy
     << "\nsigma_theta " << t.sigma_theta << "\nnoise_distance " << t.noise_distance << "\nbeams "
     << t.laser.beams << "\n";
  // Written only when not the default, so folders of Hessian runs still resume.
  if (c.matcher.information != ScanMatcherConfig::Information::kHessian)
    os << "information " << toString(c.matcher.information) << "\n";
  if (c.matcher.information == ScanMatcherConfig::Information::kCensi && c.censi_sigma > 0 &&
      c.censi_sigma != t.laser.sigma_range)
    os << "censi_sigma " << c.censi_sigma << "\n";
  return os.str();
}

}  // namespace

std::vector<int> parseSizes(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  for (std::string piece; std::getline(ss, piece, ',');) {
    if (piece.empty()) continue;
    const std::size_t dash = piece.find('-', 1);
    try {
      std::size_t used = 0;
      if (dash == std::string::npos) {
        out.push_back(std::stoi(piece, &used));
        if (used != piece.size()) throw std::invalid_argument(piece);
      } else {
        const int a = std::stoi(piece.substr(0, dash)), b = std::stoi(piece.substr(dash + 1));
        if (b < a) throw std::invalid_argument(piece);
        for (int c = a; c <= b; ++c) out.push_back(c);
      }
    } catch (const std::exception&) {
      throw Error("--sizes: '" + piece + "' is not a number or a range a-b");
    }
  }
  if (out.empty()) throw Error("--sizes: no C value given");
  for (int c : out)
    if (c < 1) throw Error("--sizes: C = " + std::to_string(c) + ": a map keeps at least 1 node");
  return out;
}

void runExperiment(const ExperimentConfig& config, const Registry& registry, std::ostream& log) {
  if (config.out.empty()) throw Error("experiment: --out is required");
  if (config.train < 1 || config.test < 1)
    throw Error("experiment: --train and --test must be at least 1");
  if (config.climbs < 1) throw Error("experiment: T (--climbs) must be at least 1");
  if (config.steps < 1) throw Error("experiment: K (--steps) must be at least 1");
  if (!(config.censi_sigma >= 0) || !std::isfinite(config.censi_sigma))
    throw Error("experiment: --censi_sigma must be a positive number of metres (0: the laser's)");
  const World world = loadWorld(config.world);
  TrialConfig tc = scenarioConfig(world.name);
  if (config.map_poses > 0) tc.map_poses = config.map_poses;
  if (config.poses > 0) tc.poses = config.poses;
  for (int c : config.sizes) checkMapSize(c, tc.map_poses, "experiment");
  for (const std::string& m : config.methods)
    if (m != "equidistant" && m != "ssm" && m != "moss")
      throw Error("experiment: unknown method '" + m + "' (equidistant, ssm, moss)");

  namespace fs = std::filesystem;
  // Verified before any work: the parameters match, every row is whole.
  apps::ResumableResults results(config.out, configText(config, tc),
                                 "world,method,C,M,train_rmse,test_rmse,test_rmse_se,seconds,"
                                 "evaluations,ms_per_evaluation,cache_hits,cache_misses,nodes,"
                                 "trials_localized_fraction");
  if (results.droppedTornRow())
    log << results.rowsPath() << ": dropped a torn last row; its unit runs again" << std::endl;
  std::set<std::pair<std::string, int>> done;
  for (const apps::ResultRow& row : results.rows())
    done.insert({row.fields[1], static_cast<int>(results.integer(row, 2))});

  const auto t0 = Clock::now();
  const PriorMap map = [&] {
    try {
      return mappingRun(world, tc, config.seed);
    } catch (const Error& e) {
      throw Error("--world " + config.world + ": " + e.what());
    }
  }();
  // Each trial is a function of (seed, stream, index): built on all threads.
  std::vector<Trial> train(config.train), test(config.test);
  parallelFor(config.threads, config.train + config.test, [&](int k) {
    if (k < config.train)
      train[k] = localizationTrial(world, map, tc, config.seed, 0, k);
    else
      test[k - config.train] = localizationTrial(world, map, tc, config.seed, 1, k - config.train);
  });
  log << world.name << ": map of " << map.poses.size() << " nodes, " << train.size()
      << " training and " << test.size() << " test trials of " << tc.poses << " poses, built in "
      << seconds(t0) << " s" << std::endl;
  writeOutputFile((fs::path(config.out) / "map.csv").string(), [&](std::ostream& m) {
    m << "node,x,y,theta\n";
    for (std::size_t j = 0; j < map.poses.size(); ++j)
      m << j << ',' << map.poses[j].x << ',' << map.poses[j].y << ',' << map.poses[j].theta << '\n';
  });
  writeOutputFile((fs::path(config.out) / "walls.csv").string(), [&](std::ostream& w) {
    w << "x1,y1,x2,y2\n";
    for (const Segment& s : world.walls)
      w << s.a.x() << ',' << s.a.y() << ',' << s.b.x() << ',' << s.b.y() << '\n';
  });
  writeOutputFile((fs::path(config.out) / "test_trials.csv").string(), [&](std::ostream& tr) {
    tr << "trial,pose,x,y,theta\n";
    for (std::size_t s = 0; s < test.size(); ++s)
      for (std::size_t i = 0; i < test[s].truth.size(); ++i)
        tr << s << ',' << i << ',' << test[s].truth[i].x << ',' << test[s].truth[i].y << ','
           << test[s].truth[i].theta << '\n';
  });

  // The localizer weighs odometry with the noise the trials were made with.
  LocalizerConfig lc = config.localizer;
  lc.sigma_xy = tc.sigma_xy;
  lc.sigma_theta = tc.sigma_theta;
  lc.noise_distance = tc.noise_distance;
  ScanMatcherConfig matcher = config.matcher;
  matcher.sigma_range = config.censi_sigma > 0 ? config.censi_sigma : tc.laser.sigma_range;
  Localizer train_loc(map, train, lc, registry, ScanMatcher(matcher));
  Localizer test_loc(map, test, lc, registry, ScanMatcher(matcher));

  const std::size_t m = map.poses.size();
  const auto write = [&](const std::string& method, int c, const Selection& a, double seconds_used,
                         std::uint64_t evaluations, double localized_fraction) {
    std::vector<double> per_trial;
    const double train_rmse = train_loc.rmse(a);
    const double test_rmse = test_loc.rmse(a, &per_trial);
    double se;
    meanAndError(per_trial, &se);
    std::ostringstream nodes;
    for (int j : selectedNodes(a)) nodes << (nodes.tellp() ? " " : "") << j;
    std::ostringstream row;
    row << world.name << ',' << method << ',' << c << ',' << m << ',' << train_rmse << ','
        << test_rmse << ',' << se << ',' << seconds_used << ',' << evaluations << ','
        << (evaluations ? 1000.0 * seconds_used / evaluations : 0.0) << ','
        << train_loc.cache().hits() << ',' << train_loc.cache().misses() << ',' << nodes.str()
        << ',' << localized_fraction;
    results.append(row.str());
    log << method << " C=" << c << ": train RMSE " << train_rmse << " m, test RMSE " << test_rmse
        << " m (" << seconds_used << " s)" << std::endl;
  };

  if (!done.count({"full", static_cast<int>(m)})) {
    const auto t = Clock::now();
    write("full", static_cast<int>(m), Selection(m, 1), seconds(t), 0, 0.0);
  }
  std::unique_ptr<SparseScanMatching> ssm;
  for (int c : config.sizes) {
    for (const std::string& method : config.methods) {
      if (done.count({method, c})) continue;
      const auto t = Clock::now();
      if (method == "equidistant") {
        write(method, c, equidistant(m, c), seconds(t), 0, 0.0);
      } else if (method == "ssm") {
        if (!ssm) ssm = std::make_unique<SparseScanMatching>(map);
        write(method, c, ssm->select(c), seconds(t), 0, 0.0);
      } else {
        MossConfig mc;
        mc.climbs = config.climbs;
        mc.steps = config.steps;
        mc.seed = config.seed;
        mc.threads = config.threads;
        mc.checkpoint_dir = (fs::path(config.out) / "climbs").string();
        mc.reuse = config.reuse;
        const std::uint64_t total = static_cast<std::uint64_t>(config.climbs) * config.steps;
        std::uint64_t seen = 0;
        auto last = Clock::now();
        mc.progress = [&](int, int, double, double best) {
          ++seen;
          if (std::chrono::duration<double>(Clock::now() - last).count() < 10.0) return;
          last = Clock::now();
          log << "  moss C=" << c << ": " << seen << "/" << total << " steps this run, best "
              << best << " m, " << 1000.0 * seconds(t) / seen << " ms per evaluation, "
              << train_loc.localizations() << " trial localizations, cache "
              << train_loc.cache().hits() << " hits / " << train_loc.cache().misses()
              << " matches, "
              << static_cast<int>(100.0 * train_loc.matchSeconds() /
                                  std::max(1e-9, train_loc.localizeSeconds()))
              << "% of localization time in scan matching" << std::endl;
        };
        const MossResult r = mossSelect(train_loc, c, mc);
        write(method, c, r.best, seconds(t), r.evaluations,
              r.trials_considered ? static_cast<double>(r.trials_localized) / r.trials_considered
                                  : 0.0);
      }
    }
  }
  log << "done: " << results.rowsPath() << std::endl;
}

}  // namespace hamal::moss
