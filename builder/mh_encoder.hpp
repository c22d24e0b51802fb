// Encodes an MhHierarchy (MH or MMH) into the random-access payload of codec/mh_format.hpp
// (docs/mh.md), read by codec/mh_decoder. Values are mh_value_for(interval) (finite, inside the
// interval). Blocks are laid out in preorder (a block, then each child's subtree in turn; shared
// MMH blocks after all their parents), so offsets point forward and a walk's deep levels lie close
// together; the offset width is the smallest of 1..4 bytes that addresses the node stream.
// Errors: invalid_input for a malformed hierarchy (check_structure) or a node stream over 4 GiB.
// Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/mh_hierarchy.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct MhEncodeOptions {
  // Embed a dense skip list at this level (clamped to the tile's levels and to 10). Off by default:
  // the decoder derives the identical list at parse time, and at level 6 it costs 4096 x (5 + offset
  // width) bytes, more than many whole tiles. Worth it for a top-level tree served on its own.
  bool embed_skip_list = false;
  unsigned skip_level = 6;
};

Result<std::vector<uint8_t>> encode_mh(const MhHierarchy& hierarchy, const MhEncodeOptions& options = {});

// Size the SBE16a layout (authors' code) would take for the same stored nodes: 8 bytes per inner
// node, 4 per empty node or leaf, shared blocks once; per-level offset padding ignored. For the
// comparison tables against the papers.
uint64_t sbe16a_reference_bytes(const MhHierarchy& hierarchy);

}  // namespace shadowtiles
