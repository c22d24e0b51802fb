// The sort key of a point in ShadowMap::query_batch (client/shadow_batch.cpp): the texel's Morton
// code in the low bits. Maps up to 2^15 texels wide (codes of at most 30 bits) also keep the texel's
// u and v in the key's upper half (u in bits 32-47, v in 48-63), so the walk reads them where wider
// maps de-interleave the code (~30 instructions per point). The sort and the runs look at code()
// only. kOffMapKey (all ones) is never a key of a texel: packed codes stop at bit 29, and a wider
// map's codes at bit 2 * 20 - 1.
// Thread safety: immutable values.
#pragma once

#include <cstdint>

#include "codec/morton.hpp"

namespace shadowtiles {

class BatchTexelKeys {
 public:
  static constexpr uint64_t kOffMapKey = ~uint64_t(0);
  // key_bits: 2 * log2(resolution).
  static BatchTexelKeys for_key_bits(unsigned key_bits) { return BatchTexelKeys(key_bits <= 30); }

  bool packed() const { return packed_; }
  // The key of texel (u, v) in each layout: make_packed when packed(), else make_wide (the batch
  // tests packed() once per block of points, not per point).
  static uint64_t make_packed(uint32_t u, uint32_t v) {
    return morton_encode16(u, v) | (uint64_t(u) << 32) | (uint64_t(v) << 48);
  }
  static uint64_t make_wide(uint32_t u, uint32_t v) { return morton_encode(u, v); }
  uint64_t code(uint64_t key) const { return key & code_mask_; }
  uint32_t u(uint64_t key) const { return packed_ ? uint32_t(key >> 32) & 0xFFFFu : morton_u(key); }
  uint32_t v(uint64_t key) const { return packed_ ? uint32_t(key >> 48) : morton_v(key); }

 private:
  explicit BatchTexelKeys(bool packed) : packed_(packed), code_mask_(packed ? 0xFFFFFFFFull : ~uint64_t(0)) {}
  bool packed_;
  uint64_t code_mask_;
};

}  // namespace shadowtiles
