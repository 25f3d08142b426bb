// libFuzzer target: the CARMEN log reader (apps/carmen/carmen_log.h) on
// arbitrary bytes. Bytes that begin as gzip does (1f 8b) go through a file
// and zlib (readCarmenLog), the others to the parser (parseCarmenLog).
// Reading either fails with a hamal::Error whose message fits a terminal,
// or gives a log whose every range and pose is finite and within the
// reader's bounds, whose scans have the beams they declare and whose
// points are finite. Any other exception, a crash or a sanitizer report is
// a bug.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "apps/carmen/carmen_log.h"
#include "core/error.h"

namespace {

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "carmen_log_fuzz: %s\n", what.c_str());
  std::abort();
}

bool finite(const hamal::Pose2& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

// The file the gzip inputs go through, removed when the fuzzer exits.
const std::string& gzipPath() {
  static const std::string path = "/tmp/carmen_log_fuzz_" + std::to_string(getpid()) + ".log.gz";
  return path;
}
void removeGzipFile() { std::remove(gzipPath().c_str()); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const bool gzip = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
  const std::string& path = gzipPath();
  if (gzip) {
    static const bool cleanup = std::atexit(removeGzipFile) == 0;
    (void)cleanup;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out.flush()) bug("cannot write " + path);
  }
  hamal::carmen::CarmenLog log;
  try {
    log =
        gzip ? hamal::carmen::readCarmenLog(path) : hamal::carmen::parseCarmenLog(text, "fuzz.log");
  } catch (const hamal::Error& e) {
    const std::string m = e.what();
    for (unsigned char c : m)
      if (c < 0x20 || c >= 0x7f) bug("an error message holds a raw control byte: " + m);
    if (m.size() > 4000) bug("an error message of " + std::to_string(m.size()) + " bytes");
    return 0;
  } catch (const std::exception& e) {
    bug(std::string("not a hamal::Error: ") + e.what());
  }
  if (log.scans.empty()) bug("a log without scans was read");
  for (const hamal::carmen::LaserScan& s : log.scans) {
    if (!finite(s.pose) || !finite(s.odometry) || !finite(s.laser_offset))
      bug("a non-finite pose was read");
    for (double r : s.ranges)
      if (!std::isfinite(r) || r < 0 || r > hamal::carmen::kMaxRange)
        bug("a non-finite, negative or absurd range was read");
    for (const hamal::Pose2* p : {&s.pose, &s.odometry})
      if (std::abs(p->x) > hamal::carmen::kMaxPose || std::abs(p->y) > hamal::carmen::kMaxPose)
        bug("a pose beyond the reader's bound was read");
    if (s.laser_offset.t().norm() > hamal::carmen::kMaxLaserOffset + 1e-9)
      bug("a laser offset beyond the reader's bound was read");
    for (const hamal::Point2& p : s.points(s.pose))
      if (!std::isfinite(p.x()) || !std::isfinite(p.y())) bug("a non-finite point");
  }
  for (const hamal::carmen::OdometryRecord& o : log.odometry)
    if (!finite(o.pose) || !std::isfinite(o.timestamp)) bug("a non-finite odometry record");
  return 0;
}
