// The first step of ShadowMap::query_batch (client/shadow_batch.cpp), shared by its two paths:
// points to light space, each point's texel key (client/batch_texel_keys.hpp; off the map:
// kOffMapKey) and biased depth, a block of points at a time. Per block, the transform runs first
// (a loop without a branch, which the compiler vectorises), then the keys (one loop per key layout,
// so the layout is not tested per point). One loop doing all of it per point cost a quarter more
// (fzk_haus 16384², 1M points: 8.7 -> 6.9 ms).
// Thread safety: const member functions only; each caller walks its own range.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "client/batch_texel_keys.hpp"
#include "codec/light_frame.hpp"

namespace shadowtiles {

class BatchPointBlocks {
 public:
  static constexpr size_t kBlock = 64;

  // resolution: the map's texels per side; bias_depth: the query bias in light-space depth.
  BatchPointBlocks(const LightFrame& frame, BatchTexelKeys keys, double resolution, double bias_depth)
      : frame_(frame), keys_(keys), resolution_(resolution), bias_depth_(bias_depth) {}

  // Calls fn(first, count, keys, thresholds) for each block of points[first, end) in order:
  // keys[j] and thresholds[j] belong to points[first + j] (off the map: kOffMapKey and 0). Returns
  // false, after the blocks before it, at the first block holding a point with a coordinate that is
  // not finite.
  template <class Fn>
  bool for_each(std::span<const Vec3> points, size_t first, size_t end, Fn&& fn) const {
    // Locals, not members: the caller's stores (histograms, items) could alias members, which
    // would then be reloaded per point.
    const LightFrame frame = frame_;
    const double res = resolution_, bias = bias_depth_;
    double block_u[kBlock], block_v[kBlock], block_depth[kBlock];
    uint64_t block_key[kBlock];
    float block_threshold[kBlock];
    for (; first < end; first += kBlock) {
      const size_t count = std::min(kBlock, end - first);
      const Vec3* const block_points = points.data() + first;
      for (size_t j = 0; j < count; ++j) {
        const LightSpacePoint light = frame.to_light(block_points[j]);
        block_u[j] = light.u;
        block_v[j] = light.v;
        block_depth[j] = light.depth;
      }
      size_t off_map = 0;
      auto keys_of_block = [&](auto make_key) {
        for (size_t j = 0; j < count; ++j) {
          const double u = block_u[j], v = block_v[j];
          const bool on_map = u >= 0 && u < res && v >= 0 && v < res;
          off_map += !on_map;
          const uint64_t key = make_key(on_map ? uint32_t(u) : 0u, on_map ? uint32_t(v) : 0u);
          block_key[j] = on_map ? key : BatchTexelKeys::kOffMapKey;
          // ShadowMap::biased_depth(), the bias hoisted.
          block_threshold[j] = on_map ? float(std::min(block_depth[j], 1.0) - bias) : 0.0f;
        }
      };
      if (keys_.packed())
        keys_of_block([](uint32_t u, uint32_t v) { return BatchTexelKeys::make_packed(u, v); });
      else
        keys_of_block([](uint32_t u, uint32_t v) { return BatchTexelKeys::make_wide(u, v); });
      // A coordinate that is not finite makes u not finite (every axis term adds it, and inf * 0
      // is NaN), so such points are all off the map: checked only there.
      for (size_t j = 0; off_map > 0 && j < count; ++j) {
        const Vec3& p = block_points[j];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return false;
      }
      fn(first, count, static_cast<const uint64_t*>(block_key), static_cast<const float*>(block_threshold));
    }
    return true;
  }

 private:
  LightFrame frame_;
  BatchTexelKeys keys_;
  double resolution_, bias_depth_;
};

}  // namespace shadowtiles
