// A JSON integer read without nlohmann's silent conversions: get<T>() turns a float into an integer
// by a cast (undefined behaviour past T's range; UBSan found it in the store's meta) and a wider
// integer by truncation. The store's meta (codec/store_meta.cpp) and the server's config
// (server/server_config.cpp) read their integer fields through this.
#pragma once

#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

namespace shadowtiles {

// The value when it is a JSON integer in [lo, hi]; nullopt for a float, a string, anything else, or
// an integer outside the range.
template <class T>
std::optional<T> json_integer_in(const nlohmann::json& value, T lo, T hi) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>);
  auto in_range = [&](auto v) -> std::optional<T> {
    if (std::cmp_less(v, lo) || std::cmp_greater(v, hi)) return std::nullopt;
    return T(v);
  };
  if (value.is_number_unsigned()) return in_range(value.get<uint64_t>());
  if (value.is_number_integer()) return in_range(value.get<int64_t>());
  return std::nullopt;
}

}  // namespace shadowtiles
