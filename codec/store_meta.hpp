// StoreMeta: the `meta` record of a store (JSON in the LMDB `meta` database under key "build"),
// everything a reader needs to turn a world point into a tile lookup: the light frame, the map
// and tile sizes, the methods present, the default query bias and whether the build completed.
// Parsing validates every field: the record comes from disk and is treated as untrusted.
// Thread safety: plain value type.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "codec/light_frame.hpp"
#include "codec/receiver_contract.hpp"
#include "codec/tile_layout.hpp"
#include "store/method.hpp"
#include "store/store_layout.hpp"
#include "common/result.hpp"

namespace shadowtiles {

// FORMAT: bump when the meta record or any tile payload changes incompatibly.
constexpr int kStoreFormatVersion = 1;
// Keys of the store's layout (store/store_layout.hpp), named here too for the readers of meta.
using store::kMetaBuildKey;
using store::top_tree_key;

// A shard store (`build --shard I/N`) holds one share of a build; `shadowtiles merge` joins them.
struct ShardInfo {
  uint32_t index = 0;
  uint32_t count = 1;
  uint64_t morton_begin = 0;  // the share: Morton tile indices [begin, end)
  uint64_t morton_end = 0;
  uint64_t tiles = 0;         // tiles with triangles in the share (its progress records when done)
  double work = 0;            // planned work (builder/shard_plan.hpp)
  bool complete = false;      // every tile of the share committed
  int zstd_level = 3;         // the build's, so the merge compresses the top levels alike
  bool operator==(const ShardInfo&) const = default;
};

struct StoreMeta {
  int format_version = kStoreFormatVersion;
  std::string builder_version;
  std::string config_hash;  // hex; a resumed build must match it
  bool complete = false;    // all tiles committed; absent tiles are then known empty

  std::string scene_path;
  std::vector<std::string> heightfield_meshes;  // as given to the build (verify reloads with them)
  uint64_t scene_triangles = 0;
  std::string up_axis;  // "z" or "y" as given to the build; empty in stores built before it was recorded
  WorldBounds scene_bounds;

  Vec3 light_direction{0, 0, -1};
  Vec3 light_origin{0, 0, 0};
  double light_extent = 1;
  double light_depth_range = 1;
  uint32_t resolution = 1;
  uint32_t tile_size = 1;
  std::vector<store::Method> methods;
  double default_bias = 0;  // world units
  double exit_margin = 0;   // world units the builder pulled exits back by
  // Which receivers the intervals answer exactly; absent in stores built before contracts: anywhere.
  ReceiverContract receivers = ReceiverContract::anywhere;
  // Exits capped by the receiver surfaces inside each texel (absent in older stores: false).
  bool exit_caps = false;
  // `surfaces`, the entry rule (docs/receiver-contracts.md): the smallest query bias (world units)
  // the interval methods' values answer for; queries with a smaller bias are refused for them.
  // Absent in older stores and when off: 0.
  double entry_slack = 0;
  // Nearly closed meshes accepted as solids (`anywhere` only; docs/receiver-contracts.md): the winding-number
  // test's parameters, which verify reloads the scene with. Absent in
  // older stores and when off: false.
  bool nearly_closed = false;
  double nearly_closed_tolerance = 0;
  double nearly_closed_max_ambiguous_area = 0;
  uint32_t nearly_closed_max_samples = 0;
  uint32_t nearly_closed_max_patch_triangles = 0;
  uint32_t nearly_closed_min_full_samples = 0;
  uint64_t nearly_closed_full_budget = 0;
  // Absent in stores built before it: 0, any misplaced sample refused (the rule they were built with).
  double nearly_closed_max_misplaced_area = 0;
  nlohmann::json build_stats = nlohmann::json::object();
  // Set only in a shard store, whose `complete` stays false: it answers for its share alone.
  std::optional<ShardInfo> shard;

  Result<LightFrame> light_frame() const;
  Result<TileLayout> layout() const;
  bool has_method(store::Method method) const;
  // The smallest query bias (world units) `method` answers for: entry_slack for the methods encoded
  // from the entry rule's intervals (MH, MMH, DAG-MH, CPVS), else 0.
  double min_query_bias(store::Method method) const;

  nlohmann::json to_json() const;
  static Result<StoreMeta> from_json(const nlohmann::json& json);
  static Result<StoreMeta> parse(std::string_view text);
};

}  // namespace shadowtiles
