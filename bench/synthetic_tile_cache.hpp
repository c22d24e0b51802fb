// The synthetic tiles the microbenchmarks run on (builder/mh_synthetic), indexed by the benchmark's
// first argument, built once per (kind, size) and shared by every benchmark of the executable.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include "builder/mh_synthetic.hpp"

namespace shadowtiles::bench {

inline constexpr MhSyntheticKind kSyntheticKinds[] = {MhSyntheticKind::steps, MhSyntheticKind::closed_plane,
                                                      MhSyntheticKind::noisy_plane, MhSyntheticKind::random_intervals};

inline const TileIntervals& cached_synthetic_tile(int kind, uint32_t size) {
  static std::mutex mutex;
  static std::map<std::pair<int, uint32_t>, std::unique_ptr<TileIntervals>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[{kind, size}];
  if (!slot) slot = std::make_unique<TileIntervals>(make_synthetic_tile(kSyntheticKinds[kind], size, 42));
  return *slot;
}

}  // namespace shadowtiles::bench
