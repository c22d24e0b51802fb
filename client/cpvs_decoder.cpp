#include "client/cpvs_decoder.hpp"

namespace shadowtiles {

Result<std::shared_ptr<const DecodedTile>> decode_cpvs_tile(std::span<const uint8_t>) {
  return make_error(ErrorCode::unsupported, "the CPVS decoder is not built yet");
}

}  // namespace shadowtiles
