// Fuzz target: the server's request parsing (server/request_parsing.hpp) on its own, without the
// HTTP layer: the first byte picks the parser, the rest is its input.
//   0  JSON batch body                       1  binary batch body (float32 triples)
//   2  a query string ("k=v&k=v", as httplib splits it) for options and a point
//   3  JSON options object                   4  number and unsigned-integer fields
// Invariants: no exception escapes; accepted points are finite; accepted options are in range.
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz/fuzz_check.hpp"
#include "server/request_parsing.hpp"

using namespace shadowtiles;
using namespace shadowtiles::server;

namespace {

constexpr unsigned kMaxPcf = 15;

bool finite(const Vec3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

void check_options(const QueryOptions& o) {
  FUZZ_CHECK(o.pcf == 0 || (o.pcf % 2 == 1 && o.pcf <= kMaxPcf));
  if (o.bias) FUZZ_CHECK(std::isfinite(*o.bias) && *o.bias >= 0);
}

Params split_query(std::string_view text) {
  Params params;
  while (!text.empty()) {
    const size_t amp = text.find('&');
    std::string_view item = text.substr(0, amp);
    const size_t eq = item.find('=');
    if (eq == std::string_view::npos)
      params.emplace(std::string(item), std::string());
    else
      params.emplace(std::string(item.substr(0, eq)), std::string(item.substr(eq + 1)));
    if (amp == std::string_view::npos) break;
    text.remove_prefix(amp + 1);
  }
  return params;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 5) {
    case 0: {
      auto batch = parse_json_batch(text, kMaxPcf, 1000);
      if (!batch) {
        FUZZ_CHECK(batch.error().code == ErrorCode::invalid_input || batch.error().code == ErrorCode::out_of_space);
        break;
      }
      FUZZ_CHECK(batch->points.size() <= 1000);
      for (const Vec3& p : batch->points) FUZZ_CHECK(finite(p));
      check_options(batch->options);
      break;
    }
    case 1: {
      auto points = points_from_binary(std::span<const uint8_t>(data + 1, size - 1));
      if (!points) break;
      FUZZ_CHECK(points->size() * 12 == size - 1);
      for (const Vec3& p : *points) FUZZ_CHECK(finite(p));
      break;
    }
    case 2: {
      const Params params = split_query(text);
      static constexpr std::string_view kExtra[] = {"x", "y", "z"};
      if (auto options = options_from_params(params, kMaxPcf, kExtra)) check_options(*options);
      if (auto point = point_from_params(params)) FUZZ_CHECK(finite(*point));
      break;
    }
    case 3: {
      const nlohmann::json json = nlohmann::json::parse(text, nullptr, false);
      if (json.is_discarded()) break;
      if (auto options = options_from_json(json, kMaxPcf)) check_options(*options);
      break;
    }
    case 4: {
      if (auto number = parse_finite_number(text, "x")) FUZZ_CHECK(std::isfinite(*number));
      if (auto count = parse_unsigned(text, "n", 1000000)) FUZZ_CHECK(*count <= 1000000);
      break;
    }
  }
  return 0;
}
