#include "builder/cpvs_dag_builder.hpp"

#include <xxhash.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <string>
#include <unordered_map>

#include "builder/cpvs_bounds_pyramid.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

uint64_t keep_bits(uint64_t hash, unsigned bits) { return bits >= 64 ? hash : hash & ((uint64_t(1) << bits) - 1); }

struct NodeHash {
  unsigned bits = 64;
  size_t operator()(const CpvsNode& node) const {
    uint32_t words[9];
    words[0] = node.codes;
    for (unsigned i = 0; i < node.ref_count; ++i) words[1 + i] = node.refs[i];
    return size_t(keep_bits(XXH3_64bits(words, sizeof(uint32_t) * (1 + node.ref_count)), bits));
  }
};

struct LeafHash {
  unsigned bits = 64;
  size_t operator()(uint64_t mask) const { return size_t(keep_bits(XXH3_64bits(&mask, sizeof mask), bits)); }
};

struct ChildRef {
  unsigned code;
  uint32_t id;
};

class DagBuilder {
 public:
  DagBuilder(const CpvsBoundsPyramid& pyramid, CpvsDag& dag, const CpvsBuildOptions& options)
      : pyramid_(pyramid),
        dag_(dag),
        layout_(options.layout),
        reuse_free_choice_(options.reuse_free_choice),
        leaf_ids_(16, LeafHash{options.hash_bits}) {
    unsigned levels = cpvs::level_count_for(dag.depth_steps);
    dag_.levels.assign(levels, {});
    for (unsigned l = 0; l < levels; ++l) node_ids_.emplace_back(16, NodeHash{options.hash_bits});
  }

  ChildRef build_root() {
    const uint32_t n = dag_.depth_steps;
    unsigned code = classify(n, 0, 0, 0, n);
    if (code != cpvs::kCodeRef) return {code, 0};
    return {code, build_node(0, n, 0, 0, 0)};
  }

 private:
  // Lit when every voxel of the box is lit or free, shadowed when every voxel is shadowed or free
  // (lit wins when the whole box is free), else it needs a ref.
  unsigned classify(uint32_t texel_side, uint32_t u0, uint32_t v0, uint32_t z0, uint32_t z_extent) const {
    CpvsBlockBounds b = pyramid_.block(texel_side, u0, v0);
    if (z0 + z_extent <= b.min_shadow_begin) return cpvs::kCodeLit;
    if (z0 >= b.max_lit_end) return cpvs::kCodeShadowed;
    return cpvs::kCodeRef;
  }

  uint32_t build_node(unsigned level, uint32_t side, uint32_t u0, uint32_t v0, uint32_t z0) {
    ++dag_.stats.nodes_visited;
    const bool last = side == cpvs::kMinSide;
    const bool slabs = last && layout_ == cpvs::LeafLayout::slab8;
    const uint32_t half = side / 2;
    CpvsNode node;
    for (unsigned c = 0; c < 8; ++c) {
      uint32_t cu = u0, cv = v0, cz = z0 + c, texel_side = side, z_extent = 1;
      if (!slabs) {
        cu = u0 + (c & 1) * half;
        cv = v0 + ((c >> 1) & 1) * half;
        cz = z0 + ((c >> 2) & 1) * half;
        texel_side = z_extent = half;
      }
      unsigned code = classify(texel_side, cu, cv, cz, z_extent);
      if (code == cpvs::kCodeRef)
        node.refs[node.ref_count++] = last ? build_leaf(cu, cv, cz) : build_node(level + 1, half, cu, cv, cz);
      node.codes = uint16_t(node.codes | code << (2 * c));
    }
    auto [it, inserted] = node_ids_[level].try_emplace(node, uint32_t(dag_.levels[level].size()));
    if (inserted) dag_.levels[level].push_back(node);
    return it->second;
  }

