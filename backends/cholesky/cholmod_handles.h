// CHOLMOD handles: RAII owners for the CHOLMOD objects the normal-equation
// back-ends use (cholesky, sec. 3.5.1's sqrt-SAM-Chol, and later aprilsam),
// so that every exit path frees what it allocated.
//
// hamal uses the SuiteSparse_long interface (cholmod_l_*) throughout: one
// cholmod_common must never be mixed between the int and long variants.
// The Common is set up quiet: CHOLMOD prints nothing and never aborts, errors
// and warnings (CHOLMOD_NOT_POSDEF) are read from common->status by the
// caller, which turns them into a Status.
#pragma once

#include <cholmod.h>

#include <utility>

namespace hamal::cholesky {

// Owns a cholmod_common: started in the constructor, finished in the destructor.
class Common {
 public:
  Common() {
    cholmod_l_start(&c_);
    c_.print = 0;                                                  // no messages on stdout
    c_.error_handler = [](int, const char*, int, const char*) {};  // and no abort
  }
  ~Common() { cholmod_l_finish(&c_); }
  Common(const Common&) = delete;
  Common& operator=(const Common&) = delete;

  cholmod_common* get() { return &c_; }
  cholmod_common* operator->() { return &c_; }

 private:
  cholmod_common c_;
};

// A unique owner of one CHOLMOD object; `Free` is the cholmod_l_free_* call.
// The Common must outlive every handle allocated from it.
template <typename T, int (*Free)(T**, cholmod_common*)>
class Handle {
 public:
  Handle() = default;
  Handle(T* p, cholmod_common* c) : p_(p), c_(c) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : p_(std::exchange(o.p_, nullptr)), c_(o.c_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      p_ = std::exchange(o.p_, nullptr);
      c_ = o.c_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  void reset() {
    if (p_) Free(&p_, c_);
    p_ = nullptr;
  }
  void reset(T* p, cholmod_common* c) {
    reset();
    p_ = p;
    c_ = c;
  }
  T* get() const { return p_; }
  T* operator->() const { return p_; }
  explicit operator bool() const { return p_ != nullptr; }
  // For CHOLMOD calls that (re)allocate through a T** (cholmod_l_solve2's X,
  // Y, E): the handle keeps ownership of whatever ends up there.
  T** out(cholmod_common* c) {
    c_ = c;
    return &p_;
  }

 private:
  T* p_ = nullptr;
  cholmod_common* c_ = nullptr;
};

using Sparse = Handle<cholmod_sparse, cholmod_l_free_sparse>;
using Factor = Handle<cholmod_factor, cholmod_l_free_factor>;
using Dense = Handle<cholmod_dense, cholmod_l_free_dense>;
using Triplet = Handle<cholmod_triplet, cholmod_l_free_triplet>;

}  // namespace hamal::cholesky
