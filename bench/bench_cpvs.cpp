// CPVS study on a real store: re-renders every tile of STORE from SCENE (the store's light frame and
// tiling) and encodes it as CPVS with both leaf layouts (8x8x1 slabs, 4x4x4 cubes) and with the
// free-voxel reuse rule off, printing bytes (payload and zstd blob), unique nodes and leaves, time
// per phase, and what one DAG merged over all tiles would save (tiles then no longer independent).
//   build-release/bench/bench_cpvs out/nefertiti.store ../shared/scenes/nefertiti/nefertiti.obj [y]
// Not a Google Benchmark: a one-shot measurement with its own main, one JSON line per variant.
#include <chrono>
#include <cstdio>
#include <string>
#include <unordered_map>

#include "builder/build_job.hpp"
#include "builder/cpvs_dag_builder.hpp"
#include "builder/cpvs_serializer.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/scene_loader.hpp"
#include "client/shadow_map.hpp"
#include "store/blob.hpp"

namespace st = shadowtiles;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

struct NodeKeyHash {
  size_t operator()(const st::CpvsNode& n) const {
    size_t h = n.codes;
    for (unsigned i = 0; i < n.ref_count; ++i) h = h * 0x9E3779B97F4A7C15ull + n.refs[i];
    return h;
  }
};

// One DAG over all tiles: each tile's unique nodes re-keyed by global child ids, bottom-up.
class CrossTileMerger {
 public:
  void add(const st::CpvsDag& dag) {
    if (levels_.empty()) levels_.resize(dag.levels.size());
    std::vector<uint32_t> below(dag.leaves.size());
    for (size_t i = 0; i < dag.leaves.size(); ++i)
      below[i] = leaves_.try_emplace(dag.leaves[i], uint32_t(leaves_.size())).first->second;
    for (size_t l = dag.levels.size(); l-- > 0;) {
      std::vector<uint32_t> here(dag.levels[l].size());
      for (size_t i = 0; i < dag.levels[l].size(); ++i) {
        st::CpvsNode node = dag.levels[l][i];
        for (unsigned r = 0; r < node.ref_count; ++r) node.refs[r] = below[node.refs[r]];
        auto [it, inserted] = levels_[l].try_emplace(node, uint32_t(levels_[l].size()));
        if (inserted) ref_bytes_ += 2 + 4ull * node.ref_count;
        here[i] = it->second;
      }
      below = std::move(here);
    }
  }
  // Nodes at 2 bytes + 4 per ref, leaves at 8: a width-agnostic size to compare with the same
  // measure summed per tile.
  uint64_t bytes() const { return ref_bytes_ + 8 * leaves_.size(); }

 private:
  std::vector<std::unordered_map<st::CpvsNode, uint32_t, NodeKeyHash>> levels_;
  std::unordered_map<uint64_t, uint32_t> leaves_;
  uint64_t ref_bytes_ = 0;
};

uint64_t fixed_width_bytes(const st::CpvsDag& dag) {
  uint64_t bytes = 8 * dag.leaves.size();
  for (const auto& level : dag.levels)
    for (const auto& node : level) bytes += 2 + 4ull * node.ref_count;
  return bytes;
}

