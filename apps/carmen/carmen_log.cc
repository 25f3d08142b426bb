// Reading CARMEN logs (carmen_log.h): one pass over the text with a
// tokenizer that does not allocate per field, so the 9.5 MB Freiburg log
// reads in well under a second.
#include "apps/carmen/carmen_log.h"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <sstream>
#include <string_view>

#include "core/error.h"
#include "core/line_tokens.h"

namespace hamal::carmen {
namespace {

constexpr double kPi = 3.14159265358979323846;
// An inferred no-return range sits this share below the range that many
// beams reach, so that a "no return" jittering just below the scanner's
// maximum is read as no return too.
constexpr double kNoReturnBand = 0.005;
// Longer than any CARMEN record (a 1081-beam ROBOTLASER1 is about 10 kB).
constexpr std::size_t kMaxLineBytes = std::size_t(1) << 24;

// "what V beyond L unit": a value past one of the bounds of carmen_log.h.
std::string beyond(const std::string& what, double v, double limit, const char* unit) {
  std::ostringstream m;
  m << what << " " << v << " is beyond " << limit << " " << unit
    << " (the bound of a CARMEN log's values)";
  return m.str();
}

// One line's fields, read in order, failing with "file:line: reason".
class Fields {
 public:
  Fields(const std::string& file, int line, std::string_view text) : file_(file), line_(line) {
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r')) ++i;
      const std::size_t start = i;
      while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r') ++i;
      if (i > start) tokens_.push_back(text.substr(start, i - start));
    }
  }
  bool empty() const { return tokens_.empty(); }
  std::string_view tag() const { return tokens_[0]; }
  std::size_t size() const { return tokens_.size(); }
  std::size_t remaining() const { return tokens_.size() - pos_; }

  [[noreturn]] void fail(const std::string& reason) const {
    throw Error(file_ + ":" + std::to_string(line_) + ": " + reason);
  }
  std::string_view next(const char* what) {
    if (pos_ >= tokens_.size())
      fail("truncated " + std::string(tag()) + " record: no " + what + " (" +
           std::to_string(tokens_.size() - 1) + " fields)");
    return tokens_[pos_++];
  }
  // A finite number.
  double number(const char* what) {
    const std::string_view t = next(what);
    double v = 0;
    const char* first = t.data();
    if (!t.empty() && t[0] == '+') ++first;
    const auto r = std::from_chars(first, t.data() + t.size(), v);
    if (r.ec == std::errc::result_out_of_range)
      v = HUGE_VAL;  // caught as non-finite below
    else if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail(std::string(what) + " is not a number: " + quoted(std::string(t)));
    if (!std::isfinite(v)) fail("non-finite " + std::string(what) + ": " + quoted(std::string(t)));
    return v;
  }
  std::size_t count(const char* what, std::size_t limit) {
    const std::string_view t = next(what);
    std::size_t v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail(std::string(what) + " is not a count: " + quoted(std::string(t)));
    if (v > limit) fail(std::string(what) + " " + std::to_string(v) + " exceeds the line's fields");
    return v;
  }
  // A finite number of magnitude at most `limit` (in `unit`).
  double bounded(const char* what, double limit, const char* unit) {
    const double v = number(what);
    if (std::abs(v) > limit) fail(beyond(what, v, limit, unit));
    return v;
  }
  Pose2 pose(const char* what) {
    const std::string w(what);
    const double x = bounded((w + " x").c_str(), kMaxPose, "m");
    const double y = bounded((w + " y").c_str(), kMaxPose, "m");
    const double theta = bounded((w + " theta").c_str(), kMaxPose, "rad");
    return {x, y, theta};
  }
  void expectEnd() const {
    if (pos_ != tokens_.size())
      fail(std::to_string(tokens_.size() - pos_) + " fields too many at the end of the " +
           std::string(tag()) + " record");
  }

