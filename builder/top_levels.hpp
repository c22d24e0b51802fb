// Top levels (docs/architecture.md, store layout): every tile's root interval forms a coarse map of
// tiles_per_side² texels, itself compressed for every method with a top tree by the method's own
// top-tree encoder (builder/method_encoders.hpp: an MH with the skip list embedded for mh/mmh, a
// DAG-MH for dagmh) and stored in `top` under top_tree_key(method).
// One function for the one-machine build and for `shadowtiles merge`, so both write the same bytes.
// Errors: from the MH/MMH/DAG-MH encoders. Thread safety: stateless.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "common/result.hpp"
#include "store/lmdb_store.hpp"
#include "store/method.hpp"

namespace shadowtiles {

struct TopLevelBlob {
  store::Method method;
  std::vector<uint8_t> blob;  // store/blob.hpp container
};

// `roots`: tiles_per_side² intervals, row-major (x fastest); tiles never stored are misses.
Result<std::vector<TopLevelBlob>> encode_top_levels(const std::vector<store::Method>& methods, uint32_t tiles_per_side,
                                                    std::vector<DepthInterval> roots, unsigned tile_level,
                                                    int zstd_level);

}  // namespace shadowtiles
