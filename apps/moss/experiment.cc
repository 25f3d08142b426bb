// Experiment: see experiment.h (thesis sec. 5.5).
#include "apps/moss/experiment.h"

#include <Eigen/LU>
#include <algorithm>
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
#include "core/stopwatch.h"

namespace hamal::moss {

namespace {

// Mean and standard error of the per-trial test RMSEs.
void meanAndError(const std::vector<double>& v, double* se) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= v.size();
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  *se = v.size() > 1 ? std::sqrt(var / (v.size() - 1) / v.size()) : 0.0;
}

std::string informationText(const ExperimentConfig& c, double laser_sigma);

// Per-trial errors as one CSV field: blank-separated, full precision.
std::string joined(const std::vector<double>& v) {
  std::ostringstream os;
  os.precision(9);
  for (std::size_t i = 0; i < v.size(); ++i) os << (i ? " " : "") << v[i];
  return os.str();
}

std::string configText(const ExperimentConfig& c, const TrialConfig& t) {
  std::ostringstream os;
  os << "world " << c.source.world << "\nseed " << c.seed << "\ntrain " << c.train << "\ntest "
     << c.test << "\nclimbs " << c.climbs << "\nsteps " << c.steps << "\nbackend "
     << c.localizer.backend << "\nmap_poses " << t.map_poses << "\nposes " << t.poses
     << "\nsigma_xy " << t.sigma_xy << "\nsigma_theta " << t.sigma_theta << "\nnoise_distance "
     << t.noise_distance << "\nbeams " << t.laser.beams << "\n"
     << informationText(c, t.laser.sigma_range);
  return os.str();
}

// What selects and scores on a log, beside the log's own options.
std::string methodText(const ExperimentConfig& c) {
  std::ostringstream os;
  os << "climbs " << c.climbs << "\nsteps " << c.steps << "\nbackend " << c.localizer.backend
     << "\n"
     << informationText(c, LaserConfig().sigma_range);
  return os.str();
}

std::string informationText(const ExperimentConfig& c, double laser_sigma) {
  std::ostringstream os;
  // Written only when not the default, so folders of Hessian runs still resume.
  if (c.localizer.objective != Objective::kRmse)
    os << "objective " << toString(c.localizer.objective) << "\n";
  if (c.localizer.gate_chi2 > 0) os << "l2g_gate " << c.localizer.gate_chi2 << "\n";
  if (c.matches.calibrate_information) os << "calibrate_information 1\n";
  if (c.matches.matcher.information != ScanMatcherConfig::Information::kHessian)
    os << "information " << toString(c.matches.matcher.information) << "\n";
  if (c.matches.matcher.information == ScanMatcherConfig::Information::kCensi &&
      c.matches.censi_sigma > 0 && c.matches.censi_sigma != laser_sigma)
    os << "censi_sigma " << c.matches.censi_sigma << "\n";
  return os.str();
}

LocalizerConfig localizerConfig(const ExperimentConfig& c, const TrialConfig& t) {
  // The localizer weighs odometry with the noise the trials were made with.
  LocalizerConfig lc = c.localizer;
  lc.sigma_xy = t.sigma_xy;
  lc.sigma_theta = t.sigma_theta;
  lc.noise_distance = t.noise_distance;
  return lc;
}

ScanMatcherConfig matcherConfig(const ExperimentConfig& c, const TrialConfig& t) {
  ScanMatcherConfig matcher = c.matches.matcher;
  matcher.sigma_range = c.matches.censi_sigma > 0 ? c.matches.censi_sigma : t.laser.sigma_range;
  return matcher;
}

MossConfig mossConfig(const ExperimentConfig& c) {
  MossConfig mc;
  mc.climbs = c.climbs;
  mc.steps = c.steps;
  mc.seed = c.seed;
  mc.threads = c.run.threads;
  mc.checkpoint_dir = (std::filesystem::path(c.run.out) / "climbs").string();
  mc.reuse = c.reuse;
  mc.only_climb = c.run.climb;
  return mc;
}

// One climb for every C, into its checkpoints; config.txt verified (or
// written) but rows.csv left to the run that picks the best.
void runClimb(const ExperimentConfig& config, const World& world, const TrialConfig& tc,
              const Registry& registry, std::ostream& log) {
  if (config.run.climb >= config.climbs)
    throw Error("experiment: --climb " + std::to_string(config.run.climb) +
                ": the climbs are 0 to " + std::to_string(config.climbs - 1) + " (T = --climbs " +
                std::to_string(config.climbs) + ")");
  if (std::find(config.methods.begin(), config.methods.end(), "moss") == config.methods.end())
    throw Error("experiment: --climb runs a MOSS climb, and --methods has no moss");
  apps::ResumableResults::verifyConfig(config.run.out, configText(config, tc));
  const Stopwatch t0;
  const PriorMap map = mappingRun(world, tc, config.seed);
  std::vector<Trial> train(config.train);
  parallelFor(config.run.threads, config.train,
              [&](int k) { train[k] = localizationTrial(world, map, tc, config.seed, 0, k); });
  Localizer train_loc(map, train, localizerConfig(config, tc), registry,
                      ScanMatcher(matcherConfig(config, tc)));
  for (int c : config.sizes) {
    const Stopwatch t;
    const MossResult r = mossSelect(train_loc, c, mossConfig(config));
    log << "moss C=" << c << " climb " << config.run.climb << ": train RMSE " << r.best_error
        << " m, " << r.evaluations << " evaluations (" << t.seconds() << " s)" << std::endl;
  }
  log << "done: climb " << config.run.climb << " in " << t0.seconds() << " s" << std::endl;
}

// The accepted L2G matches of `selected` on `trials`, graded against the
// reference: per match its position and heading error, and its chi-square
// e^T I e under the information it carries (for a calibrated information
// chi-square with 3 degrees of freedom: median 2.37). What makes a map worse
// than none is read off it: wrong matches accepted, or right ones weighed
// too strongly.
struct MatchGrades {
  std::vector<double> chi2, errors;
  int tried = 0, wrong = 0;  // wrong: more than 0.3 m off
};
constexpr double kChi2MedianOf3 = 2.366;

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// `rows`, if given, gets a CSV row per accepted match.
MatchGrades gradeMatches(Localizer& localizer, const PriorMap& map,
                         const std::vector<Trial>& trials, const Selection& selected,
                         std::ostream* rows) {
  MatchGrades g;
  if (rows)
    *rows << "trial,pose,node,pairs,rms,error_m,error_deg,chi2,sigma_x,sigma_y,sigma_theta_deg\n";
  for (std::size_t s = 0; s < trials.size(); ++s) {
    const Localization l = localizer.localize(static_cast<int>(s), selected);
    for (std::size_t i = 1; i < l.matches.size(); ++i) {
      if (l.node[i] < 0) continue;
      ++g.tried;
      const ScanMatch& m = l.matches[i];
      if (!m.ok) continue;
      const Pose2 truth = map.poses[l.node[i]].between(trials[s].truth[i]);
      // In the match's frame, as the L2G factor's residual (eq. 2.28-2.31).
      const Point2 d = truth.t() - m.relative.t();
      const double co = std::cos(m.relative.theta), si = std::sin(m.relative.theta);
      const Eigen::Vector2d dt(co * d.x() + si * d.y(), -si * d.x() + co * d.y());
      const Eigen::Vector3d e(dt.x(), dt.y(), wrapAngle(truth.theta - m.relative.theta));
      const double c = e.dot(m.information * e);
      g.chi2.push_back(c);
      g.errors.push_back(dt.norm());
      if (dt.norm() > 0.3) ++g.wrong;
      if (!rows) continue;
      const Eigen::Matrix3d cov = m.information.inverse();
      *rows << s << ',' << i << ',' << l.node[i] << ',' << m.pairs << ',' << m.rms << ','
            << dt.norm() << ',' << e.z() * 180 / M_PI << ',' << c << ',' << std::sqrt(cov(0, 0))
            << ',' << std::sqrt(cov(1, 1)) << ',' << std::sqrt(cov(2, 2)) * 180 / M_PI << '\n';
    }
  }
  return g;
}

std::string describe(const MatchGrades& g) {
  std::ostringstream os;
  os << g.chi2.size() << " of " << g.tried << " matches accepted, " << g.wrong
     << " of them more than 0.3 m off; median error " << median(g.errors)
     << " m, median chi-square " << median(g.chi2) << " (" << kChi2MedianOf3
     << " if the information were calibrated)";
  return os.str();
}

// What an experiment runs on: a synthetic world with its trial settings, or
// a CARMEN log cut into a map (its first visits) and trials; the folder's parameter
// text either way.
struct ExperimentInputs {
  bool real = false;
  World world;
  TrialConfig tc;
  carmen::CarmenLog log;
  CarmenTrials ct;
  std::string name, text;
};

// Reads the world or the log; a C the map cannot hold is refused here,
// before anything is written.
ExperimentInputs experimentInputs(const ExperimentConfig& config) {
  namespace fs = std::filesystem;
  ExperimentInputs in;
  in.real = !config.source.data.empty();
  if (in.real) {
    in.log = carmen::readCarmenLog(config.source.data, config.source.read);
    // Cut before anything is written: a C the map cannot hold leaves no folder.
    in.ct = carmenTrials(in.log, config.source.log);
    for (int c : config.sizes)
      checkMapSize(c, static_cast<int>(in.ct.map.poses.size()), "experiment");
    in.name = fs::path(config.source.data).stem().string();
    // The trials' odometry noise, which the localizer weighs odometry with:
    // drawn, or estimated on the first visits.
    in.tc.sigma_xy = in.ct.noise.sigma_xy;
    in.tc.sigma_theta = in.ct.noise.sigma_theta;
    in.tc.noise_distance = config.source.log.noise_distance;
    in.text = "data " + in.name + "\n" + describe(config.source.log) + methodText(config);
    // How the log was read, when not the default (older folders stay valid).
    const carmen::CarmenReadOptions d;
    if (config.source.read.max_time_reversal != d.max_time_reversal ||
        config.source.read.no_return_range != d.no_return_range ||
        config.source.read.declared_max_range != d.declared_max_range)
      in.text += "max_time_reversal " + std::to_string(config.source.read.max_time_reversal) +
                 "\nno_return_range " + std::to_string(config.source.read.no_return_range) +
                 "\ndeclared_max_range " + std::to_string(config.source.read.declared_max_range) +
                 "\n";
  } else {
    in.world = loadWorld(config.source.world);
    in.name = in.world.name;
    in.tc = scenarioConfig(in.world.name);
    if (config.source.map_poses > 0) in.tc.map_poses = config.source.map_poses;
    if (config.source.poses > 0) in.tc.poses = config.source.poses;
    for (int c : config.sizes) checkMapSize(c, in.tc.map_poses, "experiment");
    in.text = configText(config, in.tc);
  }
  return in;
}

// The prior map and the training and test trials (and, from a log, the map
// nodes' returns), logged with what they are.
struct ExperimentTrials {
  PriorMap map;
  std::vector<Trial> train, test;
  std::vector<Point2> points;
};

ExperimentTrials experimentTrials(const ExperimentConfig& config, ExperimentInputs* in,
                                  std::ostream& log_stream) {
  const Stopwatch t0;
  ExperimentTrials out;
  if (in->real) {
    const CarmenTrials& ct = in->ct;
    out.map = std::move(in->ct.map);
    out.train = std::move(in->ct.train);
    out.test = std::move(in->ct.test);
    out.points = std::move(in->ct.map_points);
    log_stream << in->name << ": " << ct.cut.kept_poses << " poses kept, " << ct.cut.path_length
               << " m; " << ct.cut.revisiting_poses << " revisits, " << ct.cut.first_visit_poses
               << " first visits (" << ct.cut.dropped_nodes
               << " node places dropped next to a revisit of their pass); " << ct.cut.trial_poses
               << " revisits near a map node; training until t = " << ct.times.train_until
               << " s, test from t = " << ct.times.test_from << " s; odometry "
               << toString(config.source.log.odometry) << ", sigma_xy " << ct.noise.sigma_xy
               << " m and sigma_theta " << ct.noise.sigma_theta * 180 / M_PI << " deg per "
               << config.source.log.noise_distance << " m"
               << (ct.noise.odometry_steps
                       ? " (estimated on " + std::to_string(ct.noise.odometry_steps) +
                             " first-visit steps)"
                       : std::string(" (drawn)"))
               << std::endl;
  } else {
    try {
      out.map = mappingRun(in->world, in->tc, config.seed);
    } catch (const Error& e) {
      throw Error("--world " + config.source.world + ": " + e.what());
    }
    // Each trial is a function of (seed, stream, index): built on all threads.
    out.train.resize(config.train);
    out.test.resize(config.test);
    parallelFor(config.run.threads, config.train + config.test, [&](int k) {
      if (k < config.train)
        out.train[k] = localizationTrial(in->world, out.map, in->tc, config.seed, 0, k);
      else
        out.test[k - config.train] =
            localizationTrial(in->world, out.map, in->tc, config.seed, 1, k - config.train);
    });
  }
  log_stream << in->name << ": map of " << out.map.poses.size() << " nodes, " << out.train.size()
             << " training and " << out.test.size() << " test trials of "
             << (in->real ? config.source.log.trial_poses : in->tc.poses) << " poses, built in "
             << t0.seconds() << " s" << std::endl;
  return out;
}

// map.csv, walls.csv, points.csv (from a log) and test_trials.csv: what the
// plots draw the selections on.
void writeExperimentInputs(const std::string& out, const ExperimentInputs& in,
                           const ExperimentTrials& trials) {
  namespace fs = std::filesystem;
  const PriorMap& map = trials.map;
  writeOutputFile((fs::path(out) / "map.csv").string(), [&](std::ostream& m) {
    m << "node,x,y,theta\n";
    for (std::size_t j = 0; j < map.poses.size(); ++j)
      m << j << ',' << map.poses[j].x << ',' << map.poses[j].y << ',' << map.poses[j].theta << '\n';
  });
  writeOutputFile((fs::path(out) / "walls.csv").string(), [&](std::ostream& w) {
    w << "x1,y1,x2,y2\n";
    for (const Segment& s : in.world.walls)
      w << s.a.x() << ',' << s.a.y() << ',' << s.b.x() << ',' << s.b.y() << '\n';
  });
  if (in.real)
    writeOutputFile((fs::path(out) / "points.csv").string(), [&](std::ostream& p) {
      p << "x,y\n";
      for (const Point2& q : trials.points) p << q.x() << ',' << q.y() << '\n';
    });
  const std::vector<Trial>& test = trials.test;
  writeOutputFile((fs::path(out) / "test_trials.csv").string(), [&](std::ostream& tr) {
    tr << "trial,pose,x,y,theta\n";
    for (std::size_t s = 0; s < test.size(); ++s)
      for (std::size_t i = 0; i < test[s].truth.size(); ++i)
        tr << s << ',' << i << ',' << test[s].truth[i].x << ',' << test[s].truth[i].y << ','
           << test[s].truth[i].theta << '\n';
  });
}

// The scan matcher's settings; with calibrate_information, its sigmas grown
// on the training trials only: the full map's matches graded against the
// reference give the factor by which their information is too confident;
// the sigma it assumes grows by its square root (either information scales
// with 1 / sigma^2).
ScanMatcherConfig experimentMatcher(const ExperimentConfig& config, const TrialConfig& tc,
                                    const PriorMap& map, const std::vector<Trial>& train,
                                    const LocalizerConfig& lc, const Registry& registry,
                                    std::ostream& log_stream) {
  ScanMatcherConfig matcher = matcherConfig(config, tc);
  if (!config.matches.calibrate_information) return matcher;
  Localizer probe(map, train, lc, registry, ScanMatcher(matcher));
  const MatchGrades g = gradeMatches(probe, map, train, Selection(map.poses.size(), 1), nullptr);
  const double scale = std::max(1.0, median(g.chi2) / kChi2MedianOf3);
  matcher.sigma *= std::sqrt(scale);
  matcher.sigma_range *= std::sqrt(scale);
  log_stream << "information calibrated on the training trials (full map: " << describe(g)
             << "): divided by " << scale << ", sigma " << matcher.sigma << " m" << std::endl;
  return matcher;
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

void runExperiment(const ExperimentConfig& config, const Registry& registry,
                   std::ostream& log_stream) {
  if (config.run.out.empty()) throw Error("experiment: --output is required");
  if (config.train < 1 || config.test < 1)
    throw Error("experiment: --train and --test must be at least 1");
  if (config.climbs < 1) throw Error("experiment: T (--climbs) must be at least 1");
  if (config.steps < 1) throw Error("experiment: K (--steps) must be at least 1");
  if (!(config.matches.censi_sigma >= 0) || !std::isfinite(config.matches.censi_sigma))
    throw Error("experiment: --censi_sigma must be a positive number of metres (0: the laser's)");
  namespace fs = std::filesystem;
  ExperimentInputs in = experimentInputs(config);
  const bool real = in.real;
  const std::string& name = in.name;
  for (const std::string& m : config.methods)
    if (m != "equidistant" && m != "ssm" && m != "moss")
      throw Error("experiment: unknown method '" + m + "' (equidistant, ssm, moss)");

  if (config.run.climb >= 0) {
    if (real) throw Error("experiment: --climb is not available with --data");
    runClimb(config, in.world, in.tc, registry, log_stream);
    return;
  }
  // Verified before any work: the parameters match, every row is whole.
  apps::ResumableResults results(config.run.out, in.text,
                                 "world,method,C,M,train_rmse,test_rmse,test_rmse_se,seconds,"
                                 "evaluations,ms_per_evaluation,cache_hits,cache_misses,nodes,"
                                 "trials_localized_fraction,train_mean_error,test_mean_error,"
                                 "test_mean_error_se,test_trial_rmse,test_trial_mean_error");
  if (config.run.verify_only) {
    log_stream << config.run.out << ": verified, " << results.rows().size() << " rows" << std::endl;
    return;
  }
  if (results.droppedTornRow())
    log_stream << results.rowsPath() << ": dropped a torn last row; its unit runs again"
               << std::endl;
  std::set<std::pair<std::string, int>> done;
  for (const apps::ResultRow& row : results.rows())
    done.insert({row.fields[1], static_cast<int>(results.integer(row, 2))});

  const ExperimentTrials trials = experimentTrials(config, &in, log_stream);
  const PriorMap& map = trials.map;
  const std::vector<Trial>& test = trials.test;
  writeExperimentInputs(config.run.out, in, trials);

  const LocalizerConfig lc = localizerConfig(config, in.tc);
  const ScanMatcherConfig matcher =
      experimentMatcher(config, in.tc, map, trials.train, lc, registry, log_stream);
  Localizer train_loc(map, trials.train, lc, registry, ScanMatcher(matcher));
  Localizer test_loc(map, test, lc, registry, ScanMatcher(matcher));

  const std::size_t m = map.poses.size();
  const auto write = [&](const std::string& method, int c, const Selection& a, double seconds_used,
                         std::uint64_t evaluations, double localized_fraction) {
    // Both errors are reported whichever one MOSS minimised.
    std::vector<double> per_trial, per_trial_norm;
    const double train_rmse = train_loc.rmse(a);
    const double test_rmse = test_loc.rmse(a, &per_trial);
    const double train_mean = train_loc.meanError(a);
    const double test_mean = test_loc.meanError(a, &per_trial_norm);
    double se, se_norm;
    meanAndError(per_trial, &se);
    meanAndError(per_trial_norm, &se_norm);
    std::ostringstream nodes;
    for (int j : selectedNodes(a)) nodes << (nodes.tellp() ? " " : "") << j;
    std::ostringstream row;
    row << name << ',' << method << ',' << c << ',' << m << ',' << train_rmse << ',' << test_rmse
        << ',' << se << ',' << seconds_used << ',' << evaluations << ','
        << (evaluations ? 1000.0 * seconds_used / evaluations : 0.0) << ','
        << train_loc.cache().hits() << ',' << train_loc.cache().misses() << ',' << nodes.str()
        << ',' << localized_fraction << ',' << train_mean << ',' << test_mean << ',' << se_norm
        << ',' << joined(per_trial) << ',' << joined(per_trial_norm);
    results.append(row.str());
    log_stream << method << " C=" << c << ": train RMSE " << train_rmse << " m, test RMSE "
               << test_rmse << " m (" << seconds_used << " s)" << std::endl;
  };

  if (!done.count({"full", static_cast<int>(m)})) {
    const Stopwatch t;
    write("full", static_cast<int>(m), Selection(m, 1), t.seconds(), 0, 0.0);
  }
  // No map at all (C = 0): odometry alone, what any map has to beat.
  if (!done.count({"none", 0})) {
    const Stopwatch t;
    write("none", 0, Selection(m, 0), t.seconds(), 0, 0.0);
  }
  if (real) {
    const std::string path = (fs::path(config.run.out) / "matches_full_test.csv").string();
    MatchGrades g;
    writeOutputFile(path, [&](std::ostream& os) {
      g = gradeMatches(test_loc, map, test, Selection(m, 1), &os);
    });
    log_stream << "full map, test trials: " << describe(g) << " -> " << path << std::endl;
  }
  std::unique_ptr<SparseScanMatching> ssm;
  for (int c : config.sizes) {
    for (const std::string& method : config.methods) {
      if (done.count({method, c})) continue;
      const Stopwatch t;
      if (method == "equidistant") {
        write(method, c, equidistant(m, c), t.seconds(), 0, 0.0);
      } else if (method == "ssm") {
        if (!ssm) ssm = std::make_unique<SparseScanMatching>(map);
        write(method, c, ssm->select(c), t.seconds(), 0, 0.0);
      } else {
        MossConfig mc = mossConfig(config);
        const std::uint64_t total = static_cast<std::uint64_t>(config.climbs) * config.steps;
        std::uint64_t seen = 0;
        Stopwatch last;
        mc.progress = [&](int, int, double, double best) {
          ++seen;
          if (last.seconds() < 10.0) return;
          last.restart();
          log_stream << "  moss C=" << c << ": " << seen << "/" << total << " steps this run, best "
                     << best << " m, " << 1000.0 * t.seconds() / seen << " ms per evaluation, "
                     << train_loc.localizations() << " trial localizations, cache "
                     << train_loc.cache().hits() << " hits / " << train_loc.cache().misses()
                     << " matches, "
                     << static_cast<int>(100.0 * train_loc.matchSeconds() /
                                         std::max(1e-9, train_loc.localizeSeconds()))
                     << "% of localization time in scan matching" << std::endl;
        };
        const MossResult r = mossSelect(train_loc, c, mc);
        write(method, c, r.best, t.seconds(), r.evaluations,
              r.trials_considered ? static_cast<double>(r.trials_localized) / r.trials_considered
                                  : 0.0);
      }
    }
  }
  log_stream << "done: " << results.rowsPath() << std::endl;
}

}  // namespace hamal::moss
