// The second-layer cap pass's pair enumeration (builder/second_layer_caps.cpp): every pair of
// triangles whose footprint boxes overlap, found through a uniform grid over the tile, one pair at a
// time. Header-only: the visitor is inlined into the pass.
// Thread safety: a scratch per thread.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "builder/receiver_surface_caps.hpp"  // TexelWindow

namespace shadowtiles {

namespace overlapping_box_pairs {
struct Box {
  double lo_u, hi_u, lo_v, hi_v;
  uint32_t x0, x1, y0, y1;  // the grid cells it touches
};
// A box as a cell lists it: copied into the cell's run, so the cell's pair loop reads its boxes in
// order rather than through an index each.
struct CellBox {
  double lo_u, hi_u, lo_v, hi_v;
  uint32_t k;       // index in `candidates`
  uint32_t x0, y0;  // its first cell: a pair is visited in the cell of max(x0), max(y0)
};
// The same box in floats as {lo_u, -hi_u, lo_v, -hi_v}: a prefilter, in one four-wide comparison
// against the other box's {hi_u, -lo_u, hi_v, -lo_v} (a cell's run is tested box against box: 254
// million tests on honolulu 16384^2 for 22 million pairs, 11 % of them overlapping). Rounding to
// float is monotone, so x <= y gives float(x) <= float(y): every pair the exact test keeps passes.
struct alignas(16) CellBoxFloats {
  float at[4];
};
// Whether the float boxes may overlap (`b` as stored, `a_reach` as {hi_u, -lo_u, hi_v, -lo_v}).
inline bool may_overlap(const CellBoxFloats& b, const CellBoxFloats& a_reach) {
#if defined(__SSE2__)
  return _mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(b.at), _mm_load_ps(a_reach.at))) == 0xF;
#else
  return (b.at[0] <= a_reach.at[0]) & (b.at[1] <= a_reach.at[1]) & (b.at[2] <= a_reach.at[2]) &
         (b.at[3] <= a_reach.at[3]);
#endif
}

}  // namespace overlapping_box_pairs

// Buffers kept between tiles (their capacity is reused).
struct OverlappingBoxPairsScratch {
  std::vector<overlapping_box_pairs::Box> boxes;
  std::vector<uint32_t> offsets, fill;  // the grid's cells
  std::vector<overlapping_box_pairs::CellBox> entries;
  std::vector<overlapping_box_pairs::CellBoxFloats> entry_floats;  // beside `entries`
};

