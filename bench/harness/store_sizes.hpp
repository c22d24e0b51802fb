// Store sizes: what each method's tiles take in a built store, at rest (blob bytes: header + zstd
// payload, the sum inspect prints) and decoded (payload bytes), and the number of non-empty texels
// (lower < 1, counted on the raw tiles) that "bytes per non-empty texel" divides by.
// Errors: the store's (I/O), corrupt_data for a record failing its checks.
// Thread safety: reads only; safe beside concurrent readers of the same ShadowMap.
#pragma once

#include <cstdint>
#include <map>

#include "client/shadow_map.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::bench {

struct MethodSize {
  uint64_t tiles = 0;
  uint64_t blob_bytes = 0;
  uint64_t payload_bytes = 0;
};

// Per method present in the store's `tiles` database.
Result<std::map<store::Method, MethodSize>> method_sizes(const ShadowMap& map);

// Texels whose stored raw value (the interval's lower bound) is < 1. Decodes every raw tile once.
// Errors: unsupported when the store holds no raw tiles.
Result<uint64_t> count_nonempty_texels(const ShadowMap& map);

}  // namespace shadowtiles::bench