struct Variant {
  const char* name = "";
  st::CpvsBuildOptions options{};
  uint64_t payload = 0, blob = 0, nodes = 0, leaves = 0, nodes_visited = 0, leaves_visited = 0, fixed = 0;
  double pyramid_s = 0, dag_s = 0, serialize_s = 0, zstd_s = 0;
  CrossTileMerger merger;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_cpvs STORE SCENE [y|z]\n");
    return 2;
  }
  auto map = st::ShadowMap::open(argv[1]);
  if (!map) return std::fprintf(stderr, "%s\n", map.error().message.c_str()), 1;
  st::LoadOptions load;
  load.up = argc > 3 && std::string(argv[3]) == "y" ? st::UpAxis::y : st::UpAxis::z;
  load.heightfield_meshes = (*map)->meta().heightfield_meshes;
  auto scene = st::load_scene(argv[2], load);
  if (!scene) return std::fprintf(stderr, "%s\n", scene.error().message.c_str()), 1;
  auto device = st::EmbreeDevice::create();
  if (!device) return 1;
  const st::TileLayout& layout = (*map)->layout();
  st::LightSpaceScene light_scene(*scene, (*map)->frame(), layout);
  st::DualDepthOptions options;
  options.exit_margin = float((*map)->frame().depth_from_world((*map)->meta().exit_margin));
  options.cap_exits_at_receiver_surfaces = st::BuildConfig{}.cap_exits_at_receiver_surfaces;  // as the build renders
  st::DualDepthRenderer renderer(*device, light_scene, options);

  Variant variants[4];
  variants[0].name = "slab8";
  variants[1].name = "cube4";
  variants[2].name = "slab8_no_reuse";
  variants[3].name = "cube4_no_reuse";
  variants[0].options.layout = variants[2].options.layout = st::cpvs::LeafLayout::slab8;
  variants[1].options.layout = variants[3].options.layout = st::cpvs::LeafLayout::cube4;
  variants[2].options.reuse_free_choice = variants[3].options.reuse_free_choice = false;
  double render_s = 0;
  uint64_t tiles = 0;
  for (uint64_t i = 0; i < layout.tile_count(); ++i) {
    auto start = Clock::now();
    auto intervals = renderer.render(st::TileLayout::from_morton_index(i));
    if (!intervals) return std::fprintf(stderr, "%s\n", intervals.error().message.c_str()), 1;
    render_s += seconds_since(start);
    if (intervals->all_missed()) continue;
    ++tiles;
    for (Variant& v : variants) {
      auto dag = st::build_cpvs_dag(*intervals, layout.resolution(), v.options);
      if (!dag) return std::fprintf(stderr, "%s\n", dag.error().message.c_str()), 1;
      v.pyramid_s += dag->stats.pyramid_seconds;
      v.dag_s += dag->stats.dag_seconds;
      start = Clock::now();
      auto payload = st::serialize_cpvs_dag(*dag);
      if (!payload) return 1;
      v.serialize_s += seconds_since(start);
      start = Clock::now();
      v.blob += st::store::encode_blob(st::store::Method::cpvs, *payload).size();
      v.zstd_s += seconds_since(start);
      v.payload += payload->size();
      for (const auto& level : dag->levels) v.nodes += level.size();
      v.leaves += dag->leaves.size();
      v.nodes_visited += dag->stats.nodes_visited;
      v.leaves_visited += dag->stats.leaves_visited;
      v.fixed += fixed_width_bytes(*dag);
      v.merger.add(*dag);
    }
  }
  for (const Variant& v : variants)
    std::printf(
        "{\"variant\":\"%s\",\"resolution\":%u,\"tile\":%u,\"tiles\":%llu,\"payload_bytes\":%llu,\"blob_bytes\":%llu,"
        "\"unique_nodes\":%llu,\"unique_leaves\":%llu,\"nodes_before_merge\":%llu,\"leaves_before_merge\":%llu,"
        "\"fixed_width_bytes_per_tile_sum\":%llu,\"fixed_width_bytes_one_dag\":%llu,\"cross_tile_saving\":%.4f,"
        "\"render_s\":%.3f,\"pyramid_s\":%.3f,\"dag_s\":%.3f,\"serialize_s\":%.3f,\"zstd_s\":%.3f}\n",
        v.name, layout.resolution(), layout.tile_size(), (unsigned long long)tiles, (unsigned long long)v.payload,
        (unsigned long long)v.blob, (unsigned long long)v.nodes, (unsigned long long)v.leaves,
        (unsigned long long)v.nodes_visited, (unsigned long long)v.leaves_visited, (unsigned long long)v.fixed,
        (unsigned long long)v.merger.bytes(), 1.0 - double(v.merger.bytes()) / double(v.fixed), render_s,
        v.pyramid_s, v.dag_s, v.serialize_s, v.zstd_s);
  return 0;
}
