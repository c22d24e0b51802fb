// Fuzz target: one method's tile decoder (codec/decoded_tile.hpp), compiled once per method with
// FUZZ_METHOD set (fuzz/CMakeLists.txt). The input is the payload inside the blob, so the fuzzer
// works on the decoder itself, not on the checksum in front of it.
// A payload the decoder accepts is then queried the ways the server and clients do (points at
// every level, PCF boxes, Morton-sorted batches), and the answers must agree with each other:
// lit() with the value (depth-map methods), sample() with value() (depth maps) or with its own proven
// bound (CPVS: threshold <= value iff lit) and with lit(), lit_count() with the
// per-texel lit(), lit_sorted() with lit(). Values must be finite where the format promises it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "codec/decoded_tile.hpp"
#include "fuzz/fuzz_check.hpp"

using namespace shadowtiles;

namespace {

// Query positions derived from the input bytes (deterministic per input).
struct Mixer {
  uint64_t state;
  uint32_t next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return uint32_t(state >> 33);
  }
};

uint64_t seed_of(const uint8_t* data, size_t size) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < size; i += std::max<size_t>(1, size / 64)) h = (h ^ data[i]) * 1099511628211ull;
  return h ^ size;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const store::Method method = store::Method::FUZZ_METHOD;
  auto tile = decode_tile(method, std::span<const uint8_t>(data, size));
  if (!tile) {
    FUZZ_CHECK(tile.error().code == ErrorCode::corrupt_data || tile.error().code == ErrorCode::unsupported);
    FUZZ_CHECK(!tile.error().message.empty());
    return 0;
  }
  const DecodedTile& t = **tile;
  const uint32_t n = t.size();
  FUZZ_CHECK(n >= 1 && (n & (n - 1)) == 0);
  const bool depth_map = !store::method_properties(method).stores_visibility;  // CPVS: visibility, not one depth
  Mixer mix{seed_of(data, size)};

  std::vector<TexelQuery> queries;
  for (int i = 0; i < 48; ++i) {
    const uint32_t u = mix.next() % n, v = mix.next() % n;
    const float value = t.value(u, v);
    if (depth_map) FUZZ_CHECK(!std::isnan(value));
    // Thresholds around the value, and a few arbitrary ones.
    const float threshold = (i % 3 == 0) ? value : (i % 3 == 1) ? std::nextafter(value, INFINITY)
                                                                : float(int32_t(mix.next())) / 65536.0f;
    const bool lit = t.lit(u, v, threshold);
    if (depth_map && !std::isnan(threshold)) FUZZ_CHECK(lit == (threshold <= value));
    const DecodedTile::Sample s = t.sample(u, v, threshold);
    FUZZ_CHECK(s.lit == lit);
    if (depth_map) {
      FUZZ_CHECK(s.value == value || (std::isnan(s.value) && std::isnan(value)));
    } else if (!std::isnan(threshold)) {
      // Visibility methods: the sample's value is the bound its answer proves (codec/cpvs_decoder.hpp).
      FUZZ_CHECK(!std::isnan(s.value) && (threshold <= s.value) == s.lit);
    }
    for (unsigned level = 0; level < 16; level += 5) (void)t.value(u, v, level);
    queries.push_back({u, v, threshold});
  }
  // Morton order inside the tile, as ShadowMap::query_batch sorts them.
  auto morton = [](uint32_t u, uint32_t v) {
    uint64_t key = 0;
    for (int b = 0; b < 16; ++b) key |= uint64_t((u >> b) & 1) << (2 * b) | uint64_t((v >> b) & 1) << (2 * b + 1);
    return key;
  };
  std::sort(queries.begin(), queries.end(),
            [&](const TexelQuery& a, const TexelQuery& b) { return morton(a.u, a.v) < morton(b.u, b.v); });
  std::vector<uint8_t> lit(queries.size(), 2);
  t.lit_sorted(queries, 255, lit.data());
  for (size_t i = 0; i < queries.size(); ++i)
    FUZZ_CHECK(lit[i] == uint8_t(t.lit(queries[i].u, queries[i].v, queries[i].threshold)));

  for (int i = 0; i < 4; ++i) {
    const uint32_t kw = 1 + mix.next() % std::min<uint32_t>(n, 7), kh = 1 + mix.next() % std::min<uint32_t>(n, 7);
    const uint32_t u0 = mix.next() % (n - kw + 1), v0 = mix.next() % (n - kh + 1);
    const float threshold = t.value(u0 + kw / 2, v0 + kh / 2);
    uint32_t expected = 0;
    for (uint32_t v = v0; v < v0 + kh; ++v)
      for (uint32_t u = u0; u < u0 + kw; ++u) expected += t.lit(u, v, threshold);
    FUZZ_CHECK(t.lit_count(u0, v0, kw, kh, threshold) == expected);
  }
  (void)t.memory_bytes();
  (void)t.size_breakdown();
  return 0;
}
