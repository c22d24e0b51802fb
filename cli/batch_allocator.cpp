#include "cli/batch_allocator.hpp"

#include <algorithm>
#include <cstdlib>  // defines __GLIBC__ on glibc (tested below)

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace shadowtiles::cli {
namespace {

#if defined(__GLIBC__) && defined(__linux__) && defined(MADV_HUGEPAGE)
// The heap a build grows in its first tiles (hundreds of MiB on a full-depth tree), in 2 MiB pages
// where the kernel allows: one page fault per 2 MiB instead of per 4 KiB. On this VM a fault costs
// several microseconds, and the faults of the heap's growth were 7 % of honolulu 16384² `anywhere`'s
// samples; with glibc's own switch for it (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, which a program
// cannot set for itself) that build took 7.67 / 7.42 / 7.20 -> 6.59 / 6.40 / 6.55 s. So: one block
// of kHeapReserve from the heap (M_MMAP_MAX is 0, so it extends the program break), advised as huge
// pages and freed. It stays in the heap (below the trim threshold), untouched pages cost nothing
// resident, and the tiles' buffers that later reuse it fault in 2 MiB at a time. Under other
// allocators (ASan's) the advice lands on memory malloc returns to them: no effect, no harm.
constexpr size_t kHeapReserve = size_t(768) << 20;
constexpr uintptr_t kHugePage = uintptr_t(2) << 20;

void back_heap_growth_with_huge_pages() {
  void* block = std::malloc(kHeapReserve);
  if (!block) return;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(block) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(block) + kHeapReserve) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice only
  std::free(block);
}
#else
void back_heap_growth_with_huge_pages() {}
#endif

}  // namespace

void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  // Every tile allocates and frees the same large buffers (a build's hierarchies, the MMH merge's
  // copy and compacted tree, payloads; inspect's decoded tiles: tens of MiB each on a full-depth
  // tree). glibc maps blocks over its threshold (32 MiB at most) afresh each time and trims freed
  // heap, so each tile faulted zeroed pages in again: on fzk_haus 16384² `anywhere` 1.1 M page
  // faults and 14 % of a build's CPU. Kept in the heap, they are reused. One arena for every
  // thread too: a worker's own arena is made of 64 MiB heaps that glibc unmaps as soon as one is
  // empty, whatever the trim threshold, and its blocks over 64 MiB are mapped afresh; the main
  // arena grows without either. Against glibc's defaults, that build: wall 0.75x with the first two
  // settings (peak RSS 832 -> 919 MiB), then 0.70x of that with one arena (peak 886 -> 793 MiB);
  // dragon `surfaces`, whose tiles allocate little, 0.99x. `inspect` of the fzk_haus store: 0.31x.
  // The one arena's lock is taken rarely: blocks over 1 KiB are a few hundred per tile (counted:
  // 260 on dragon `surfaces`, ~600 on fzk_haus `anywhere`), and most small ones come from each
  // thread's cache (tcache) without it. Not for `verify` (4096² fzk_haus `surfaces`: 1.1x slower).
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_ARENA_MAX, 1);
  back_heap_growth_with_huge_pages();
#endif
}

void keep_transaction_buffers_resident(uint64_t transaction_bytes) {
#if defined(__GLIBC__)
  // The merge allocates and frees blob-sized buffers (its chunks, LMDB's pages of each transaction)
  // over and over; by default glibc hands blocks over its mmap threshold straight back to the kernel
  // and trims the heap's top, so every transaction faulted fresh zeroed pages in again (a sixth of
  // the merge's time in perf). Kept in the heap, they are reused.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, int(std::min<uint64_t>(transaction_bytes * 4, 1ull << 30)));
#else
  (void)transaction_bytes;
#endif
}

}  // namespace shadowtiles::cli
