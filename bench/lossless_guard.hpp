// A guard for the decoder microbenchmarks: before a decoder is timed, a sample of its point
// lookups must lie inside the tile's intervals, or the executable stops with a message. A decoder
// that walks the wrong way can be much faster and would otherwise print good figures (session 44:
// a step that ranked a DAG-MH node's references wrongly read 2-6x faster in bench_dagmh until the
// unit tests failed it).
#pragma once

#include <cstdio>
#include <cstdlib>

#include "builder/depth_interval.hpp"

namespace shadowtiles::bench {

// Every texel of every 13th row and of the last row: lookup(u, v) must lie in tile.at(u, v).
template <class Lookup>
void require_lookups_inside(const TileIntervals& tile, Lookup&& lookup, const char* what) {
  auto check_row = [&](uint32_t v) {
    for (uint32_t u = 0; u < tile.size; ++u) {
      const float value = lookup(u, v);
      const DepthInterval& iv = tile.at(u, v);
      if (!iv.contains(value)) {
        std::fprintf(stderr, "%s: texel (%u, %u) decodes to %.9g outside [%.9g, %.9g]; not timing a wrong decoder\n",
                     what, u, v, double(value), double(iv.lower), double(iv.upper));
        std::exit(1);
      }
    }
  };
  for (uint32_t v = 0; v < tile.size; v += 13) check_row(v);
  if (tile.size > 0) check_row(tile.size - 1);
}

}  // namespace shadowtiles::bench