 private:
  const std::string& file_;
  int line_;
  std::vector<std::string_view> tokens_;
  std::size_t pos_ = 1;
};

// The ranges of a record whose count says n: exactly n numbers must follow
// before the `trailer` fields, so a short line is "truncated" and a count
// that disagrees with the line says both numbers.
std::vector<double> readRanges(Fields& f, std::size_t trailer, const char* what) {
  const std::size_t n = f.count("range count", f.size());
  if (f.remaining() != n + trailer) {
    std::ostringstream m;
    if (f.remaining() < n + trailer) m << "truncated " << f.tag() << " record: ";
    m << "it declares " << n << " ranges, so " << n + trailer
      << " fields must follow the count (the ranges, pose, odometry, timestamp, host, logger "
         "timestamp), but "
      << f.remaining() << " do";
    f.fail(m.str());
  }
  std::vector<double> ranges(n);
  for (std::size_t i = 0; i < n; ++i) {
    ranges[i] = f.number(what);
    if (ranges[i] < 0)
      f.fail("negative range " + std::to_string(ranges[i]) + " (beam " + std::to_string(i) + ")");
    if (ranges[i] > kMaxRange)
      f.fail(beyond("range", ranges[i], kMaxRange, "m") + " (beam " + std::to_string(i) + ")");
  }
  return ranges;
}

// The timestamp, host and logger timestamp that end every record.
double readTrailer(Fields& f) {
  const double t = f.number("timestamp");
  f.next("host");
  f.number("logger timestamp");
  return t;
}

std::string readFile(const std::string& path) {
  gzFile in = gzopen(path.c_str(), "rb");
  if (!in) throw Error(path + ": cannot open the log");
  std::string text;
  char buffer[1 << 16];
  std::size_t line_start = 0, lines = 1;  // of the line being read
  for (;;) {
    const int got = gzread(in, buffer, sizeof buffer);
    if (got < 0) {
      int code = 0;
      const std::string why = gzerror(in, &code);
      gzclose(in);
      throw Error(path + ": cannot read the log (" + why + ")");
    }
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    // A line without end (/dev/zero, a binary file) is refused before it fills the memory.
    for (std::size_t i = text.size() - std::size_t(got); i < text.size(); ++i)
      if (text[i] == '\n') {
        line_start = i + 1;
        ++lines;
      }
    if (text.size() - line_start > kMaxLineBytes) {
      gzclose(in);
      throw Error(path + ":" + std::to_string(lines) + ": a line longer than " +
                  std::to_string(kMaxLineBytes >> 20) + " MB (not a CARMEN log?)");
    }
  }
  // zlib hands out what it could inflate and notes a stream cut short (a
  // log copied while it was written, a partial download) as Z_BUF_ERROR;
  // cut at a line boundary, what came out would read as a whole log.
  int code = Z_OK;
  std::string why = gzerror(in, &code);
  if (why.rfind(path + ": ", 0) == 0) why.erase(0, path.size() + 2);  // zlib names the file too
  const bool ended = gzeof(in);
  gzclose(in);
  if (code == Z_BUF_ERROR)
    throw Error(path + ": the gzip stream is cut short (" + why +
                "): a truncated file, not a whole log");
  if (code != Z_OK) throw Error(path + ": cannot read the log (" + why + ")");
  if (!ended) throw Error(path + ": cannot read the log to its end");
  return text;
}

// Time order per stream: a record may fall behind the latest by at most the tolerance.
struct Clock {
  double latest = -HUGE_VAL;
  int latest_line = 0;
};

// One pass over a log's text: the records read so far and what reading
// the next needs (each stream's clock, where each PARAM was last set).
class LogReader {
 public:
  LogReader(const std::string& name, const CarmenReadOptions& options)
      : name_(name), options_(options) {
    log_.file = name;
  }

  void readLines(const std::string& text);
  void requireLaser() const;
  void mountFrontAndRearLasers();
  CarmenLog take() { return std::move(log_); }

 private:
  void checkTime(Fields& f, const std::string& stream, double t, int line);
  void readFrontOrRearLaser(Fields& f, std::string_view tag, int line);
  void readRobotLaser(Fields& f, int line);
  // A laser record's common end: its timestamps, nothing after them, time
  // in order; then the scan is kept.
  void keepScan(Fields& f, LaserScan s, int line);
  void readOdometryRecord(Fields& f, int line);
  void readParam(Fields& f, int line);
  bool numericParam(const std::string& key, double lo, double hi, const char* unit, double* out);
  std::string noReturnRange(const std::vector<LaserScan*>& scans, bool is_front, double* no_return);

