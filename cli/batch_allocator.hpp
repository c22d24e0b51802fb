// Allocator policy of the CLI's batch commands that allocate and free the same large buffers tile
// after tile (`build`, `inspect`). Process-wide, so it is set by those commands, never by the
// library (a program linking the library keeps its own policy).
#pragma once

namespace shadowtiles::cli {

// glibc: freed memory stays in one arena's heap for the next tile instead of going back to the
// kernel (no mmap for large blocks, a 1 GiB trim threshold, one arena for every thread). Measured
// in docs/build-time.md (session 20). Other C libraries: nothing is changed.
void keep_freed_memory_for_reuse();

}  // namespace shadowtiles::cli
