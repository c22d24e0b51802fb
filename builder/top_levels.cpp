#include "builder/top_levels.hpp"

#include <algorithm>

#include "builder/method_encoders.hpp"
#include "store/blob.hpp"

namespace shadowtiles {

Result<std::vector<TopLevelBlob>> encode_top_levels(const std::vector<store::Method>& methods, uint32_t tiles_per_side,
                                                    std::vector<DepthInterval> roots, unsigned tile_level,
                                                    int zstd_level) {
  TileIntervals grid;
  grid.size = tiles_per_side;
  grid.texels = std::move(roots);
  std::vector<TopLevelBlob> blobs;
  for (store::Method method : methods) {
    if (!store::method_properties(method).has_top_tree) continue;
    const MethodEncoder* encoder = find_encoder(method);
    if (!encoder || !encoder->encode_top_tree)
      return make_error(ErrorCode::unsupported,
                        std::string("no top-tree encoder for method '") + store::method_name(method) + "'");
    // The skip list reaches at most 6 levels down (or the tile level, when the grid is shallower).
    auto payload = encoder->encode_top_tree(grid, std::min<unsigned>(6, tile_level));
    if (!payload) return payload.error();
    blobs.push_back({method, store::encode_blob(method, *payload, 0, zstd_level)});
  }
  return blobs;
}

}  // namespace shadowtiles