  uint32_t build_leaf(uint32_t u0, uint32_t v0, uint32_t z0) {
    ++dag_.stats.leaves_visited;
    uint64_t must_lit = 0, must_shadow = 0;
    auto place = [&](unsigned bit, cpvs::StepBounds t, uint32_t z) {
      if (z < t.lit_end) must_lit |= uint64_t(1) << bit;
      else if (z >= t.shadow_begin) must_shadow |= uint64_t(1) << bit;
    };
    if (layout_ == cpvs::LeafLayout::slab8) {
      for (unsigned dv = 0; dv < 8; ++dv)
        for (unsigned du = 0; du < 8; ++du) place(du | dv << 3, pyramid_.texel(u0 + du, v0 + dv), z0);
    } else {
      for (unsigned dv = 0; dv < 4; ++dv)
        for (unsigned du = 0; du < 4; ++du) {
          cpvs::StepBounds t = pyramid_.texel(u0 + du, v0 + dv);
          for (unsigned dz = 0; dz < 4; ++dz) place(du | dv << 2 | dz << 4, t, z0 + dz);
        }
    }
    const uint64_t free_as_lit = must_shadow, free_as_shadowed = ~must_lit;
    if (reuse_free_choice_ && free_as_lit != free_as_shadowed) {
      if (auto it = leaf_ids_.find(free_as_lit); it != leaf_ids_.end()) return it->second;
      if (auto it = leaf_ids_.find(free_as_shadowed); it != leaf_ids_.end()) {
        ++dag_.stats.leaves_matched_by_free_choice;
        return it->second;
      }
    }
    auto [it, inserted] = leaf_ids_.try_emplace(free_as_lit, uint32_t(dag_.leaves.size()));
    if (inserted) dag_.leaves.push_back(free_as_lit);
    return it->second;
  }

  const CpvsBoundsPyramid& pyramid_;
  CpvsDag& dag_;
  cpvs::LeafLayout layout_;
  bool reuse_free_choice_;
  std::vector<std::unordered_map<CpvsNode, uint32_t, NodeHash>> node_ids_;
  std::unordered_map<uint64_t, uint32_t, LeafHash> leaf_ids_;
};

Status check_intervals(const TileIntervals& intervals, uint32_t map_resolution) {
  const uint32_t size = intervals.size;
  if (size == 0 || !std::has_single_bit(size) || intervals.texels.size() != size_t(size) * size)
    return make_error(ErrorCode::invalid_input, "cpvs: tile side must be a power of two with side^2 texels");
  if (map_resolution < size || map_resolution > cpvs::kMaxDepthSteps)
    return make_error(ErrorCode::invalid_input, "cpvs: map resolution " + std::to_string(map_resolution) +
                                                    " must be in [tile side, 2^20]");
  for (const DepthInterval& t : intervals.texels)
    if (std::isnan(t.lower) || std::isnan(t.upper) || t.upper < t.lower)
      return make_error(ErrorCode::invalid_input, "cpvs: interval with NaN or lower > upper");
  return {};
}

}  // namespace

Result<CpvsDag> build_cpvs_dag(const TileIntervals& intervals, uint32_t map_resolution,
                               const CpvsBuildOptions& options) {
  if (Status s = check_intervals(intervals, map_resolution); !s) return s.error();
  if (options.hash_bits < 1 || options.hash_bits > 64)
    return make_error(ErrorCode::invalid_input, "cpvs: hash_bits must be in [1, 64]");
  CpvsDag dag;
  dag.tile_size = intervals.size;
  dag.depth_steps = cpvs::depth_steps_for(map_resolution, intervals.size);
  dag.layout = options.layout;
  auto start = Clock::now();
  CpvsBoundsPyramid pyramid(intervals, dag.depth_steps);
  dag.stats.pyramid_seconds = seconds_since(start);
  start = Clock::now();
  DagBuilder builder(pyramid, dag, options);
  ChildRef root = builder.build_root();
  dag.root_code = root.code;
  dag.stats.dag_seconds = seconds_since(start);
  return dag;
}

}  // namespace shadowtiles
