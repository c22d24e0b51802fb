#include "builder/sst_encoder.hpp"

namespace shadowtiles {

bool sst_encoder_available() { return false; }

Result<std::vector<uint8_t>> encode_sst_tile(const TileIntervals&) {
  return make_error(ErrorCode::unsupported, "the SST encoder is not built yet");
}

}  // namespace shadowtiles
