// How much one dictionary of subtree shapes shared by every tile of a map would save against the
// per-tile DAGs DAG-MH stores (issue #4, "a DAG shared across all tiles"). Tiles are added one at
// a time (their topology only: dagmh_topology); shapes are hash-consed into one global dictionary
// with full-key comparison, as the per-tile encoder does.
// Accounting (bytes, the DAG-MH node layout of codec/dagmh_format.hpp):
// - per-tile: each tile's DAG nodes and treelets with that tile's ref/count widths;
// - shared: the dictionary's distinct nodes and treelets with the map-wide widths, plus a root ref
//   per tile (the tile would keep its header and values). The dictionary must be fetched before
//   any tile can be read, so it costs streaming independence; see docs/dagmh.md.
// Thread safety: one study per thread.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "builder/dagmh_encoder.hpp"

namespace shadowtiles {

struct DagMhSharingFigures {
  uint64_t tiles = 0;
  uint64_t per_tile_nodes = 0, per_tile_treelets = 0, per_tile_bytes = 0;
  uint64_t shared_nodes = 0, shared_treelets = 0;
  uint64_t dictionary_bytes = 0;  // distinct nodes + treelets, map-wide widths
  uint64_t root_ref_bytes = 0;    // one root reference per tile
  uint64_t shared_bytes() const { return dictionary_bytes + root_ref_bytes; }
};

class DagMhSharingStudy {
 public:
  explicit DagMhSharingStudy(unsigned treelet_height = 4) : treelet_height_(treelet_height) {}
  // Adds one tile's topology. Errors as dagmh_topology.
  Status add_tile(const MhHierarchy& hierarchy);
  DagMhSharingFigures figures() const;

 private:
  struct KeyHash {
    size_t operator()(const std::array<uint32_t, 5>& k) const;
  };
  unsigned treelet_height_;
  uint64_t tiles_ = 0, per_tile_nodes_ = 0, per_tile_treelets_ = 0, per_tile_bytes_ = 0;
  uint64_t max_values_ = 0;
  std::unordered_map<std::array<uint32_t, 5>, uint32_t, KeyHash> nodes_;  // key -> global id
  std::vector<uint8_t> node_masks_;                                       // by global id
  std::unordered_map<std::string, uint32_t> treelets_;
};

}  // namespace shadowtiles
