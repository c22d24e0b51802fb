#include <spdlog/spdlog.h>

#include "builder/accuracy.hpp"
#include "builder/solid_interior.hpp"
#include "bench/harness/stability_scenarios.hpp"

namespace shadowtiles::bench {

void ScenarioResult::check(const std::string& name, bool ok, const std::string& detail) {
  checks.push_back({name, ok, detail});
  if (!ok) spdlog::warn("  check failed: {}: {}", name, detail);
}

bool ScenarioResult::passed() const {
  for (const StabilityCheck& c : checks)
    if (!c.passed) return false;
  return true;
}

StabilityContext::StabilityContext(StabilityOptions options) : options_(std::move(options)) {}

Status StabilityContext::init() {
  auto device = EmbreeDevice::create();
  if (!device) return device.error();
  device_ = std::make_unique<EmbreeDevice>(std::move(*device));
  std::error_code ec;
  std::filesystem::create_directories(options_.work_dir, ec);
  if (ec) return make_error(ErrorCode::io_error, "cannot create " + options_.work_dir.string() + ": " + ec.message());
  return {};
}

Result<const StabilityContext::LoadedScene*> StabilityContext::scene(const std::filesystem::path& file,
                                                                     const LoadOptions& load) {
  std::string key = file.string();
  for (const std::string& h : load.heightfield_meshes) key += "|" + h;
  auto found = scenes_.find(key);
  if (found != scenes_.end()) return found->second.get();
  auto loaded = load_scene(file, load);
  if (!loaded) return loaded.error();
  auto entry = std::make_unique<LoadedScene>();
  entry->file = file;
  entry->load = load;
  entry->scene = std::move(*loaded);
  entry->receivers = sample_receivers(entry->scene, options_.receivers, options_.seed);
  const LoadedScene* pointer = entry.get();
  scenes_[key] = std::move(entry);
  return pointer;
}

Result<const StabilityContext::LoadedScene*> StabilityContext::shared_scene(const std::string& relative, UpAxis up,
                                                                            bool heightfield) {
  LoadOptions load;
  load.up = up;
  if (heightfield) load.heightfield_meshes = {"*"};
  return scene(scene_file(relative), load);
}

Result<std::vector<StabilityRow>> StabilityContext::measure(const LoadedScene& scene, MeasureSpec spec) {
  spec.scene_file = scene.file;
  spec.load = scene.load;
  // Receivers inside solids are no receivers under either contract (builder/solid_interior.hpp).
  std::vector<Receiver> receivers = scene.receivers;
  drop_receivers_inside_solids(*device_, scene.scene, spec.light, receivers);
  GroundTruth truth(*device_, scene.scene, spec.light);
  const std::vector<uint8_t> lit = point_truth(truth, receivers);
  return measure_build(spec, receivers, lit, options_.work_dir);
}

Status StabilityContext::measure_into(const LoadedScene& scene, const MeasureSpec& spec, ScenarioResult& result) {
  auto rows = measure(scene, spec);
  if (!rows) return rows.error();
  for (StabilityRow& r : *rows) result.rows.push_back(std::move(r));
  return {};
}

MeasureSpec sun_spec(const std::string& subject, uint32_t resolution, double azimuth, double elevation, UpAxis up) {
  MeasureSpec spec;
  spec.subject = subject;
  spec.light = *light_direction_from_sun(azimuth, elevation, up);
  spec.resolution = resolution;
  return spec;
}

const std::vector<ScenarioEntry>& all_scenarios() {
  static const std::vector<ScenarioEntry> entries{
      {"open_geometry", run_open_geometry},       {"thin_walls", run_thin_walls},
      {"grazing_sun", run_grazing_sun},           {"tile_seams", run_tile_seams},
      {"precision", run_precision},               {"resolution_sweep", run_resolution_sweep},
      {"degenerate_input", run_degenerate_input}, {"hash_collisions", run_hash_collisions},
      {"surfaces_contract", run_surfaces_contract},
  };
  return entries;
}

}  // namespace shadowtiles::bench
