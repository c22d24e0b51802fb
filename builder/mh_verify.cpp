#include "builder/mh_verify.hpp"

#include <string>

namespace shadowtiles {

Status verify_lossless(const TileIntervals& tile, const MhTileView& view, MhVerifyReport* report) {
  MhVerifyReport local;
  MhVerifyReport& r = report ? *report : local;
  r = MhVerifyReport{};
  if (tile.size != view.size() || tile.texels.size() != size_t(tile.size) * tile.size)
    return make_error(ErrorCode::invalid_input, "MH verify: tile size " + std::to_string(tile.size) +
                                                    " does not match the payload's " + std::to_string(view.size()));
  for (uint32_t v = 0; v < tile.size; ++v) {
    for (uint32_t u = 0; u < tile.size; ++u) {
      const float value = view.lookup(u, v);
      const DepthInterval& t = tile.at(u, v);
      ++r.texels;
      if (t.contains(value)) continue;
      if (r.violations++ == 0) r.first_u = u, r.first_v = v, r.first_value = value, r.first_interval = t;
    }
  }
  if (r.violations == 0) return Status::success();
  return make_error(ErrorCode::corrupt_data,
                    "MH verify: " + std::to_string(r.violations) + " of " + std::to_string(r.texels) +
                        " texels outside their interval; first (" + std::to_string(r.first_u) + ", " +
                        std::to_string(r.first_v) + "): " + std::to_string(r.first_value) + " not in [" +
                        std::to_string(r.first_interval.lower) + ", " + std::to_string(r.first_interval.upper) + "]");
}

}  // namespace shadowtiles
