// TopBackoff: when reeliminate=top stops batching at every step (hamal's,
// not in the thesis; the top re-elimination's fallback, README.md
// "Re-eliminating the top"). A top over top_share falls back to a full
// batch; right after one, L holds the variables that batch's Gauss-Newton
// step moved by delta_T or more. When that is no fewer than the batch
// started from, it made no progress. Three such batches in a row
// say the map is where Gauss-Newton does not converge (a robust wrapper's
// choice of closures can leave it so: GNC's on ais2klinik + 1000 random),
// and a batch at every step pays a full factorisation per step for an
// estimate that only jumps. So the next tops over top_share stay
// incremental for 2, 4, 8... updates (at most `top_backoff`), after which
// one batch looks again; an update the policy lets stay incremental, or a
// top that runs, starts it over. A batch that shrinks L is Gauss-Newton
// converging and is not held back, so a graph that converges batches as
// before (TopBackoff.HoldsOnlyWithoutProgress).
#pragma once

#include <algorithm>

namespace hamal::aprilsam {

class TopBackoff {
 public:
  explicit TopBackoff(long max_steps) : max_(max_steps) {}

  // Whether the top over top_share at update `step`, with |L| = `moved`,
  // stays incremental (the policy's batch held back).
  bool hold(long step, long moved) {
    if (max_ <= 0) return false;
    if (step < until_) return true;
    if (stalls_ < kStalls || step != last_step_ + 1 || moved < last_moved_) return false;
    wait_ = std::min(max_, wait_ > 0 ? 2 * wait_ : 2);
    until_ = step + wait_;
    return true;
  }
  // A full batch ran at `step` for a top over top_share, from |L| = `moved`.
  void batched(long step, long moved) {
    // A stall goes on across a hold (the batch that ends it looks again).
    if (last_step_ >= 0 && (step == last_step_ + 1 || step == until_) && moved >= last_moved_)
      ++stalls_;
    else if (step != until_)
      stalls_ = 0;
    last_step_ = step;
    last_moved_ = moved;
  }
  // Progress (no batch asked, or a top ran): the back-off starts over.
  void reset() {
    wait_ = 0;
    stalls_ = 0;
    until_ = -1;
    last_step_ = -1;
  }
  // The first update at which a batch may run again.
  long until() const { return until_; }

 private:
  // A hold needs this many fallback batches in a row that made no
  // progress, besides the last one: the first steps after a long loop
  // closure can move more of the map than the closure did (two in a row
  // on ais2klinik + 1000 random s1, the tuning run; judged on M3500 and
  // city10000, clean and + 1000 under GNC, and intel, CSAIL, MIT and
  // manhattan + 100, where no batch is held; a clean ais2klinik holds two
  // updates in its last closure and ends where it did without).
  static constexpr long kStalls = 2;
  long stalls_ = 0;      // fallback batches in a row that made no progress
  long max_;             // top_backoff: the longest hold, in updates; 0: off
  long wait_ = 0;        // the last hold's length
  long until_ = -1;      // holding before this update
  long last_step_ = -1;  // the last fallback batch's update
  long last_moved_ = 0;  // |L| it started from
};

}  // namespace hamal::aprilsam
