// Rewrites a blob's XXH64 checksum (store/blob.hpp layout) to match its bytes, so a fuzz target can
// reach the code behind the checksum; a no-op on inputs shorter than the header.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#define XXH_STATIC_LINKING_ONLY
#include <xxhash.h>

#include "store/blob.hpp"

namespace shadowtiles::fuzzing {

inline void fix_blob_checksum(std::vector<uint8_t>& blob) {
  if (blob.size() < store::kBlobHeaderSize) return;
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, blob.data(), 24);
  XXH64_update(&state, blob.data() + store::kBlobHeaderSize, blob.size() - store::kBlobHeaderSize);
  const uint64_t sum = XXH64_digest(&state);
  std::memcpy(blob.data() + 24, &sum, 8);  // little-endian host (the blob format is little-endian)
}

}  // namespace shadowtiles::fuzzing
