// Fuzz target: per-tile preview records (store/tile_preview.hpp), read by the inspector's render
// routes from the `preview` database. Input: one byte naming the expected method (its low bit also
// asks for the blob checksum to be recomputed, so the fuzzer reaches the payload checks), then the
// record blob. Invariant: an accepted preview has P x P values in each of its three planes.
#include <cstdint>
#include <vector>

#include "fuzz/blob_fixup.hpp"
#include "fuzz/fuzz_check.hpp"
#include "store/tile_preview.hpp"

using namespace shadowtiles;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const auto methods = store::all_methods();
  const store::Method expected = methods[(data[0] >> 1) % methods.size()];
  std::vector<uint8_t> blob(data + 1, data + size);
  if (data[0] & 1) fuzzing::fix_blob_checksum(blob);
  auto preview = store::decode_preview(blob, expected);
  if (!preview) {
    FUZZ_CHECK(!preview.error().message.empty());
    return 0;
  }
  const size_t n = size_t(preview->size) * preview->size;
  FUZZ_CHECK(preview->size >= 1 && preview->lower.size() == n && preview->value.size() == n && preview->width.size() == n);
  return 0;
}
