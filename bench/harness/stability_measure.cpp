#include "bench/harness/stability_measure.hpp"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "builder/accuracy.hpp"
#include "builder/tile_encoder.hpp"

namespace shadowtiles::bench {
namespace {

double number_at(const nlohmann::json& stats, const char* group, const std::string& key) {
  if (!stats.contains(group) || !stats[group].contains(key) || !stats[group][key].is_number()) return 0.0;
  return stats[group][key].get<double>();
}

// The build summary's scene.nearly_closed.triangles (builder/build_job.cpp), 0 when absent.
uint64_t nearly_closed_triangles(const nlohmann::json& stats) {
  if (!stats.contains("scene") || !stats["scene"].contains("nearly_closed")) return 0;
  const nlohmann::json& closing = stats["scene"]["nearly_closed"];
  return closing.contains("triangles") && closing["triangles"].is_number() ? closing["triangles"].get<uint64_t>() : 0;
}

}  // namespace


std::vector<store::Method> supported_methods() {
  std::vector<store::Method> methods;
  for (store::Method m : store::all_methods())
    if (builder_supports(m)) methods.push_back(m);
  std::stable_partition(methods.begin(), methods.end(), [](store::Method m) { return store::method_properties(m).reference; });
  return methods;
}

Result<std::vector<StabilityRow>> measure_build(const MeasureSpec& spec, std::span<const Receiver> receivers,
                                                std::span<const uint8_t> truth,
                                                const std::filesystem::path& work_dir) {
  if (truth.size() != receivers.size()) return make_error(ErrorCode::invalid_input, "one truth per receiver");
  const std::filesystem::path store_dir = work_dir / "store";
  std::error_code ec;
  std::filesystem::remove_all(store_dir, ec);
  BuildConfig build;
  build.scene_path = spec.scene_file;
  build.store_path = store_dir;
  build.light_direction = spec.light;
  build.resolution = spec.resolution;
  build.tile_size = std::min(spec.tile_size, spec.resolution);
  build.methods = spec.methods.empty() ? supported_methods() : spec.methods;
  build.load = spec.load;
  build.open_exit_at_far_plane = spec.open_exit_at_far_plane;
  build.close_nearly_closed = spec.close_nearly_closed;
  build.receivers = spec.receivers;
  build.cap_exits_at_receiver_surfaces = true;  // the suite measures `build --exit-caps` (STABILITY.md)
  build.overwrite = true;
  auto summary = run_build(build);
  if (!summary) return summary.error();
  const nlohmann::json& stats = summary->stats;
  const double depth_seconds =
      number_at(stats, "seconds", "bvh_thread_sum") + number_at(stats, "seconds", "rays_thread_sum");

  std::vector<StabilityRow> rows;
  {
    auto map = ShadowMap::open(store_dir);
    if (!map) return map.error();
    std::vector<uint8_t> raw_answers;  // raw is first when present
    for (store::Method method : build.methods) {
      const std::string name = store::method_name(method);
      const bool is_raw = store::method_properties(method).reference;
      auto accuracy = point_accuracy(**map, method, receivers, truth, is_raw ? std::span<const uint8_t>{} : raw_answers,
                                     is_raw ? &raw_answers : nullptr);
      if (!accuracy) return accuracy.error();
      StabilityRow row;
      row.subject = spec.subject;
      row.method = spec.open_exit_at_far_plane ? name + " [far-plane exit]"
                   : spec.close_nearly_closed   ? name + " [nearly closed]"
                                                : name;
      row.resolution = spec.resolution;
      row.elevation = spec.elevation;
      row.receivers = accuracy->receivers;
      row.false_lit = accuracy->false_lit;
      row.false_shadowed = accuracy->false_shadowed;
      row.differs_from_raw = accuracy->differs_from_raw;
      row.worse_than_raw = accuracy->worse_than_raw;
      row.bytes = uint64_t(number_at(stats, "bytes_by_method", name) + number_at(stats, "top_bytes_by_method", name));
      row.build_seconds = depth_seconds + number_at(stats, "encode_seconds_by_method", name);
      if (is_raw || spec.close_nearly_closed)
        row.note = "exit texels " + std::to_string(uint64_t(stats.value("exit_texels", 0.0)));
      if (spec.close_nearly_closed && is_raw)
        row.note += fmt::format(", {} of {} triangles nearly closed", nearly_closed_triangles(stats),
                                uint64_t(number_at(stats, "scene", "triangles")));
      rows.push_back(std::move(row));
    }
  }
  std::filesystem::remove_all(store_dir, ec);
  spdlog::info("  {} {}^2{}: raw false lit {}, built in {:.1f} s", spec.subject, spec.resolution,
               spec.open_exit_at_far_plane ? " [far-plane exit]" : "", rows.empty() ? 0 : rows.front().false_lit,
               number_at(stats, "seconds", "total"));
  return rows;
}

}  // namespace shadowtiles::bench
