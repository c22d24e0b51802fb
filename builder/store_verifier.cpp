#include "builder/store_verifier.hpp"

#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include "builder/dual_depth_renderer.hpp"
#include "builder/light_space_scene.hpp"
#include "codec/cpvs_format.hpp"

namespace shadowtiles {
namespace {

void check_tile(const TileIntervals& intervals, const DecodedTile* tile, TileCoord coord, MethodVerification& out) {
  ++out.tiles;
  for (uint32_t v = 0; v < intervals.size; ++v)
    for (uint32_t u = 0; u < intervals.size; ++u) {
      const DepthInterval& interval = intervals.at(u, v);
      float value = tile ? tile->value(u, v) : std::numeric_limits<float>::infinity();
      ++out.texels;
      if (!interval.contains(value)) {
        if (out.outside++ == 0)
          out.first_violation = "tile " + std::to_string(coord.x) + "," + std::to_string(coord.y) + " texel " +
                                std::to_string(u) + "," + std::to_string(v) + ": value " + std::to_string(value) +
                                " outside [" + std::to_string(interval.lower) + ", " +
                                std::to_string(interval.upper) + "]";
        continue;
      }
      // Depths just outside the interval: in front is lit, behind is shadowed, as for the exact
      // entry depth. (Finite bounds only: a miss has no "behind".)
      float before = std::nextafter(interval.lower, -1.0f);
      if (!(before <= value)) ++out.wrong_answers;
      if (std::isfinite(interval.upper)) {
        float behind = std::nextafter(interval.upper, 2.0f);
        if (behind <= value) ++out.wrong_answers;
      }
    }
}

// CPVS stores visibility per quantised depth step, not a value, and is lossy by that quantisation:
// depths within a step of a bound may go either way. The rule checked (docs/cpvs.md): a receiver
// 1.5 steps in front of `lower` is lit and one 1.5 steps behind a finite `upper` shadowed (when that
// is still in front of the far plane). `outside` stays 0: there is no value to bound.
void check_cpvs_tile(const TileIntervals& intervals, const DecodedTile* tile, TileCoord coord, uint32_t depth_steps,
                     MethodVerification& out) {
  ++out.tiles;
  const float margin = 1.5f / float(depth_steps);
  for (uint32_t v = 0; v < intervals.size; ++v)
    for (uint32_t u = 0; u < intervals.size; ++u) {
      const DepthInterval& interval = intervals.at(u, v);
      ++out.texels;
      const float before = interval.lower - margin, behind = interval.upper + margin;
      bool wrong = tile && !tile->lit(u, v, before);
      if (std::isfinite(interval.upper) && behind < 1.0f) wrong |= !tile || tile->lit(u, v, behind);
      if (wrong && out.wrong_answers++ == 0)
        out.first_violation = "tile " + std::to_string(coord.x) + "," + std::to_string(coord.y) + " texel " +
                              std::to_string(u) + "," + std::to_string(v) + ": cpvs answer more than a step off [" +
                              std::to_string(interval.lower) + ", " + std::to_string(interval.upper) + "]";
    }
}

}  // namespace

Result<VerifyReport> verify_store(const ShadowMap& map, const Scene& scene, const std::vector<store::Method>& methods,
                                  unsigned threads, const std::function<void(uint64_t, uint64_t)>& progress) {
  for (store::Method m : methods)
    if (!map.meta().has_method(m))
      return make_error(ErrorCode::invalid_input, std::string("method '") + store::method_name(m) + "' is not in the store");
  auto device = EmbreeDevice::create();
  if (!device) return device.error();
  LightSpaceScene light_scene(scene, map.frame(), map.layout());
  DualDepthOptions options;
  options.exit_margin = float(map.frame().depth_from_world(map.meta().exit_margin));
  DualDepthRenderer renderer(*device, light_scene, options);

  std::vector<TileCoord> tiles;
  for (uint64_t i = 0; i < map.layout().tile_count(); ++i) tiles.push_back(TileLayout::from_morton_index(i));

  const uint32_t cpvs_steps = cpvs::depth_steps_for(map.layout().resolution(), map.layout().tile_size());
  VerifyReport report;
  for (store::Method m : methods) report.methods[m];
  std::mutex mutex;
  std::optional<Error> error;
  std::atomic<size_t> next{0};
  std::atomic<uint64_t> done{0};
  auto worker = [&] {
    while (true) {
      size_t i = next++;
      if (i >= tiles.size()) return;
      {
        std::lock_guard lock(mutex);
        if (error) return;
      }
      auto intervals = renderer.render(tiles[i]);
      if (!intervals) {
        std::lock_guard lock(mutex);
        error = intervals.error();
        return;
      }
      std::map<store::Method, MethodVerification> local;
      for (store::Method m : methods) {
        auto tile = map.tile(m, tiles[i]);
        if (!tile) {
          std::lock_guard lock(mutex);
          error = tile.error();
          return;
        }
        if (m == store::Method::cpvs)
          check_cpvs_tile(*intervals, tile->get(), tiles[i], cpvs_steps, local[m]);
        else
          check_tile(*intervals, tile->get(), tiles[i], local[m]);
      }
      std::lock_guard lock(mutex);
      for (auto& [m, v] : local) {
        auto& total = report.methods[m];
        if (total.first_violation.empty()) total.first_violation = v.first_violation;
        total.texels += v.texels;
        total.outside += v.outside;
        total.wrong_answers += v.wrong_answers;
        total.tiles += v.tiles;
      }
      ++report.tiles_checked;
      if (progress) progress(++done, tiles.size());
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < std::max(1u, threads); ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (error) return *error;
  return report;
}

}  // namespace shadowtiles
