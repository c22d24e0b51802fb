// Page-cache advice for byte ranges inside a read-only store's memory map (spans from
// Store::Snapshot::Cursor or get_view), for streaming a store once in key order (a merge): ask the
// kernel to start reading a value before it is needed, and drop a consumed value's pages from this
// process's map so its resident memory stays bounded whatever the store's size. The page cache keeps
// the data; a later touch of a dropped page faults it back in from there or from the file.
// Only for maps LMDB opened read-only (never written through the map). Advice failures are ignored:
// they only cost speed or memory, never correctness.
// Thread safety: pure system calls.
#pragma once

#include <cstdint>
#include <span>

namespace shadowtiles::store {

// Starts asynchronous read-ahead of the pages under `bytes` (MADV_WILLNEED).
void advise_will_need(std::span<const uint8_t> bytes);
// Unmaps the pages under `bytes` from this process (MADV_DONTNEED on a shared read-only file map).
void advise_done_with(std::span<const uint8_t> bytes);

}  // namespace shadowtiles::store
