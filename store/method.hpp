// Tile encoding methods (docs/architecture.md §14, §15): what a method is, in one table.
// Each method has a byte (in tile keys and blob headers), a name (in URLs, configs, the CLI and the C
// API) and its properties; every per-method decision outside the method's own files asks this table.
// The built-in methods' bytes and names are FORMAT constants: never renumber or rename one, only
// append. Decoders (codec/method_decoders.hpp) and encoders (builder/method_encoders.hpp) are
// tables of their own, keyed by the same byte, because each layer ships as its own library.
// Errors: parse functions return invalid_input for unknown or malformed names and bytes.
// Thread safety: lookups are safe concurrently; register_method() must happen before any concurrent
// use (at start-up or in a test's set-up). Safe on untrusted input.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles::store {

// The byte that names a method. The enumerators are the built-in methods (FORMAT constants); a
// method registered at run time (register_method) takes any other nonzero byte.
enum class Method : uint8_t {
  raw = 1,    // uncompressed [lower, upper] depth texels (baseline)
  mh = 2,     // multiresolution hierarchy
  mmh = 3,    // merged MH
  dagmh = 4,  // DAG-compressed MH
  cpvs = 5,   // baseline
  sst = 6,    // baseline
};

struct MethodProperties {
  // The accuracy reference: what the other methods' answers are compared with (raw). Listed first.
  bool reference = false;
  // A tree of intervals with a root interval per tile, searchable to a level (max_level).
  bool hierarchical = false;
  // Every decoded value lies inside its texel's [lower, upper]: lossless under the store's receiver
  // contract, checked texel by texel by `verify`.
  bool interval_exact = false;
  // The store holds a top tree over the tiles' root intervals with a skip list (`top/<name>`).
  bool has_top_tree = false;
  // Stores visibility, not one depth value per texel (lit() is no comparison with value()):
  // `verify` checks its answers instead of its values.
  bool stores_visibility = false;
};

struct MethodInfo {
  Method id{};
  std::string_view name;      // lowercase, [a-z0-9_], unique
  MethodProperties properties;
  std::string_view lossy_by;  // empty: loses nothing; else what it gives up
  std::string_view doc;       // the method's own page
};

// Every registered method, built-in ones first, in byte order for those.
std::span<const Method> all_methods();

// The method's table entry. Precondition: `method` is registered (every value parse_method,
// method_from_byte or all_methods gives).
const MethodInfo& method_info(Method method);
inline const MethodProperties& method_properties(Method method) { return method_info(method).properties; }

// The method's name ("raw", "mh", "mmh", "dagmh", "cpvs", "sst", ...); FORMAT for built-ins.
// Precondition: `method` is registered.
const char* method_name(Method method);

// Exact, case-sensitive name → method; anything else → invalid_input.
Result<Method> parse_method(std::string_view name);

// Comma-separated names ("raw,mh"); spaces around names are ignored, duplicates are dropped keeping
// first-seen order. An empty list, an empty item or an unknown name → invalid_input.
Result<std::vector<Method>> parse_method_list(std::string_view names);

// A stored method byte → method; bytes no registered method has → invalid_input.
Result<Method> method_from_byte(uint8_t byte);

// Adds a method (an extension, or a test's toy method). The name and strings must outlive the
// process (string literals). Errors: invalid_input for byte 0, a taken byte or name, or a name
// outside [a-z0-9_]{1,32}.
Status register_method(const MethodInfo& info);

}  // namespace shadowtiles::store
