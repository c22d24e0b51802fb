// A reusable array of trivially copyable T in memory the kernel may back with 2 MiB pages
// (madvise(MADV_HUGEPAGE); transparent huge pages in `madvise` or `always` mode). For large tables
// read at random, whose every access would otherwise miss the TLB: one entry covers 2 MiB instead
// of 4 KiB. Elsewhere (no THP, other systems) it is an ordinary aligned allocation.
// Thread safety: none; one owner (typically thread_local, reused across calls).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace shadowtiles {

template <class T>
class HugePageArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  HugePageArray() = default;
  HugePageArray(const HugePageArray&) = delete;
  HugePageArray& operator=(const HugePageArray&) = delete;
  ~HugePageArray() { std::free(data_); }

  // Sizes the array to n elements, every byte zero (allocating only when it grows).
  void assign_zero(size_t n) {
    if (n > capacity_) {
      std::free(data_);
      data_ = nullptr, capacity_ = 0, size_ = 0;
      const size_t bytes = (n * sizeof(T) + kHugePage - 1) / kHugePage * kHugePage;
      data_ = static_cast<T*>(std::aligned_alloc(kHugePage, bytes));
      if (!data_) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
      madvise(data_, bytes, MADV_HUGEPAGE);  // advice only: failure leaves 4 KiB pages
#endif
      capacity_ = bytes / sizeof(T);
    }
    size_ = n;
    if (n > 0) std::memset(static_cast<void*>(data_), 0, n * sizeof(T));  // data_ may be null when n == 0
  }
  size_t size() const { return size_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  static constexpr size_t kHugePage = size_t(2) << 20;
  T* data_ = nullptr;
  size_t size_ = 0, capacity_ = 0;
};

}  // namespace shadowtiles
