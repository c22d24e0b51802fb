#include "builder/store_verifier.hpp"

#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include "builder/dual_depth_renderer.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/nearly_closed_meshes.hpp"
#include "builder/reference_caps.hpp"
#include "builder/reference_entry_bounds.hpp"
#include "builder/second_layer_rule.hpp"
#include "codec/cpvs_format.hpp"

namespace shadowtiles {
namespace {

// `ulps`: how many float steps above a capped upper bound a value may lie (the brute-force caps and
// the build's fast caps round differently; see kCapUlps).
void check_tile(const TileIntervals& intervals, const DecodedTile* tile, TileCoord coord, unsigned ulps,
                MethodVerification& out) {
  ++out.tiles;
  for (uint32_t v = 0; v < intervals.size; ++v)
    for (uint32_t u = 0; u < intervals.size; ++u) {
      DepthInterval interval = intervals.at(u, v);
      for (unsigned k = 0; k < ulps && std::isfinite(interval.upper) && interval.upper > interval.lower; ++k)
        interval.upper = std::nextafter(interval.upper, 2.0f);
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
  const StoreMeta& meta = map.meta();
  // Nearly closed meshes are solids when the store says so: the scene is closed here with the store's
  // parameters unless the caller loaded it closed already.
  std::optional<Scene> closed_copy;
  if (meta.nearly_closed && !scene.nearly_closed_tested) {
    closed_copy = scene;
    close_nearly_closed_meshes(*closed_copy, nearly_closed_options(meta));
  } else if (!meta.nearly_closed && !scene.patch_triangles.empty()) {
    return make_error(ErrorCode::invalid_input,
                      "the scene was loaded with nearly closed meshes accepted as solids; the store was built without");
  }
  const Scene& solids = closed_copy ? *closed_copy : scene;
  auto device = EmbreeDevice::create();
  if (!device) return device.error();
  LightSpaceScene light_scene(solids, map.frame(), map.layout());
  DualDepthOptions options;
  options.exit_margin = float(map.frame().depth_from_world(meta.exit_margin));
  options.receivers = meta.receivers;
  options.cap_exits_at_receiver_surfaces = meta.exit_caps;
  const double coplanar_epsilon = second_layer::coplanar_epsilon(map.frame().depth_from_world(meta.default_bias));
  options.coplanar_epsilon = float(coplanar_epsilon);
  DualDepthRenderer renderer(*device, light_scene, options);
  // The build rounds its fast caps to float after exact clipping in another order than the
  // reference: a value may sit a float step or two above the reference's bound (~1e-7 of the depth
  // range, far inside the exit margin less the bias that receivers rely on).
  const unsigned cap_ulps = meta.exit_caps ? kCapUlps : 0;
  const double entry_slack = map.frame().depth_from_world(meta.entry_slack);
  const double entry_tolerance = entry_tolerance_depth(map.frame(), meta.scene_bounds);

  std::vector<TileCoord> tiles;
  for (uint64_t i = 0; i < map.layout().tile_count(); ++i) tiles.push_back(TileLayout::from_morton_index(i));

  const uint32_t cpvs_steps = cpvs::depth_steps_for(map.layout().resolution(), map.layout().tile_size());
  VerifyReport report;
  report.receivers = meta.receivers;
  report.exit_caps = meta.exit_caps;
  report.entry_slack = meta.entry_slack;
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
      // Texel-centre intervals from the ray caster, capped by the brute-force reference (not the
      // build's cap pass) when the store was built with exit caps.
      auto intervals = renderer.render_centre(tiles[i]);
      if (!intervals) {
        std::lock_guard lock(mutex);
        error = intervals.error();
        return;
      }
      ReferenceCapStats cap_stats;
      if (meta.exit_caps)
        apply_reference_caps(light_scene, tiles[i], meta.receivers, coplanar_epsilon, options.exit_margin, *intervals,
                             &cap_stats);
      // With the entry rule, the interval methods' values may lie down to the reference's bound
      // (builder/reference_entry_bounds.hpp); raw and SST still hold the first hit.
      std::optional<TileIntervals> entry_applied;
      if (entry_slack > 0) {
        entry_applied = *intervals;
        entry_applied->entry_lower =
            reference_entry_bounds(light_scene, tiles[i], *intervals, entry_slack, entry_tolerance, options.exit_margin);
        apply_entry_rule(*entry_applied);
      }
      std::map<store::Method, MethodVerification> local;
      for (store::Method m : methods) {
        const TileIntervals& expected = entry_applied && meta.min_query_bias(m) > 0 ? *entry_applied : *intervals;
        auto tile = map.tile(m, tiles[i]);
        if (!tile) {
          std::lock_guard lock(mutex);
          error = tile.error();
          return;
        }
        if (store::method_properties(m).stores_visibility)  // answers, not values
          check_cpvs_tile(expected, tile->get(), tiles[i], cpvs_steps, local[m]);
        else
          check_tile(expected, tile->get(), tiles[i], cap_ulps, local[m]);
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
      report.reference_cap_texels += cap_stats.texels;
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
