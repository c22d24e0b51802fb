// Request parsing for the shadow query API (docs/architecture.md §10): query-string parameters, JSON batch
// bodies and binary batch bodies (little-endian float32 x, y, z triples) → points and options.
// Independent of the HTTP library so it can be tested on its own.
//
// Strict by design: a missing, duplicated, unknown, empty or non-numeric parameter, NaN or infinity,
// a PCF kernel that is even, zero or above the configured maximum, a JSON value of the wrong type or
// a binary body whose length is not a multiple of 12 is an invalid_input error whose message says
// what was wrong (sent to the client as a 400). Semantic checks that need the store (method present,
// level in range) are left to the caller and ShadowMap.
// Thread safety: pure functions. Safe on untrusted input: no exceptions escape, nothing is read out
// of bounds, allocations are bounded by the input's size.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "codec/light_frame.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::server {

// Query-string parameters as the HTTP layer hands them over (httplib::Params has this type).
using Params = std::multimap<std::string, std::string>;

// Options shared by single and batch queries.
struct QueryOptions {
  std::optional<store::Method> method;  // absent: the store's default method
  unsigned pcf = 0;                     // 0: point query; else odd k x k PCF kernel
  std::optional<unsigned> level;        // level of detail (ShadowMap::query); absent: finest
  std::optional<double> bias;           // world units, finite and >= 0; absent: the build's
};

// A finite decimal number, the whole text (no spaces, no trailing bytes).
Result<double> parse_finite_number(std::string_view text, std::string_view name);
// A decimal unsigned integer <= max, the whole text.
Result<uint64_t> parse_unsigned(std::string_view text, std::string_view name, uint64_t max);

// pcf / method / level / bias from the query string; any other parameter must be listed in
// `extra_allowed`, else invalid_input (a typo such as "pfc=3" must not silently mean "no PCF").
Result<QueryOptions> options_from_params(const Params& params, unsigned max_pcf,
                                         std::span<const std::string_view> extra_allowed = {});
// x, y, z from the query string (each exactly once, finite).
Result<Vec3> point_from_params(const Params& params);

// pcf / method / level / bias from a JSON object of scalars (a batch body without "points");
// other keys are refused.
Result<QueryOptions> options_from_json(const nlohmann::json& options, unsigned max_pcf);

struct JsonBatch {
  std::vector<Vec3> points;
  QueryOptions options;
};
// A JSON batch body {"points": [[x, y, z], ...], "pcf": k, "method": ..., "level": ..., "bias": ...}.
// Parsed as a stream (SAX) straight into points, so memory is bounded by the point count and deep
// nesting is refused instead of recursed into. More than `max_points` points → out_of_space (the
// HTTP layer answers 413); anything malformed → invalid_input.
Result<JsonBatch> parse_json_batch(std::string_view body, unsigned max_pcf, uint64_t max_points);

// Little-endian float32 triples; the length must be a multiple of 12 bytes and every value finite.
Result<std::vector<Vec3>> points_from_binary(std::span<const uint8_t> body);

}  // namespace shadowtiles::server
