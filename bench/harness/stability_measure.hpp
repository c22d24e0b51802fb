// Stability suite (issue #8), the measuring step shared by every scenario: one build of a scene with
// every method the builder supports, then per method the point answers on the scenario's receivers
// against Embree ground truth (false lit / false shadowed), bytes at rest and build seconds.
// Methods are iterated generically (builder_supports), so methods that land later are measured too.
// Errors: the build's or the store's (scene load, invalid input, corrupt tile).
// Thread safety: one call at a time per work directory; the build uses its own threads.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "builder/build_job.hpp"
#include "builder/embree_device.hpp"
#include "builder/ground_truth.hpp"
#include "builder/receiver_sampler.hpp"
#include "client/shadow_map.hpp"
#include "store/method.hpp"

namespace shadowtiles::bench {

// One row of a scenario table: one subject (scene + setting) x one method.
struct StabilityRow {
  std::string subject;       // e.g. "terragen", "room (one-sided roof)"
  std::string method;        // method name, with a suffix for comparison rules ("mh [far-plane exit]")
  uint32_t resolution = 0;
  double elevation = std::numeric_limits<double>::quiet_NaN();  // sun elevation, degrees, when varied
  uint64_t receivers = 0;
  uint64_t false_lit = 0;       // store lit, truth shadowed: light leaks
  uint64_t false_shadowed = 0;  // store shadowed, truth lit
  uint64_t differs_from_raw = 0;  // answers unlike raw's (same build)
  uint64_t worse_than_raw = 0;    // ... of which raw was right
  uint64_t bytes = 0;           // blobs at rest (tiles + top tree)
  double build_seconds = 0;     // shared dual depth (BVH + rays, thread sum) + this method's encode
  std::string note;

  double error_rate() const { return receivers ? double(false_lit + false_shadowed) / double(receivers) : 0.0; }
  double false_lit_rate() const { return receivers ? double(false_lit) / double(receivers) : 0.0; }
  double false_shadowed_rate() const { return receivers ? double(false_shadowed) / double(receivers) : 0.0; }
};

// Every method the builder supports, raw first.
std::vector<store::Method> supported_methods();

struct MeasureSpec {
  std::string subject;
  std::filesystem::path scene_file;
  LoadOptions load;
  Vec3 light{0, 0, -1};
  uint32_t resolution = 1024;
  uint32_t tile_size = 1024;
  double elevation = std::numeric_limits<double>::quiet_NaN();
  bool open_exit_at_far_plane = false;  // comparison rule (rows get a suffix)
  // Nearly closed meshes accepted as solids (BuildConfig::close_nearly_closed; rows get a suffix). Off
  // in the suite unless a scenario compares it, so its rows keep measuring the closed/open rule alone.
  bool close_nearly_closed = false;
  ReceiverContract receivers = ReceiverContract::anywhere;  // the build's contract (docs/receiver-contracts.md)
  std::vector<store::Method> methods;   // empty: supported_methods()
};

// Builds `spec` into `work_dir`/store (removed before and after) and measures every method on
// `receivers` whose ground truth is `truth` (1 = lit, see point_truth).
Result<std::vector<StabilityRow>> measure_build(const MeasureSpec& spec, std::span<const Receiver> receivers,
                                                std::span<const uint8_t> truth,
                                                const std::filesystem::path& work_dir);

}  // namespace shadowtiles::bench