// Calls visit(i, j) once for every pair of `candidates` (indices into `prepared`, whose entries have
// lo_u, hi_u, lo_v, hi_v in global texels) whose footprint boxes, padded by 1/256 texel for
// rounding, overlap. A uniform grid over the tile lists each box in the cells it touches; a pair
// is visited in the one cell holding the corner (max lo_u, max lo_v) of the boxes' overlap. Pairs
// are handled as they are found (no list of them: tens of millions on a city tile), on this thread.
template <class Footprint, class Visit>
void for_each_overlapping_pair(OverlappingBoxPairsScratch& scratch, const std::vector<Footprint>& prepared,
                               const std::vector<uint32_t>& candidates,
                               const TexelWindow& window, Visit visit) {
  using overlapping_box_pairs::Box, overlapping_box_pairs::CellBox, overlapping_box_pairs::CellBoxFloats;
  if (candidates.size() < 2) return;
  constexpr double kPad = 1.0 / 256;
  std::vector<Box>& boxes = scratch.boxes;
  boxes.resize(candidates.size());
  double extent = 0;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Footprint& t = prepared[candidates[k]];
    const double u = window.u0, v = window.v0;
    boxes[k] = {t.lo_u - u - kPad, t.hi_u - u + kPad, t.lo_v - v - kPad, t.hi_v - v + kPad, 0, 0, 0, 0};
    extent += std::min(boxes[k].hi_u - boxes[k].lo_u, double(window.size)) +
              std::min(boxes[k].hi_v - boxes[k].lo_v, double(window.size));
  }
  // Cells about twice the mean box side: each box touches a few cells, each cell holds few boxes.
  // A power of two of texels, 4 to 256 where triangles are a texel or more across. Below that the
  // cells go finer, down to 1/64 texel and at most kFineCells a side, since a dense mesh on a coarse
  // map crowds them (oahu's 490k triangles on one 64^2 tile put ~2,000 boxes in each 4-texel cell:
  // ~460 million box tests, 17 s), but coarser again while the boxes would make more than
  // kEntriesPerBox entries each (a few huge ground triangles over a fine grid).
  const size_t n = candidates.size();
  const double mean_side = extent / (2.0 * double(n));
  // Cells a side for cells of `size` texels, and the cell of coordinate `at` (clamped: boxes reach
  // past the tile); the estimate below and the lists share them.
  auto cells_for = [&](double size) { return uint32_t(std::max(1.0, std::ceil(double(window.size) / size))); };
  auto index_of = [](double at, double size, uint32_t cells) {
    return uint32_t(std::clamp(std::floor(at / size), 0.0, double(cells - 1)));
  };
  double cell;
  if (2 * mean_side >= 2) {
    cell = double(std::clamp(std::bit_ceil(uint32_t(std::ceil(2 * mean_side))), 4u, 256u));
  } else {
    constexpr double kFineCells = 1024;
    constexpr size_t kEntriesPerBox = 8;
    // (Tiles over 4096 texels wide never reach below 4 texels: kFineCells bounds them first.)
    const double finest = std::min(4.0, std::max(1.0 / 64, double(window.size) / kFineCells));
    cell = std::clamp(std::exp2(std::ceil(std::log2(std::max(2 * mean_side, 1.0 / 64)))), finest, 4.0);
    auto entries_at = [&](double size) {  // as the lists below will hold them
      const uint32_t side = cells_for(size);
      size_t total = 0;
      for (const Box& b : boxes)
        total += size_t(index_of(b.hi_u, size, side) - index_of(b.lo_u, size, side) + 1) *
                 (index_of(b.hi_v, size, side) - index_of(b.lo_v, size, side) + 1);
      return total;
    };
    while (cell < 4 && entries_at(cell) > kEntriesPerBox * n) cell *= 2;
  }
  const uint32_t cells = cells_for(cell);
  auto cell_of = [&](double at) { return index_of(at, cell, cells); };
  // The cells' lists, packed (counts, then offsets, then entries).
  std::vector<uint32_t>& offsets = scratch.offsets;
  offsets.assign(size_t(cells) * cells + 1, 0);
  for (Box& box : boxes) {
    box.x0 = cell_of(box.lo_u), box.x1 = cell_of(box.hi_u), box.y0 = cell_of(box.lo_v), box.y1 = cell_of(box.hi_v);
    for (uint32_t y = box.y0; y <= box.y1; ++y)
      for (uint32_t x = box.x0; x <= box.x1; ++x) ++offsets[size_t(y) * cells + x + 1];
  }
  for (size_t c = 1; c < offsets.size(); ++c) offsets[c] += offsets[c - 1];
  std::vector<CellBox>& entries = scratch.entries;
  entries.resize(offsets.back());
  std::vector<CellBoxFloats>& floats = scratch.entry_floats;
  floats.resize(offsets.back());
  std::vector<uint32_t>& fill = scratch.fill;
  fill.assign(offsets.begin(), offsets.end() - 1);
  for (uint32_t k = 0; k < boxes.size(); ++k) {
    const Box& b = boxes[k];
    const CellBox entry{b.lo_u, b.hi_u, b.lo_v, b.hi_v, k, b.x0, b.y0};
    const CellBoxFloats entry_floats{{float(b.lo_u), -float(b.hi_u), float(b.lo_v), -float(b.hi_v)}};
    for (uint32_t y = b.y0; y <= b.y1; ++y)
      for (uint32_t x = b.x0; x <= b.x1; ++x) {
        const uint32_t at = fill[size_t(y) * cells + x]++;
        entries[at] = entry, floats[at] = entry_floats;
      }
  }
  for (uint32_t y = 0; y < cells; ++y)
    for (uint32_t x = 0; x < cells; ++x) {
      const size_t c = size_t(y) * cells + x;
      const size_t end = offsets[c + 1];
      for (size_t a = offsets[c]; a < end; ++a) {
        const CellBox box = entries[a];  // a copy: visit() may write memory the compiler cannot rule out
        const CellBoxFloats reach{{-floats[a].at[1], -floats[a].at[0], -floats[a].at[3], -floats[a].at[2]}};
        for (size_t j = a + 1; j < end; ++j) {
          if (!overlapping_box_pairs::may_overlap(floats[j], reach)) continue;
          const CellBox* const b = &entries[j];
          if (box.lo_u > b->hi_u || b->lo_u > box.hi_u || box.lo_v > b->hi_v || b->lo_v > box.hi_v) continue;
          if (std::max(box.x0, b->x0) != x || std::max(box.y0, b->y0) != y) continue;  // cell_of is monotone
          visit(candidates[box.k], candidates[b->k]);
        }
      }
    }
}

}  // namespace shadowtiles
