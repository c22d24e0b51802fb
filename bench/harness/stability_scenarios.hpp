// The stability scenarios of issue #8: each reproduces a known failure mode of compressed shadow
// maps, measures every method the builder supports on it and checks what must hold. Behind
// `shadowtiles stability` (which turns the results into STABILITY.md); the assertions are also
// GoogleTests (tests/test_stability*.cpp).
//   1 open geometry      open scans and a room with a one-sided roof; the far-plane exit rule compared
//   2 thin walls         closed bust and walls 4, 1, 0.5, 0.1 texels thick
//   3 grazing sun        terrain at sun elevations 2..90 degrees
//   4 tile seams         one tile vs many tiles: identical point and PCF answers, tile borders, corners
//   5 precision          oahu at 2^18 / 2^20 (a window of tiles), 10^6 translation, float32 depth
//   6 resolution sweep   lossless error vs resolution, power of two to power of two
//   7 degenerate input   empty, one triangle, NaN/inf, zero area, edge-on light, zero light, R = 1
//   8 hash collisions    MMH merging with the topology hash cut to a few bits
//   9 surfaces contract  `--receivers surfaces`: open roof, leaf, stacked shells, a mesh with holes, a thin
//                        open wall; nothing leaks beyond raw
// Errors: a scenario returns an error only when it cannot run (missing scene, I/O); what it finds
// goes into its checks. Thread safety: one scenario at a time (builds use their own threads).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench/harness/stability_measure.hpp"
#include "builder/scene_loader.hpp"

namespace shadowtiles::bench {

struct StabilityOptions {
  bool quick = false;                  // smaller resolutions and fewer cases (seconds, not minutes)
  std::filesystem::path scene_root;    // the shared scenes (../shared/scenes)
  std::filesystem::path work_dir;      // stores and synthetic scenes are written here
  size_t receivers = 20000;            // uniform surface receivers per scene
  uint64_t seed = 1;
};

struct StabilityCheck {
  std::string name;
  bool passed = false;
  std::string detail;
};

// A table that is not one accuracy row per method (seams, precision, degenerate input, hashing).
struct StabilityTable {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

struct ScenarioResult {
  ScenarioResult() = default;
  ScenarioResult(std::string id_, std::string title_) : id(std::move(id_)), title(std::move(title_)) {}

  std::string id;     // "open_geometry", ...
  std::string title;
  std::string setup;  // what was run (scenes, light, resolution), for the report
  std::vector<StabilityRow> rows;
  std::vector<StabilityTable> tables;
  std::vector<StabilityCheck> checks;
  std::vector<std::string> notes;  // findings and inherent limits, with figures
  double seconds = 0;

  void check(const std::string& name, bool passed, const std::string& detail);
  bool passed() const;
};

// Loaded scenes and their receivers, shared by the scenarios of one run.
class StabilityContext {
 public:
  explicit StabilityContext(StabilityOptions options);
  const StabilityOptions& options() const { return options_; }
  const EmbreeDevice& device() const { return *device_; }
  std::filesystem::path scene_file(const std::string& relative) const { return options_.scene_root / relative; }

  struct LoadedScene {
    std::filesystem::path file;
    LoadOptions load;
    Scene scene;
    std::vector<Receiver> receivers;
  };
  // Loads (once) and samples options().receivers receivers (seeded).
  Result<const LoadedScene*> scene(const std::filesystem::path& file, const LoadOptions& load);
  // scene() of the shared scene scene_file(relative) with `up`; `heightfield`: every mesh declared
  // one (terrains).
  Result<const LoadedScene*> shared_scene(const std::string& relative, UpAxis up, bool heightfield = false);
  // Builds `spec` and measures every method on the scene's receivers against ground truth.
  Result<std::vector<StabilityRow>> measure(const LoadedScene& scene, MeasureSpec spec);
  // measure(), its rows appended to `result`'s.
  Status measure_into(const LoadedScene& scene, const MeasureSpec& spec, ScenarioResult& result);
  Status init();

 private:
  StabilityOptions options_;
  std::unique_ptr<EmbreeDevice> device_;
  std::map<std::string, std::unique_ptr<LoadedScene>> scenes_;
};

// A spec for `subject` at `resolution`, lit by the sun at (azimuth, elevation) over `up`.
MeasureSpec sun_spec(const std::string& subject, uint32_t resolution, double azimuth, double elevation, UpAxis up);

Result<ScenarioResult> run_open_geometry(StabilityContext& context);
Result<ScenarioResult> run_thin_walls(StabilityContext& context);
Result<ScenarioResult> run_grazing_sun(StabilityContext& context);
Result<ScenarioResult> run_tile_seams(StabilityContext& context);
Result<ScenarioResult> run_precision(StabilityContext& context);
Result<ScenarioResult> run_resolution_sweep(StabilityContext& context);
Result<ScenarioResult> run_degenerate_input(StabilityContext& context);
Result<ScenarioResult> run_hash_collisions(StabilityContext& context);
Result<ScenarioResult> run_surfaces_contract(StabilityContext& context);

struct ScenarioEntry {
  const char* id;
  Result<ScenarioResult> (*run)(StabilityContext&);
};
// Every scenario, in the order.
const std::vector<ScenarioEntry>& all_scenarios();

}  // namespace shadowtiles::bench
