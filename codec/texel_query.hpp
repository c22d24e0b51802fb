// TexelQuery: one receiver of a batch inside a tile (tile-local texel and biased depth), the unit
// the decoders' batch walks (lit_sorted) answer: lit when threshold <= the texel's value.
// Thread safety: plain value type.
#pragma once

#include <cstdint>

namespace shadowtiles {

struct TexelQuery {
  uint32_t u, v;  // tile-local texel
  float threshold;
};

}  // namespace shadowtiles
