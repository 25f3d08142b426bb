// BackendHandle: a back-end as Python holds it, with the spec and options
// it was made from, and the UpdateResult with the update's wall time, so a
// Python loop reports what hamal_bench's rows report (apps/bench).
//
// A back-end is not thread-safe, and Python threads share it freely, so
// every call from Python holds the handle's lock (python/README.md,
// "Threads and callbacks"): a second thread's call waits, with the GIL
// released, until the first returns, and a reader never sees a half-made
// update. A call made from inside the back-end's own update (a Python
// factor's function or predict, on whatever thread the back-end evaluates
// it) would wait for itself, so it is refused with RuntimeError instead.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/backend.h"

namespace hamal::python {

struct TimedUpdateResult : UpdateResult {
  double seconds = 0;  // wall time of Backend::update alone
};

class BackendHandle {
 public:
  // What one call from Python holds: the lock and, for a call that may run
  // Python callbacks (`calls_python`), the mark that makes a call from
  // those callbacks a RuntimeError rather than a deadlock. Must be made
  // with the GIL held; waits with it released. `what` names the call in
  // the refusal.
  class Access {
   public:
    Access(BackendHandle& handle, const char* what, bool calls_python = false);
    ~Access();
    Access(const Access&) = delete;
    Access& operator=(const Access&) = delete;

   private:
    BackendHandle& handle_;
    std::unique_lock<std::mutex> lock_;
    bool calls_python_;
  };

  std::unique_ptr<Backend> backend;
  std::string spec;
  std::map<std::string, std::string> options;

  TimedUpdateResult update(const Step& step);
  // The back-end's ClosingVerdict (core/closing_verdict.h), ok without one.
  Status closingVerdict();

 private:
  std::mutex mutex_;
  // Set while a holder of the lock may run Python code: the thread holding
  // it (Python code on that thread is inside the call) and, for callbacks
  // on the back-end's own worker threads, insidePythonCallback().
  std::atomic<bool> calling_python_{false};
  std::atomic<std::thread::id> owner_{};
};

// True once `factor` has been given to a back-end's update (and not refused):
// the back-end evaluates it with its loss, Ceres through a raw pointer, so
// Factor.set_loss refuses it rather than free a loss in use.
bool heldByBackend(const Factor& factor);

}  // namespace hamal::python
