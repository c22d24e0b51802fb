// Exhaustive losslessness check of a decoded MH/MMH tile against the intervals it was built from
// (docs/architecture.md §5 invariant): every texel's full-resolution lookup must lie in [lower, upper]. Used by
// the tests and by `shadowtiles verify`.
// Errors: invalid_input when sizes differ; corrupt_data when any texel is outside its interval (the
// message gives the count and the first offender). The report, when given, is filled either way.
// Thread safety: reads only; safe to run concurrently on the same view.
#pragma once

#include <cstdint>

#include "builder/depth_interval.hpp"
#include "codec/mh_decoder.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct MhVerifyReport {
  uint64_t texels = 0;
  uint64_t violations = 0;
  // First violation (row-major order), valid when violations > 0.
  uint32_t first_u = 0, first_v = 0;
  float first_value = 0;
  DepthInterval first_interval;
};

Status verify_lossless(const TileIntervals& tile, const MhTileView& view, MhVerifyReport* report = nullptr);

}  // namespace shadowtiles
