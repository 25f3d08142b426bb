// hamal_log: what a CARMEN log holds (carmen_log.h), and its scans' point
// cloud and reference trajectory as CSV for plotting, the first look at a
// real recording before FLAG (thesis ch. 4) or MOSS (ch. 5) run on it.
#include <gflags/gflags.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <set>

#include "apps/carmen/carmen_log.h"
#include "apps/carmen/carmen_log_flags.h"
#include "apps/common/cli.h"
#include "core/error.h"
#include "core/output_file.h"

DEFINE_string(data, "", "the CARMEN log (plain or gzip)");
DEFINE_string(output, "",
              "prefix of what is written: <prefix>_points.csv (every return, world frame, from "
              "the logged poses) and <prefix>_trajectory.csv (the scans' poses); empty: summary "
              "only");
// The reader's flags (--max_time_reversal, --no_return_range,
// --declared_max_range) are carmen_log_flags.h's; --max_range is the old
// spelling of --no_return_range here.
HAMAL_FLAG_ALIAS(max_range, no_return_range);

namespace hamal::carmen {
namespace {

const char kUsage[] =
    "summary of a CARMEN log; its point cloud and reference trajectory as CSV.\n\n"
    "  hamal_log --data ../shared/data/carmen/intel.log --output intel";

constexpr double kDeg = 180 / 3.14159265358979323846;

// Through OutputFile (core/output_file.h): a failure leaves nothing half
// written.
template <typename Body>
void writeCsv(const std::string& path, Body body) {
  writeOutputFile(path, [&](std::ostream& out) {
    out << std::setprecision(9);
    body(out);
  });
}

int run(const std::vector<std::string>& positional) {
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_data.empty()) throw Error("no log: give --data FILE (see --help)");
  const std::string points_path = FLAGS_output + "_points.csv";
  const std::string trajectory_path = FLAGS_output + "_trajectory.csv";
  if (!FLAGS_output.empty()) {
    apps::checkOutputPaths({{"output", points_path}, {"output", trajectory_path}},
                           {{"data", FLAGS_data}});
  }
  const CarmenLog log = readCarmenLog(FLAGS_data, readOptionsFromFlags());

  std::cout << "log: " << log.file << "\nrecords:";
  for (const auto& [tag, n] : log.records) std::cout << ' ' << tag << ' ' << n;
  std::cout << "\n";
  if (log.odometry_echoes)
    std::cout << "  ODOM repeating the pose of the scan before it (left out): "
              << log.odometry_echoes << "\n";
  std::cout << "skipped:";
  if (log.skipped.empty()) std::cout << " none";
  for (const auto& [tag, n] : log.skipped) std::cout << ' ' << tag << ' ' << n;
  std::cout << "\n";
  std::set<std::string> tags;
  for (const LaserScan& s : log.scans) tags.insert(s.tag);
  std::cout << "lasers: " << tags.size() << "\n";
  for (const std::string& tag : tags) {
    const auto scans = log.scansOf(tag);
    std::size_t lo = scans[0]->ranges.size(), hi = lo, beams = 0, no_return = 0;
    double range_max = 0, path = 0;
    for (std::size_t k = 0; k < scans.size(); ++k) {
      const LaserScan& s = *scans[k];
      lo = std::min(lo, s.ranges.size());
      hi = std::max(hi, s.ranges.size());
      for (std::size_t i = 0; i < s.ranges.size(); ++i) {
        ++beams;
        if (!s.hit(i))
          ++no_return;
        else
          range_max = std::max(range_max, s.ranges[i]);
      }
      if (k) path += std::hypot(s.pose.x - scans[k - 1]->pose.x, s.pose.y - scans[k - 1]->pose.y);
    }
    const LaserScan& first = *scans.front();
    std::cout << "  " << tag << ": " << scans.size() << " scans, " << lo;
    if (hi != lo) std::cout << "-" << hi;
    std::cout << " beams from " << first.start_angle * kDeg << " deg every "
              << first.angular_step * kDeg << " deg, no return at " << first.max_range << " m ("
              << no_return << " of " << beams << " beams), farthest return " << range_max << " m\n";
    if (log.no_return.count(tag)) std::cout << "  no return: " << log.no_return.at(tag) << "\n";
    std::cout << "  duration " << scans.back()->timestamp - first.timestamp << " s ("
              << first.timestamp << " to " << scans.back()->timestamp << "), reference path "
              << path << " m\n";
  }
  std::cout << "odometry records: " << log.odometry.size() << "\n";
  std::cout << "time steps back within the tolerance: " << log.time_reversals;
  if (log.time_reversals) std::cout << " (largest " << log.largest_time_reversal << " s)";
  std::cout << "\n";
  if (FLAGS_output.empty()) return 0;
  std::size_t written = 0;
  writeCsv(points_path, [&](std::ostream& out) {
    out << "scan,x,y\n";
    for (std::size_t k = 0; k < log.scans.size(); ++k)
      for (const Point2& p : log.scans[k].points(log.scans[k].pose)) {
        out << k << ',' << p.x() << ',' << p.y() << '\n';
        ++written;
      }
  });
  writeCsv(trajectory_path, [&](std::ostream& out) {
    out << "scan,tag,timestamp,x,y,theta\n";
    for (std::size_t k = 0; k < log.scans.size(); ++k) {
      const LaserScan& s = log.scans[k];
      out << k << ',' << s.tag << ',' << s.timestamp << ',' << s.pose.x << ',' << s.pose.y << ','
          << s.pose.theta << '\n';
    }
  });
  std::cout << "wrote " << points_path << " (" << written << " points), " << trajectory_path << " ("
            << log.scans.size() << " poses)\n";
  return 0;
}

}  // namespace
}  // namespace hamal::carmen

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_log", [&] {
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::carmen::kUsage);
    return hamal::carmen::run(positional);
  });
}
