#include "cli/batch_allocator.hpp"

#include <algorithm>
#include <cstdlib>  // defines __GLIBC__ on glibc (tested below)

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace shadowtiles::cli {

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
  // The heap is not advised as transparent huge pages. Session 25's advice (a freed 768 MiB block
  // under madvise(MADV_HUGEPAGE)) once sped builds up (honolulu `anywhere` wall/rays 6.71 / 6.88 /
  // 6.61 -> 6.26 / 5.98 / 6.40), but on this VM a fresh 2 MiB page now costs several times its 512
  // small pages: a first touch of 400 MiB took 1.53 / 1.46 / 1.17 s in huge pages against 0.27 /
  // 0.29 / 0.27 s in small ones, alternated. Without the advice honolulu `anywhere` took 10.8 /
  // 10.0 / 9.2 / 9.9 s against 12.7 / 11.1 / 11.9 / 11.0 s with it, and oahu `surfaces` 3.66 s
  // against 4.17 s (means of five); docs/build-time.md, session 38.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_ARENA_MAX, 1);
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
