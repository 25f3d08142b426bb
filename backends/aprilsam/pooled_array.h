// PooledArray: the growable array of numbers behind IncrementalCholesky's
// pooled rows (thesis sec. 3.4.1: R kept between steps) and the normal
// equations' blocks.
//
// It is std::vector without what costs on a long incremental run: growing
// does not zero-fill (the owner writes every number it uses), and on Linux
// an array of 2 MiB or more lives in its own mapping, aligned to and sized
// in huge pages, with transparent huge pages asked for. The first touch of
// each 4 KiB page is a page fault, and on a virtual machine a fault costs
// as much as tens of thousands of flops; R's pool reaches megabytes, and a
// batch that outgrows it touches all of its new room at once. With huge
// pages that is one fault per 2 MiB where the kernel has them to give
// (elsewhere the mapping behaves as 4 KiB pages, no worse than malloc). The
// array never shrinks by itself: release() is for an owner that knows a
// peak has passed.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace hamal::aprilsam {

template <typename T>
class PooledArray {
  static_assert(std::is_trivially_copyable_v<T>, "PooledArray holds plain numbers");

 public:
  PooledArray() = default;
  ~PooledArray() { freeAll(); }
  PooledArray(const PooledArray& o) { copyFrom(o); }
  PooledArray& operator=(const PooledArray& o) {
    if (this != &o) copyFrom(o);
    return *this;
  }
  PooledArray(PooledArray&& o) noexcept { swap(o); }
  PooledArray& operator=(PooledArray&& o) noexcept {
    swap(o);
    return *this;
  }
  void swap(PooledArray& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(capacity_, o.capacity_);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    std::swap(mapped_, o.mapped_);
#endif
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  // Room for this many numbers; all of them are the owner's to read and write.
  std::size_t capacity() const { return capacity_; }

  // Room for at least n numbers, the first capacity() kept; the new ones
  // are uninitialised. Grows to twice the room at least, so that growing
  // one row at a time costs O(1) per number.
  void reserve(std::size_t n) {
    if (n <= capacity_) return;
    std::size_t c = capacity_ < 16 ? 16 : 2 * capacity_;
    if (c < n) c = n;
    reallocate(c);
  }
  // Room for exactly n >= the numbers in use (the first n kept): hands the
  // rest back after a peak has passed.
  void release(std::size_t n) {
    if (n < capacity_) reallocate(n);
  }

 private:
  // Arrays of at least this many bytes live in their own mappings, aligned
  // to and sized in huge pages.
  static constexpr std::size_t kHuge = std::size_t{1} << 21;

  // Moves the first min(n, capacity()) numbers to a block with room for n:
  // a mapping when it is kHuge bytes or more (Linux), the heap otherwise.
  void reallocate(std::size_t n) {
    if (n > (SIZE_MAX - kHuge) / sizeof(T)) throw std::bad_alloc();
    std::size_t bytes = n * sizeof(T), mapped = 0;
    void* p = nullptr;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes >= kHuge) {
      // A new mapping and a copy, not mremap: the copy runs at memory
      // speed, and mremap could move the pages off the huge-page alignment.
      bytes = mapped = (bytes + kHuge - 1) & ~(kHuge - 1);
      p = mapHuge(bytes);
    }
#endif
    if (mapped == 0 && bytes > 0 && (p = std::malloc(bytes)) == nullptr) throw std::bad_alloc();
    const std::size_t keep = std::min(bytes, capacity_ * sizeof(T));
    if (keep > 0) std::memcpy(p, data_, keep);
    freeAll();
    data_ = static_cast<T*>(p);
    capacity_ = bytes / sizeof(T);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    mapped_ = mapped;
#endif
  }
  void copyFrom(const PooledArray& o) {
    reallocate(o.capacity_);
    if (o.capacity_ > 0) std::memcpy(data_, o.data_, o.capacity_ * sizeof(T));
  }
  void freeAll() {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (mapped_ > 0) {
      munmap(data_, mapped_);
      mapped_ = 0;
      data_ = nullptr;
      return;
    }
#endif
    std::free(data_);
    data_ = nullptr;
  }
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // `bytes` (a multiple of kHuge) at a kHuge-aligned address, to be backed
  // by huge pages where the kernel allows (transparent huge pages enabled
  // or set to madvise).
  static void* mapHuge(std::size_t bytes) {
    void* raw =
        mmap(nullptr, bytes + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const std::uintptr_t r = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t a = (r + kHuge - 1) & ~(std::uintptr_t{kHuge} - 1);
    if (a > r) munmap(raw, a - r);
    if (r + kHuge > a) munmap(reinterpret_cast<void*>(a + bytes), r + kHuge - a);
    void* p = reinterpret_cast<void*>(a);
    (void)madvise(p, bytes, MADV_HUGEPAGE);
    return p;
  }
  std::size_t mapped_ = 0;  // bytes of data_'s own mapping; 0: data_ is malloc'd
#endif

  T* data_ = nullptr;
  std::size_t capacity_ = 0;
};

}  // namespace hamal::aprilsam
