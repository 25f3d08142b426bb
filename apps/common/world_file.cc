// WorldFile: see world_file.h.
#include "apps/common/world_file.h"

#include <istream>
#include <sstream>

#include "core/error.h"
#include "core/key.h"
#include "core/line_tokens.h"

namespace hamal::apps {

namespace {

Point2 point(LineTokens& t, const char* x, const char* y) {
  const double px = t.number(x);
  return Point2(px, t.number(y));
}

// A landmark variable's index has 56 bits: a larger id would alias another.
std::uint64_t landmarkId(LineTokens& t, const char* what) {
  const std::uint64_t id = t.id(what);
  if (id > Key::kMaxIndex)
    t.fail(std::string(what) + " " + std::to_string(id) +
           " is larger than the largest landmark id " + std::to_string(Key::kMaxIndex));
  return id;
}

}  // namespace

WorldFile parseWorldFile(std::istream& in, const std::string& file) {
  WorldFile w;
  w.file = file;
  std::string text;
  while (std::getline(in, text)) {
    const int line = ++w.lines;
    const auto hash = text.find('#');
    if (hash != std::string::npos) text.resize(hash);
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    LineTokens t = LineTokens::split(file, line, text);
    const std::string& tag = t.tag();
    if (tag == "WORLD") {
      w.name = t.word("name");
    } else if (tag == "START") {
      if (w.has_start) t.fail("a second START");
      const double x = t.number("x"), y = t.number("y"), theta = t.angle("theta");
      w.start = Pose2(x, y, theta);
      w.has_start = true;
      w.start_line = line;
    } else if (tag == "ROUTE") {
      w.route.push_back({point(t, "x", "y"), line});
    } else if (tag == "PATH") {
      w.path.push_back({point(t, "x", "y"), line});
    } else if (tag == "WALL") {
      WorldFile::Wall wall;
      wall.a = point(t, "x1", "y1");
      wall.b = point(t, "x2", "y2");
      wall.line = line;
      if ((wall.b - wall.a).norm() < kMinWallLength) t.fail("zero-length wall");
      w.walls.push_back(wall);
    } else if (tag == "CORNER") {
      WorldFile::Corner c;
      c.id = landmarkId(t, "id");
      c.truth = point(t, "x", "y");
      if (t.remaining() > 0) {
        c.label = point(t, "label_x", "label_y");
        c.has_label = true;
      }
      c.line = line;
      t.expectEnd();
      for (const WorldFile::Corner& o : w.corners)
        if (o.id == c.id) t.fail("corner " + std::to_string(c.id) + " is defined twice");
      w.corners.push_back(c);
    } else if (tag == "OBJECT") {
      WorldFile::Object o;
      o.position = point(t, "x", "y");
      o.height = t.number("height");
      if (o.height < 0) t.fail("height must be >= 0");
      if (t.remaining() > 0) o.hides = static_cast<std::int64_t>(landmarkId(t, "hides_id"));
      o.line = line;
      w.objects.push_back(o);
    } else if (tag == "PERSON") {
      WorldFile::Person p;
      p.from = point(t, "x1", "y1");
      p.to = point(t, "x2", "y2");
      p.t0 = t.number("t0");
      p.speed = t.number("speed");
      p.line = line;
      t.expectEnd();
      if (!(p.speed > 0)) t.fail("speed must be > 0");
      w.people.push_back(p);
    } else {
      t.fail("unknown record '" + tag +
             "' (expected WORLD, START, ROUTE, WALL, CORNER, OBJECT, PERSON or PATH)");
    }
    t.expectEnd();
  }
  // A directory opens, then fails to read: say so rather than "no walls".
  if (in.bad()) throw Error(file + ": cannot read the world file");
  return w;
}

WorldFile parseWorldFile(const std::string& text, const std::string& file) {
  std::istringstream in(text);
  return parseWorldFile(in, file);
}

}  // namespace hamal::apps
