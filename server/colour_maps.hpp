// Colour maps of the inspector's rendered layers (/v1/render) and their legends: perceptually
// uniform viridis for depths, inferno for heat maps (bytes, diff), fixed colours for coverage.
// The page draws its legends from legend_json (/v1/render/legend), so the server is the one
// source of the colours.
// Thread safety: immutable tables, pure functions.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace shadowtiles::server {

using Rgb = std::array<uint8_t, 3>;

enum class ColourMap { viridis, inferno, relief };

// t in [0, 1] (clamped; NaN → 0).
Rgb colour_at(ColourMap map, double t);
// "#rrggbb" stops of the map, evenly spaced over [0, 1], for legends.
std::vector<std::string> colour_stops(ColourMap map);
std::string hex_colour(const Rgb& rgb);

// Coverage categories.
inline constexpr Rgb kCoverageStored{46, 157, 91};
inline constexpr Rgb kCoverageEmpty{70, 76, 90};
inline constexpr Rgb kCoverageMissing{215, 38, 61};
inline constexpr Rgb kCoverageNoPreview{244, 162, 97};
inline constexpr Rgb kCoverageCorrupt{255, 0, 255};

}  // namespace shadowtiles::server
