#include "builder/tile_encoder.hpp"

#include "client/raw_tile.hpp"

namespace shadowtiles {

bool builder_supports(store::Method method) { return method == store::Method::raw; }

Result<std::vector<uint8_t>> encode_tile_payload(store::Method method, const TileIntervals& intervals) {
  switch (method) {
    case store::Method::raw: {
      std::vector<float> lower(intervals.texels.size());
      for (size_t i = 0; i < lower.size(); ++i) lower[i] = intervals.texels[i].lower;
      return encode_raw_tile(intervals.size, lower);
    }
    default:
      return make_error(ErrorCode::unsupported,
                        std::string("method '") + store::method_name(method) + "' is not implemented by this builder");
  }
}

}  // namespace shadowtiles
