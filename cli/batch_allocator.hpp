// Allocator policies of the CLI's batch commands that allocate and free the same large buffers over
// and over (`build` and `inspect` tile after tile, `merge` transaction after transaction).
// Process-wide, so they are set by those commands, never by the library (a program linking the
// library keeps its own policy). Other C libraries than glibc: nothing is changed.
#pragma once

#include <cstdint>

namespace shadowtiles::cli {

// glibc: freed memory stays in one arena's heap for the next tile instead of going back to the
// kernel (no mmap for large blocks, a 1 GiB trim threshold, one arena for every thread), in small
// pages (huge pages were dropped in session 38). Measured in docs/build-time.md (sessions 20, 25, 38).
void keep_freed_memory_for_reuse();

// glibc: blocks up to 32 MiB come from the heap, and up to 4 transactions' worth of free heap (at
// most 1 GiB) is kept, so the heap's peak stays bounded by the transaction and chunk sizes.
void keep_transaction_buffers_resident(uint64_t transaction_bytes);

}  // namespace shadowtiles::cli
