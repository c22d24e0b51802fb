// Tile encoding methods (docs/architecture.md §5–§8): the byte that names how a tile's payload is encoded.
// It appears in tile keys, blob headers and URLs (/v1/tiles/{method}/...), so values and names are
// FORMAT constants: never renumber or rename one, only append.
// Errors: parse functions return invalid_input for unknown or malformed names.
// Thread safety: pure functions. Safe on untrusted input.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles::store {

// FORMAT constants: stored in keys and blob headers.
enum class Method : uint8_t {
  raw = 1,    // uncompressed [lower, upper] depth texels (baseline)
  mh = 2,     // multiresolution hierarchy
  mmh = 3,    // merged MH
  dagmh = 4,  // DAG-compressed MH
  cpvs = 5,   // baseline
  sst = 6,    // baseline
};

// Every method, in numeric order.
std::span<const Method> all_methods();

// Lowercase name ("raw", "mh", "mmh", "dagmh", "cpvs", "sst"); FORMAT (used in URLs and configs).
// Precondition: `method` is one of the enumerators.
const char* method_name(Method method);

// Exact, case-sensitive name → method; anything else → invalid_input.
Result<Method> parse_method(std::string_view name);

// Comma-separated names ("raw,mh"); spaces around names are ignored, duplicates are dropped keeping
// first-seen order. An empty list, an empty item or an unknown name → invalid_input.
Result<std::vector<Method>> parse_method_list(std::string_view names);

// A stored method byte → method; values outside the enum → invalid_input.
Result<Method> method_from_byte(uint8_t byte);

}  // namespace shadowtiles::store
