#pragma once
// Splitting an index range over a few threads, for the builder's and the client's short
// data-parallel passes (no pool: each call's threads end with it).

#include <cstddef>
#include <functional>

namespace shadowtiles {

// Runs fn(begin, end) over [0, count) in up to `threads` contiguous parts, each part once (one empty
// part when count is 0); the calling thread takes the first part. threads = 0 counts as 1.
void parallel_for_ranges(unsigned threads, size_t count, const std::function<void(size_t, size_t)>& fn);

}  // namespace shadowtiles