  const std::string& name_;
  const CarmenReadOptions& options_;
  CarmenLog log_;
  std::map<std::string, Clock> clocks_;
  std::map<std::string, int> param_lines_;  // where each PARAM was last set
  bool last_was_scan_ = false;
};

void LogReader::checkTime(Fields& f, const std::string& stream, double t, int line) {
  Clock& c = clocks_[stream];
  if (t < c.latest) {
    const double back = c.latest - t;
    if (back > options_.max_time_reversal) {
      std::ostringstream m;
      m << "time goes backwards: " << stream << " at " << t << " s after " << c.latest
        << " s on line " << c.latest_line << " (" << back << " s back; tolerance "
        << options_.max_time_reversal << " s, max_time_reversal)";
      f.fail(m.str());
    }
    ++log_.time_reversals;
    log_.largest_time_reversal = std::max(log_.largest_time_reversal, back);
    return;
  }
  c.latest = t;
  c.latest_line = line;
}

void LogReader::readLines(const std::string& text) {
  std::size_t pos = 0;
  int line = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view view(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    if (view.empty() || view[0] == '#') continue;
    Fields f(name_, line, view);
    if (f.empty()) continue;
    const std::string_view tag = f.tag();
    if (tag == "FLASER" || tag == "RLASER") {
      readFrontOrRearLaser(f, tag, line);
    } else if (tag == "ROBOTLASER1") {
      readRobotLaser(f, line);
    } else if (tag == "ODOM") {
      readOdometryRecord(f, line);
    } else if (tag == "PARAM") {
      readParam(f, line);
    } else {
      ++log_.skipped[std::string(tag)];
      continue;
    }
    ++log_.records[std::string(tag)];
  }
}

void LogReader::readFrontOrRearLaser(Fields& f, std::string_view tag, int line) {
  LaserScan s;
  s.tag = std::string(tag);
  s.line = line;
  s.ranges = readRanges(f, 9, "range");
  s.start_angle = -kPi / 2;
  s.angular_step = s.ranges.size() > 1 ? kPi / double(s.ranges.size() - 1) : 0;
  s.pose = f.pose("pose");
  s.odometry = f.pose("odometry");
  keepScan(f, std::move(s), line);
}

void LogReader::keepScan(Fields& f, LaserScan s, int line) {
  s.timestamp = readTrailer(f);
  f.expectEnd();
  checkTime(f, s.tag, s.timestamp, line);
  log_.scans.push_back(std::move(s));
  last_was_scan_ = true;
}

void LogReader::readRobotLaser(Fields& f, int line) {
  LaserScan s;
  s.tag = "ROBOTLASER1";
  s.line = line;
  f.number("laser type");
  s.start_angle = f.number("start angle");
  const double fov = f.number("field of view");
  s.angular_step = f.number("angular resolution");
  s.max_range = f.number("maximum range");
  f.number("accuracy");
  f.number("remission mode");
  if (!(fov > 0) || !(s.angular_step > 0) || !(s.max_range > 0))
    f.fail("field of view, angular resolution and maximum range must be > 0");
  if (s.max_range > kMaxRange) f.fail(beyond("maximum range", s.max_range, kMaxRange, "m"));
  // ranges, the remission count and its values, then 14 fields
  const std::size_t n = f.count("range count", f.size());
  if (f.remaining() < n + 1 + 14) {
    std::ostringstream m;
    m << "truncated ROBOTLASER1 record: it declares " << n << " ranges, so at least " << n + 15
      << " fields must follow the count, but only " << f.remaining() << " do";
    f.fail(m.str());
  }
  s.ranges.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.ranges[i] = f.number("range");
    if (s.ranges[i] < 0) f.fail("negative range (beam " + std::to_string(i) + ")");
    if (s.ranges[i] > kMaxRange)
      f.fail(beyond("range", s.ranges[i], kMaxRange, "m") + " (beam " + std::to_string(i) + ")");
  }
  const std::size_t m = f.count("remission count", f.remaining());
  if (f.remaining() != m + 14) {
    std::ostringstream msg;
    msg << "ROBOTLASER1 record declares " << n << " ranges and " << m
        << " remissions, which disagrees with its " << f.size() - 1 << " fields";
    f.fail(msg.str());
  }
  for (std::size_t i = 0; i < m; ++i) f.number("remission");
  const Pose2 laser = f.pose("laser pose");
  s.pose = s.odometry = f.pose("pose");
  s.laser_offset = s.pose.between(laser);
  if (s.laser_offset.t().norm() > kMaxLaserOffset)
    f.fail(beyond("the laser's distance from the robot", s.laser_offset.t().norm(), kMaxLaserOffset,
                  "m"));
  for (const char* w : {"tv", "rv", "forward safety", "side safety", "turn axis"}) f.number(w);
  keepScan(f, std::move(s), line);
}

