#include "client/sst_decoder.hpp"

namespace shadowtiles {

Result<std::shared_ptr<const DecodedTile>> decode_sst_tile(std::span<const uint8_t>) {
  return make_error(ErrorCode::unsupported, "the SST decoder is not built yet");
}

}  // namespace shadowtiles
