// A reusable array of trivially copyable T in memory the kernel may back with 2 MiB pages
// (madvise(MADV_HUGEPAGE); transparent huge pages in `madvise` or `always` mode). For large tables
// read at random, whose every access would otherwise miss the TLB: one entry covers 2 MiB instead
// of 4 KiB. Arrays under 2 MiB get an ordinary cache-line-aligned allocation (rounding them up to a
// huge page would multiply their memory); so does every array where there is no THP.
// Thread safety: none; one owner (a thread_local reused across calls, or a decoded tile).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

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
  HugePageArray(HugePageArray&& other) noexcept { swap(other); }
  HugePageArray& operator=(HugePageArray&& other) noexcept {
    HugePageArray(std::move(other)).swap(*this);
    return *this;
  }
  ~HugePageArray() { std::free(data_); }

  // Sizes the array to n elements, every byte zero (allocating only when it grows).
  void assign_zero(size_t n) {
    resize_for_overwrite(n);
    if (n > 0) std::memset(static_cast<void*>(data_), 0, n * sizeof(T));  // data_ may be null when n == 0
  }
  // Sizes the array to n elements whose contents are unspecified (allocating only when it grows):
  // for a caller that writes every element next.
  void resize_for_overwrite(size_t n) {
    if (n > capacity_) {
      std::free(data_);
      data_ = nullptr, capacity_ = 0, size_ = 0;
      const bool huge = n * sizeof(T) >= kHugePage;
      const size_t align = huge ? kHugePage : kCacheLine;
      const size_t bytes = (n * sizeof(T) + align - 1) / align * align;
      data_ = static_cast<T*>(std::aligned_alloc(align, bytes));
      if (!data_) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
      if (huge) madvise(data_, bytes, MADV_HUGEPAGE);  // advice only: failure leaves 4 KiB pages
#endif
      capacity_ = bytes / sizeof(T);
    }
    size_ = n;
  }
  size_t size() const { return size_; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  void swap(HugePageArray& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    std::swap(capacity_, other.capacity_);
  }
  static constexpr size_t kHugePage = size_t(2) << 20;
  static constexpr size_t kCacheLine = 64;
  T* data_ = nullptr;
  size_t size_ = 0, capacity_ = 0;
};

}  // namespace shadowtiles