// An ODOM record that repeats the scan just before it is that scan's echo:
// counted, not kept.
void LogReader::readOdometryRecord(Fields& f, int line) {
  OdometryRecord o;
  o.line = line;
  o.pose = f.pose("pose");
  o.tv = f.number("tv");
  o.rv = f.number("rv");
  o.accel = f.number("accel");
  o.timestamp = readTrailer(f);
  f.expectEnd();
  const bool echo = last_was_scan_ && log_.scans.back().pose.x == o.pose.x &&
                    log_.scans.back().pose.y == o.pose.y &&
                    log_.scans.back().pose.theta == o.pose.theta;
  last_was_scan_ = false;
  if (echo) {
    ++log_.odometry_echoes;
    return;
  }
  checkTime(f, "ODOM", o.timestamp, line);
  log_.odometry.push_back(o);
}

void LogReader::readParam(Fields& f, int line) {
  // CARMEN writes "name value timestamp host logger_timestamp"; older
  // logs (Intel, ACES) "name value host timestamp": the value is the
  // field after the name, what follows is not used.
  const std::string key(f.next("parameter name"));
  const std::string value(f.next("parameter value"));
  log_.params[key] = value;
  param_lines_[key] = line;
  last_was_scan_ = false;
}

void LogReader::requireLaser() const {
  if (log_.scans.empty() && options_.require_laser)
    throw Error(name_ + ": no laser scan (FLASER, RLASER or ROBOTLASER1) in the log");
}

// A PARAM is a number only when the reader uses it, so only then refused.
bool LogReader::numericParam(const std::string& key, double lo, double hi, const char* unit,
                             double* out) {
  const auto it = log_.params.find(key);
  if (it == log_.params.end()) return false;
  const std::string& value = it->second;
  const std::string where = name_ + ":" + std::to_string(param_lines_[key]) + ": PARAM " + key;
  const char* first = value.data() + (!value.empty() && value[0] == '+');
  const auto r = std::from_chars(first, value.data() + value.size(), *out);
  if (r.ec != std::errc() || r.ptr != value.data() + value.size() || !std::isfinite(*out))
    throw Error(where + " is not a number: " + quoted(value));
  if (!(*out >= lo && *out <= hi)) {
    std::ostringstream m;
    m << where << " " << *out << " " << unit << " is outside [" << lo << ", " << hi << "] " << unit;
    throw Error(m.str());
  }
  return true;
}

// A FLASER/RLASER stream's no-return range: given, declared by a PARAM, or
// inferred from the ranges its beams reach; returns how it was found.
std::string LogReader::noReturnRange(const std::vector<LaserScan*>& scans, bool is_front,
                                     double* no_return) {
  const std::string key = is_front ? "robot_front_laser_max" : "robot_rear_laser_max";
  if (options_.no_return_range > 0) {
    *no_return = options_.no_return_range;
    return "given (no_return_range)";
  }
  if (options_.declared_max_range && numericParam(key, 0, kMaxRange, "m", no_return)) {
    if (!(*no_return > 0))
      throw Error(name_ + ":" + std::to_string(param_lines_[key]) + ": PARAM " + key +
                  " must be > 0 m");
    return "declared by PARAM " + key + " (line " + std::to_string(param_lines_[key]) + ")";
  }
  std::vector<double> ranges;
  for (const LaserScan* s : scans) ranges.insert(ranges.end(), s->ranges.begin(), s->ranges.end());
  if (ranges.empty()) ranges.push_back(0);  // scans of no beams: nothing to infer
  // The k-th largest range: up to k - 1 absurd ranges on top do not move it.
  const std::size_t k = std::min(
      ranges.size(), std::max<std::size_t>(2, std::size_t(std::ceil(1e-4 * ranges.size()))));
  std::nth_element(ranges.begin(), ranges.begin() + std::ptrdiff_t(k - 1), ranges.end(),
                   std::greater<double>());
  const double reached = ranges[k - 1];
  *no_return = reached * (1 - kNoReturnBand);
  std::ostringstream m;
  m << "inferred: " << k << " of " << ranges.size() << " beams reach " << reached << " m, less "
    << kNoReturnBand * 100 << "%";
  return m.str();
}

