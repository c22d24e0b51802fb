// Allocator policy of the `shadowtiles serve` process: keeps a batch request's large buffers (the
// body, its points, query_batch's sort arrays, the answer) in the malloc heap between requests instead
// of mapping and unmapping them each time. With glibc's defaults every 100k-point binary batch took
// ~1,300 page faults (zeroed fresh pages for ~5 MB of buffers): 25% of the request's CPU time.
// Process-wide, so it is called by the serve command, never by the library.
#pragma once

namespace shadowtiles::server {

// glibc: buffers up to 32 MiB (a largest batch: 16 MiB body, 24 MiB of points are above it and stay
// mapped) come from the heap, and up to 64 MiB of free heap per arena is kept rather than returned.
// Returns false when the C library refused (other C libraries: a no-op).
bool keep_batch_buffers_resident();

}  // namespace shadowtiles::server
