// The MH and MMH payloads of one synthetic tile, each parsed at a list of skip-list levels: the sweep
// the MH decoder tests run their checks over. Fails the calling test (gtest assertions) when a step
// fails; check ::testing::Test::HasFatalFailure() after it.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"

namespace shadowtiles {

struct MhTileViews {
  struct Entry {
    bool merged;    // MMH (else MH)
    unsigned skip;  // MhParseOptions::skip_level
    MhTileView view;
  };
  std::array<std::vector<uint8_t>, 2> payloads;  // MH, MMH: the views read these bytes
  std::vector<Entry> views;
};

inline void make_mh_tile_views(const TileIntervals& tile, std::initializer_list<unsigned> skips, MhTileViews& out) {
  auto tree = build_mh(tile);
  ASSERT_TRUE(tree.ok());
  auto merged = merge_mmh(*tree);
  ASSERT_TRUE(merged.ok());
  for (int m = 0; m < 2; ++m) {
    auto bytes = encode_mh(m ? *merged : *tree);
    ASSERT_TRUE(bytes.ok());
    out.payloads[m] = std::move(*bytes);
    for (unsigned skip : skips) {
      MhParseOptions options;
      options.skip_level = skip;
      auto view = MhTileView::parse(out.payloads[m], options);
      ASSERT_TRUE(view.ok());
      out.views.push_back({m == 1, skip, *view});
    }
  }
}

}  // namespace shadowtiles
