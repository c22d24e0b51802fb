#include "builder/top_levels.hpp"

#include <algorithm>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mmh_merger.hpp"
#include "store/blob.hpp"

namespace shadowtiles {

bool is_hierarchical(store::Method method) {
  return method == store::Method::mh || method == store::Method::mmh || method == store::Method::dagmh;
}

Result<std::vector<TopLevelBlob>> encode_top_levels(const std::vector<store::Method>& methods, uint32_t tiles_per_side,
                                                    std::vector<DepthInterval> roots, unsigned tile_level,
                                                    int zstd_level) {
  TileIntervals grid;
  grid.size = tiles_per_side;
  grid.texels = std::move(roots);
  std::vector<TopLevelBlob> blobs;
  for (store::Method method : methods) {
    if (!is_hierarchical(method)) continue;
    auto top = build_mh(grid);
    if (!top) return top.error();
    if (method == store::Method::mmh) {
      auto merged = merge_mmh(*top);
      if (!merged) return merged.error();
      top = std::move(merged);
    }
    Result<std::vector<uint8_t>> payload = std::vector<uint8_t>{};
    if (method == store::Method::dagmh) {
      payload = encode_dagmh(*top);  // its own skip list (DagMhOptions defaults, as the tiles)
    } else {
      MhEncodeOptions top_options;
      top_options.embed_skip_list = true;
      top_options.skip_level = std::min<unsigned>(6, tile_level);
      payload = encode_mh(*top, top_options);
    }
    if (!payload) return payload.error();
    blobs.push_back({method, store::encode_blob(method, *payload, 0, zstd_level)});
  }
  return blobs;
}

}  // namespace shadowtiles
