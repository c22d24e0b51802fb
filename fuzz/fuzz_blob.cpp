// Fuzz target: the blob container (store/blob.hpp), what the server and clients read first from
// disk and the network. A random input almost never has a valid XXH64, which would stop the fuzzer
// at the checksum; so an input whose first byte is odd gets its checksum recomputed before the
// check, and zstd decompression and the size checks behind the checksum are reached too.
// Invariants: a decoded blob has exactly raw_size bytes, and re-encoding it round-trips.
#include <cstdint>
#include <vector>

#include "fuzz/blob_fixup.hpp"
#include "fuzz/fuzz_check.hpp"
#include "store/blob.hpp"

using namespace shadowtiles;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const bool fix_checksum = data[0] & 1;
  std::vector<uint8_t> blob(data + 1, data + size);
  if (fix_checksum) fuzzing::fix_blob_checksum(blob);
  auto checked = store::check_blob(blob);
  store::BlobHeader header{};
  auto decoded = store::decode_blob(blob, &header);
  if (!decoded) return 0;
  FUZZ_CHECK(checked.ok());
  FUZZ_CHECK(decoded->size() == header.raw_size);
  const auto again = store::encode_blob(header.method, *decoded, header.flags);
  auto round = store::decode_blob(again);
  FUZZ_CHECK(round.ok() && *round == *decoded);
  return 0;
}
