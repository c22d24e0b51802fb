// PLY's scalar property types (char ... float64): their sizes and kinds, shared by the PLY pre-check
// (builder/mesh_file_prechecks) and the binary triangle reader (builder/ply_triangle_reader).
// Thread safety: pure functions.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <utility>

namespace shadowtiles {

struct PlyScalarType {
  uint8_t bytes = 0;  // 0: not a PLY type
  bool is_signed = false;
  bool is_integer = false;
};

inline PlyScalarType ply_type(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, PlyScalarType>, 16> kTypes{{
      {"char", {1, true, true}},     {"int8", {1, true, true}},     {"uchar", {1, false, true}},
      {"uint8", {1, false, true}},   {"short", {2, true, true}},    {"int16", {2, true, true}},
      {"ushort", {2, false, true}},  {"uint16", {2, false, true}},  {"int", {4, true, true}},
      {"int32", {4, true, true}},    {"uint", {4, false, true}},    {"uint32", {4, false, true}},
      {"float", {4, true, false}},   {"float32", {4, true, false}}, {"double", {8, true, false}},
      {"float64", {8, true, false}},
  }};
  for (const auto& [key, type] : kTypes)
    if (key == name) return type;
  return {};
}

}  // namespace shadowtiles
