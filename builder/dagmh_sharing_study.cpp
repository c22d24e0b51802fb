#include "builder/dagmh_sharing_study.hpp"

#include <algorithm>

#include "codec/dagmh_format.hpp"

namespace shadowtiles {
namespace {

namespace F = dagmh_format;

unsigned width_for(uint64_t max_value) {
  unsigned w = 1;
  while (w < 4 && max_value >= (uint64_t(1) << (8 * w))) ++w;
  return w;
}

// DAG section bytes of `masks` with the given widths (the smallest ref width that addresses it).
uint64_t dag_bytes(const std::vector<uint8_t>& masks, uint64_t treelets, unsigned count_width, unsigned* ref_width) {
  for (unsigned wr = 1;; ++wr) {
    uint64_t bytes = 0;
    for (uint8_t m : masks) bytes += F::node_bytes(m, wr, count_width);
    if (std::max(bytes, treelets) < (uint64_t(1) << (8 * wr)) || wr == 4) {
      *ref_width = wr;
      return bytes;
    }
  }
}

}  // namespace

size_t DagMhSharingStudy::KeyHash::operator()(const std::array<uint32_t, 5>& k) const {
  uint64_t h = 0x9e3779b97f4a7c15ULL;
  for (uint32_t x : k) {
    h ^= x;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 32;
  }
  return size_t(h);
}

Status DagMhSharingStudy::add_tile(const MhHierarchy& hierarchy) {
  auto topology = dagmh_topology(hierarchy, treelet_height_);
  if (!topology) return topology.error();
  ++tiles_;
  max_values_ = std::max(max_values_, topology->values);

  // This tile alone, as encode_dagmh lays it out.
  std::vector<uint8_t> masks;
  for (const auto& n : topology->nodes) masks.push_back(n.mask);
  unsigned wr = 1;
  per_tile_bytes_ += dag_bytes(masks, topology->treelets.size(), width_for(topology->values), &wr) +
                     topology->treelets.size() * F::treelet_bytes(treelet_height_);
  per_tile_nodes_ += topology->nodes.size();
  per_tile_treelets_ += topology->treelets.size();

  // Into the dictionary: children come first, so their global ids are known.
  std::vector<uint32_t> treelet_id(topology->treelets.size());
  for (size_t t = 0; t < topology->treelets.size(); ++t)
    treelet_id[t] = treelets_.try_emplace(topology->treelets[t], uint32_t(treelets_.size())).first->second;
  std::vector<uint32_t> node_id(topology->nodes.size());
  for (size_t i = 0; i < topology->nodes.size(); ++i) {
    const auto& n = topology->nodes[i];
    std::array<uint32_t, 5> key{uint32_t(n.mask) | (uint32_t(n.valued) << 8), 0, 0, 0, 0};
    for (unsigned c = 0; c < 4; ++c) {
      const unsigned code = F::child_code(n.mask, c);
      key[1 + c] = code == F::kCodeDag ? node_id[n.child_id[c]] : code == F::kCodeTreelet ? treelet_id[n.child_id[c]] : 0;
    }
    auto [it, fresh] = nodes_.try_emplace(key, uint32_t(node_masks_.size()));
    if (fresh) node_masks_.push_back(n.mask);
    node_id[i] = it->second;
  }
  return Status::success();
}

DagMhSharingFigures DagMhSharingStudy::figures() const {
  DagMhSharingFigures f;
  f.tiles = tiles_;
  f.per_tile_nodes = per_tile_nodes_;
  f.per_tile_treelets = per_tile_treelets_;
  f.per_tile_bytes = per_tile_bytes_;
  f.shared_nodes = node_masks_.size();
  f.shared_treelets = treelets_.size();
  unsigned wr = 1;
  f.dictionary_bytes = dag_bytes(node_masks_, treelets_.size(), width_for(max_values_), &wr) +
                       treelets_.size() * F::treelet_bytes(treelet_height_);
  f.root_ref_bytes = tiles_ * wr;
  return f;
}

}  // namespace shadowtiles
