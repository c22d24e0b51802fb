// Fuzz target: the store's meta record (codec/store_meta.hpp), JSON read from disk or from a
// server's /v1/meta. Invariants: an accepted record yields a light frame and a layout or a clear
// error, and its own JSON parses back to the same JSON.
#include <cstdint>
#include <string_view>

#include "codec/store_meta.hpp"
#include "fuzz/fuzz_check.hpp"

using namespace shadowtiles;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto meta = StoreMeta::parse(std::string_view(reinterpret_cast<const char*>(data), size));
  if (!meta) {
    FUZZ_CHECK(!meta.error().message.empty());
    return 0;
  }
  (void)meta->light_frame();
  (void)meta->layout();
  const nlohmann::json json = meta->to_json();
  auto again = StoreMeta::from_json(json);
  FUZZ_CHECK(again.ok());
  FUZZ_CHECK(again->to_json() == json);
  return 0;
}
