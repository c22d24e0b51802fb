#include "builder/mh_synthetic.hpp"

#include <algorithm>
#include <limits>
#include <random>

namespace shadowtiles {

const char* synthetic_kind_name(MhSyntheticKind kind) {
  switch (kind) {
    case MhSyntheticKind::random_intervals: return "random_intervals";
    case MhSyntheticKind::noisy_plane: return "noisy_plane";
    case MhSyntheticKind::closed_plane: return "closed_plane";
    case MhSyntheticKind::steps: return "steps";
    case MhSyntheticKind::all_miss: return "all_miss";
    case MhSyntheticKind::boxes_and_misses: return "boxes_and_misses";
  }
  return "unknown";
}

TileIntervals make_synthetic_tile(MhSyntheticKind kind, uint32_t size, uint64_t seed) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  TileIntervals tile;
  tile.size = size;
  tile.texels.assign(size_t(size) * size, DepthInterval{1.0f, kInf});
  const float inv = 1.0f / float(size);
  const float a = 0.3f * unit(rng), b = 0.3f * unit(rng), c = 0.2f + 0.2f * unit(rng);
  auto plane = [&](uint32_t u, uint32_t v) { return c + a * float(u) * inv + b * float(v) * inv; };
  switch (kind) {
    case MhSyntheticKind::random_intervals:
      for (auto& t : tile.texels) {
        const float r = unit(rng);
        if (r < 0.1f) continue;  // miss
        t.lower = unit(rng);
        t.upper = r < 0.4f ? t.lower : t.lower + 0.3f * unit(rng);
      }
      break;
    case MhSyntheticKind::noisy_plane:
    case MhSyntheticKind::closed_plane:
      for (uint32_t v = 0; v < size; ++v)
        for (uint32_t u = 0; u < size; ++u) {
          auto& t = tile.at(u, v);
          t.lower = plane(u, v) + 1e-4f * unit(rng);
          t.upper = kind == MhSyntheticKind::noisy_plane ? t.lower : t.lower + 0.05f + 0.01f * unit(rng);
        }
      break;
    case MhSyntheticKind::steps:
    case MhSyntheticKind::boxes_and_misses: {
      if (kind == MhSyntheticKind::steps)
        for (uint32_t v = 0; v < size; ++v)
          for (uint32_t u = 0; u < size; ++u) tile.at(u, v) = DepthInterval{0.8f + 0.1f * plane(u, v), 1.0f};
      const unsigned boxes = 4 + size / 8;
      for (unsigned k = 0; k < boxes; ++k) {
        const uint32_t w = 1 + uint32_t(unit(rng) * float(std::max(1u, size / 4)));
        const uint32_t hgt = 1 + uint32_t(unit(rng) * float(std::max(1u, size / 4)));
        const uint32_t x0 = uint32_t(unit(rng) * float(size)), y0 = uint32_t(unit(rng) * float(size));
        const float top = 0.1f + 0.5f * unit(rng), bottom = top + 0.05f + 0.3f * unit(rng);
        for (uint32_t v = y0; v < std::min(size, y0 + hgt); ++v)
          for (uint32_t u = x0; u < std::min(size, x0 + w); ++u) {
            auto& t = tile.at(u, v);
            if (top < t.lower) t = DepthInterval{top, std::min(bottom, t.lower)};
          }
      }
      break;
    }
    case MhSyntheticKind::all_miss:
      break;
  }
  return tile;
}

}  // namespace shadowtiles
