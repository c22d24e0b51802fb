#include "builder/cpvs_encoder.hpp"

namespace shadowtiles {

bool cpvs_encoder_available() { return false; }

Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals&, uint32_t) {
  return make_error(ErrorCode::unsupported, "the CPVS encoder is not built yet");
}

}  // namespace shadowtiles
