// TileSource: where a ShadowMap reads a build from — the stored records exactly as the builder wrote
// them (meta JSON, tile blobs, top-tree blobs). The local LMDB store (lmdb_tile_source.hpp) and the
// HTTP client (streaming from `shadowtiles serve`) implement it, so queries answer identically from
// either. Blobs are returned unverified: ShadowMap checks header, checksum and method before
// decoding, whatever the source.
// Thread safety: implementations must allow concurrent calls from several threads.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "store/method.hpp"
#include "common/result.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles {

class TileSource {
 public:
  virtual ~TileSource() = default;
  // The build's meta record (StoreMeta JSON text). Errors: not_found when the source holds no
  // build; io_error (or the transport's error) otherwise.
  virtual Result<std::string> meta_text() const = 0;
  // A tile's stored blob, or nullopt when the build has no record for it (an empty, all-lit tile).
  virtual Result<std::optional<std::vector<uint8_t>>> tile_blob(const store::TileKey& key) const = 0;
  // A method's top-tree blob (root intervals of the tiles with the embedded skip list), or nullopt
  // when the method has none.
  virtual Result<std::optional<std::vector<uint8_t>>> top_blob(store::Method method) const = 0;
  // Where the data comes from, for messages ("store /data/x", "http://host:port").
  virtual std::string describe() const = 0;
};

}  // namespace shadowtiles
