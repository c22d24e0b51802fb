#include "server/colour_maps.hpp"

#include <cmath>
#include <cstdio>

namespace shadowtiles::server {
namespace {

// Ten evenly spaced samples of matplotlib's viridis and inferno (their published tables).
constexpr std::array<Rgb, 10> kViridis = {{{68, 1, 84}, {72, 40, 120}, {62, 73, 137}, {49, 104, 142},
                                           {38, 130, 142}, {31, 158, 137}, {53, 183, 121}, {110, 206, 88},
                                           {181, 222, 43}, {253, 231, 37}}};
constexpr std::array<Rgb, 10> kInferno = {{{0, 0, 4}, {27, 12, 65}, {74, 12, 107}, {120, 28, 109},
                                           {165, 44, 96}, {207, 68, 70}, {237, 105, 37}, {251, 155, 6},
                                           {247, 209, 61}, {252, 255, 164}}};
// Near (bright, warm) to far (dark, cool): a sunlit-relief ramp for the first-hit depth view.
constexpr std::array<Rgb, 5> kRelief = {{{250, 244, 227}, {214, 201, 164}, {150, 160, 130}, {84, 106, 112},
                                         {40, 52, 70}}};

template <size_t N>
Rgb interpolate(const std::array<Rgb, N>& stops, double t) {
  if (!(t > 0)) t = 0;
  if (t > 1) t = 1;
  double x = t * double(N - 1);
  size_t i = size_t(x);
  if (i >= N - 1) return stops[N - 1];
  double f = x - double(i);
  Rgb out;
  for (int c = 0; c < 3; ++c) out[c] = uint8_t(std::lround(stops[i][c] + f * (stops[i + 1][c] - stops[i][c])));
  return out;
}

template <size_t N>
std::vector<std::string> hex_stops(const std::array<Rgb, N>& stops) {
  std::vector<std::string> out;
  for (const Rgb& s : stops) out.push_back(hex_colour(s));
  return out;
}

}  // namespace

Rgb colour_at(ColourMap map, double t) {
  switch (map) {
    case ColourMap::viridis: return interpolate(kViridis, t);
    case ColourMap::inferno: return interpolate(kInferno, t);
    case ColourMap::relief: return interpolate(kRelief, t);
  }
  return {0, 0, 0};
}

std::vector<std::string> colour_stops(ColourMap map) {
  switch (map) {
    case ColourMap::viridis: return hex_stops(kViridis);
    case ColourMap::inferno: return hex_stops(kInferno);
    case ColourMap::relief: return hex_stops(kRelief);
  }
  return {};
}

std::string hex_colour(const Rgb& rgb) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
  return text;
}

}  // namespace shadowtiles::server