// FLASER/RLASER: the lasers' mounting and no-return ranges from PARAMs.
void LogReader::mountFrontAndRearLasers() {
  double front = 0, rear = 0;
  numericParam("robot_frontlaser_offset", -kMaxLaserOffset, kMaxLaserOffset, "m", &front);
  numericParam("robot_rearlaser_offset", -kMaxLaserOffset, kMaxLaserOffset, "m", &rear);
  for (const char* tag : {"FLASER", "RLASER"}) {
    const bool is_front = tag[0] == 'F';
    std::vector<LaserScan*> scans;
    for (LaserScan& s : log_.scans)
      if (s.tag == tag) scans.push_back(&s);
    if (scans.empty()) continue;
    double no_return = 0;
    log_.no_return[tag] = noReturnRange(scans, is_front, &no_return);
    for (LaserScan* s : scans) {
      s->max_range = no_return;
      s->laser_offset = is_front ? Pose2(front, 0, 0) : Pose2(rear, 0, kPi);
    }
  }
}

}  // namespace

void CarmenReadOptions::validate() const {
  if (!(max_time_reversal >= 0) || !std::isfinite(max_time_reversal))
    throw Error("max_time_reversal must be >= 0 s");
  if (!(no_return_range >= 0) || !std::isfinite(no_return_range))
    throw Error("no_return_range must be >= 0 m");
}

std::vector<Point2> LaserScan::points() const {
  std::vector<Point2> out;
  out.reserve(ranges.size());
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (!hit(i)) continue;
    const double b = bearing(i);
    out.push_back(
        laser_offset.transformFrom(Point2(ranges[i] * std::cos(b), ranges[i] * std::sin(b))));
  }
  return out;
}

std::vector<Point2> LaserScan::points(const Pose2& robot) const {
  std::vector<Point2> out = points();
  for (Point2& p : out) p = robot.transformFrom(p);
  return out;
}

std::vector<const LaserScan*> CarmenLog::scansOf(const std::string& tag) const {
  std::vector<const LaserScan*> out;
  for (const LaserScan& s : scans)
    if (s.tag == tag) out.push_back(&s);
  return out;
}

std::vector<const LaserScan*> keyScans(const CarmenLog& log, const KeyScanOptions& options) {
  const std::vector<const LaserScan*> all = log.scansOf(options.tag);
  if (all.empty()) throw Error(log.file + ": no " + options.tag + " scans");
  std::vector<const LaserScan*> kept{all.front()};
  for (const LaserScan* s : all) {
    const Pose2 d = kept.back()->pose.between(s->pose);
    if (d.t().norm() >= options.step || std::abs(wrapAngle(d.theta)) >= options.turn)
      kept.push_back(s);
  }
  return kept;
}

CarmenLog parseCarmenLog(const std::string& text, const std::string& name,
                         const CarmenReadOptions& options) {
  options.validate();
  LogReader reader(name, options);
  reader.readLines(text);
  reader.requireLaser();
  reader.mountFrontAndRearLasers();
  return reader.take();
}

CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options) {
  options.validate();
  return parseCarmenLog(readFile(path), path, options);
}

Pose2 interpolateOdometry(const Pose2& a, const Pose2& b, double u) {
  return Pose2(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y),
               wrapAngle(a.theta + u * wrapAngle(b.theta - a.theta)));
}

}  // namespace hamal::carmen
