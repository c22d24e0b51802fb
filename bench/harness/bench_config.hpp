// BenchConfig: what `shadowtiles bench` measures (config/bench-quick.json, config/bench-full.json):
// scenes (file, up axis, sun, heightfield meshes, resolutions), the methods to build, receiver
// counts, PCF kernels, thread counts and timing budget.
//
// JSON schema (every key optional except "scenes"; unknown keys are an error so typos fail fast):
//   scene_root      folder scene files are relative to; relative itself to the config file's folder
//   methods         ["raw", "mh", ...]; raw is always built (it is the accuracy and texel reference)
//   resolutions     [1024, ...] default for every scene (power-of-two map sides)
//   tile_size       tile side in texels (clamped to the map)
//   build_threads   builder worker threads
//   receivers       receivers sampled uniformly over the surfaces (per scene)
//   contract        the stores' receiver contract, "anywhere" (default) or "surfaces"
//                   (docs/receiver-contracts.md); every receiver the bench samples lies on a surface
//   camera          {"width", "height", "azimuth", "elevation", "fov"}: receivers = the visible
//                   pixels of a fixed camera, in screen order; width 0 disables
//   pcf_kernels     [3, 5] odd kernel sides
//   pcf_supersample s: ground-truth PCF traces s x s jittered samples per kernel texel
//   threads         [1, 2] lookup threads
//   min_seconds     every timed lookup loop runs at least this long in all (after a warm-up pass), in 5
//                   rounds whose best rate is reported (bench/harness/lookup_rate.hpp)
//   cache_mib       ShadowMap tile cache budget
//   keep_stores     keep the built stores under OUT/stores (default false: removed when measured)
//   seed            receiver sampling seed
//   batch_points    surface points of the query_batch rows (shuffled; 0 disables them)
//   scenes          [{"name", "file", "up": "y"|"z", "sun": [az, el], "heightfield": ["*"],
//                     "resolutions": [...] (overrides), "receivers": n (overrides),
//                     "contract": "anywhere"|"surfaces" (overrides),
//                     "camera": {...} (overrides keys of the default camera)}]
// Errors: invalid_input with the offending key; not_found when the config file is missing.
// Thread safety: plain value types.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "codec/light_frame.hpp"
#include "codec/receiver_contract.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::bench {

struct CameraSpec {
  uint32_t width = 96;
  uint32_t height = 64;
  double azimuth = 200;    // degrees, same convention as the sun (clockwise from north)
  double elevation = 35;   // degrees above the horizon
  double fov = 50;         // vertical field of view, degrees
};

struct SceneSpec {
  std::string name;
  std::filesystem::path file;  // resolved (absolute or relative to the working directory)
  UpAxis up = UpAxis::z;
  double sun_azimuth = 135;
  double sun_elevation = 45;
  std::vector<std::string> heightfield;
  std::vector<uint32_t> resolutions;
  size_t receivers = 2000;
  ReceiverContract contract = ReceiverContract::anywhere;
  CameraSpec camera;
};

struct BenchConfig {
  std::vector<store::Method> methods{store::Method::raw};
  uint32_t tile_size = 1024;
  unsigned build_threads = 2;
  std::vector<unsigned> pcf_kernels{3, 5};
  unsigned pcf_supersample = 2;
  std::vector<unsigned> threads{1, 2};
  double min_seconds = 0.3;
  uint64_t cache_mib = 1024;
  bool keep_stores = false;
  uint64_t seed = 1;
  uint64_t batch_points = 1000000;
  std::vector<SceneSpec> scenes;
  nlohmann::json source;  // the config as read, echoed into results.json
};

// Parses `json`; relative scene paths resolve against `base_dir` (+ scene_root).
Result<BenchConfig> parse_bench_config(const nlohmann::json& json, const std::filesystem::path& base_dir);
// Reads and parses a config file.
Result<BenchConfig> load_bench_config(const std::filesystem::path& file);
// Keeps only the named scenes / methods (comma-separated; empty = keep all). raw stays in the
// method list. Errors: invalid_input for a name the config does not have.
Status filter_bench_config(BenchConfig& config, const std::string& scenes, const std::string& methods);

}  // namespace shadowtiles::bench
