// VisitStamps: "seen in this pass" for the passes over factors or variables
// of AprilSAM's graph (the top re-elimination's factors on the top, the
// component-switch hook's switched factors and their variables): a stamp
// per item, a new pass a new stamp, so a pass costs the items it visits and
// never clears the map's worth of flags.
#pragma once

#include <cstddef>
#include <vector>

namespace hamal::aprilsam {

class VisitStamps {
 public:
  // A new pass over items 0..n-1.
  void newPass(std::size_t n) {
    if (stamps_.size() < n) stamps_.resize(n, 0);
    ++current_;
  }
  // True the first time item i is visited in this pass.
  bool visit(int i) {
    if (stamps_[i] == current_) return false;
    stamps_[i] = current_;
    return true;
  }

 private:
  std::vector<long> stamps_;
  long current_ = 0;
};

}  // namespace hamal::aprilsam
