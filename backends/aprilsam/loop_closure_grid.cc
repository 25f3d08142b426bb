// LoopClosureGrid: see loop_closure_grid.h (thesis Alg. 3.1 line 9).
#include "backends/aprilsam/loop_closure_grid.h"

#include <algorithm>
#include <cmath>

namespace hamal::aprilsam {

namespace {
// A grid coordinate, clamped so that a far-off (or diverged) estimate still
// converts to an integer without overflow.
long cellIndex(double coordinate, double r) {
  constexpr double kLimit = 1e15;
  return static_cast<long>(std::clamp(std::floor(coordinate / r), -kLimit, kLimit));
}

// Packs two grid coordinates, negative ones included, into one hash key.
// Shifting a negative long is undefined: the packing is done unsigned.
long cellKey(long cx, long cy) {
  const unsigned long packed =
      (static_cast<unsigned long>(cx) << 32) ^ (static_cast<unsigned long>(cy) & 0xffffffffUL);
  return static_cast<long>(packed);
}

Eigen::Vector2d location(const Values::Entry& lin) { return {lin.data[0], lin.data[1]}; }
}  // namespace

long LoopClosureGrid::cell(double x, double y) const {
  return cellKey(cellIndex(x, radius_), cellIndex(y, radius_));
}

void LoopClosureGrid::insert(int v, const Values::Entry& lin) {
  if (!counts()) return;
  const Eigen::Vector2d p = location(lin);
  if (!p.allFinite()) return;
  cells_[cell(p.x(), p.y())].push_back(v);
}

void LoopClosureGrid::refile(const std::vector<Values::Entry>& lin) {
  if (!counts()) return;
  // Cells emptied by earlier refiles stay in the map, and a map whose
  // estimate wanders (a robust model's batches, a diverging solve) leaves
  // ever more of them: clearing them all at every batch then costs more
  // than the batch. Past twice the variables, start from an empty map.
  if (cells_.size() > 2 * lin.size() + 64)
    cells_.clear();
  else
    for (auto& c : cells_) c.second.clear();  // keep the cells' capacity
  for (int v = 0; v < static_cast<int>(lin.size()); ++v) insert(v, lin[v]);
}

long LoopClosureGrid::countPossibleLoopClosureNodes(int newest,
                                                    const std::vector<Values::Entry>& lin) const {
  if (n_lc_ > 0) return n_lc_;
  const double r = radius_;
  if (r <= 0 || newest < 0) return 0;
  const Eigen::Vector2d c = location(lin[newest]);
  if (!c.allFinite()) return 0;
  const long cx = cellIndex(c.x(), r);
  const long cy = cellIndex(c.y(), r);
  long count = 0;
  for (long dx = -1; dx <= 1; ++dx)
    for (long dy = -1; dy <= 1; ++dy) {
      auto it = cells_.find(cellKey(cx + dx, cy + dy));
      if (it == cells_.end()) continue;
      for (int v : it->second)
        if (v != newest && (location(lin[v]) - c).norm() < r) ++count;
    }
  return count;
}

}  // namespace hamal::aprilsam
