// DecodedTile: a tile of any method, ready for random-access lookups. Each method's decoder adapts
// its view to this interface so the query layer (point, PCF, LOD) is written once.
// Thread safety: implementations are immutable after decoding; lookups may run concurrently.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "codec/texel_query.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles {

class DecodedTile {
 public:
  virtual ~DecodedTile() = default;
  virtual uint32_t size() const = 0;
  // Shadow value of tile-local texel (u, v) < size(); lit when depth <= value + bias.
  // `max_level` limits the descent of hierarchical methods (0 = tile root); flat methods ignore it.
  virtual float value(uint32_t u, uint32_t v, unsigned max_level = 255) const = 0;
  virtual size_t memory_bytes() const = 0;
  // How many texels of the kw x kh box at (u0, v0) (inside the tile) are lit for a receiver whose
  // biased depth is `threshold` (lit: threshold <= value), at full resolution. Hierarchical methods
  // override it with one descent to the box's common ancestor.
  virtual uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const;
  // Is a receiver at tile-local texel (u, v) with biased depth `threshold` lit? Depth-map methods
  // compare with value(); methods that store visibility itself (CPVS: voxels along depth) override
  // it, because one value per texel cannot describe them.
  virtual bool lit(uint32_t u, uint32_t v, float threshold, unsigned max_level = 255) const {
    return threshold <= value(u, v, max_level);
  }
  // Value and lit() of one texel together: one descent for depth-map methods (a point query needs
  // both). Methods whose lit() is not a comparison with value() override it.
  struct Sample {
    float value;
    bool lit;
  };
  virtual Sample sample(uint32_t u, uint32_t v, float threshold, unsigned max_level = 255) const {
    const float x = value(u, v, max_level);
    return {x, threshold <= x};
  }
  // Batch point lookups: lit[i] = lit(q.u, q.v, q.threshold, max_level) for each query, the queries
  // sorted along the Morton curve inside the tile (any order is answered correctly; sorted ones
  // share their descents). Hierarchical methods resume each descent from the deepest node the
  // query shares with the previous one.
  virtual void lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const {
    for (size_t i = 0; i < queries.size(); ++i) lit[i] = this->lit(queries[i].u, queries[i].v, queries[i].threshold, max_level);
  }
  // Batch PCF: counts[i] = lit_count(c.u, c.v, k, k, c.threshold) for the k x k boxes inside the
  // tile whose lower corners c = corners[i] are sorted along the Morton curve (any order is answered
  // correctly). Hierarchical methods share the descents to the boxes' common ancestors.
  virtual void lit_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const {
    for (size_t i = 0; i < corners.size(); ++i)
      counts[i] = lit_count(corners[i].u, corners[i].v, k, k, corners[i].threshold);
  }
  // The payload's size split into named parts (e.g. DAG nodes, treelets, chunk headers), for
  // `inspect`; empty when the method has no breakdown.
  struct SizePart {
    std::string name;
    uint64_t bytes = 0;
  };
  virtual std::vector<SizePart> size_breakdown() const { return {}; }
  // Counts of the payload's structure for `inspect`, in named groups (e.g. "nodes", "dag"), summed
  // over a store's tiles, or their maximum where `is_max`; empty when the method has none.
  struct StructureCount {
    std::string group;
    std::string name;
    uint64_t value = 0;
    bool is_max = false;
  };
  virtual std::vector<StructureCount> structure_counts() const { return {}; }
};

// Decodes a blob's payload for `method` through the decoder table (codec/method_decoders.hpp).
// Errors: corrupt_data (malformed payload), unsupported (no decoder). Safe on untrusted input.
Result<std::shared_ptr<const DecodedTile>> decode_tile(store::Method method, std::span<const uint8_t> payload);

// The built-in decoders of raw, MH/MMH and DAG-MH (their adapters live in decoded_tile.cpp; CPVS's
// and SST's in their own decoder files).
Result<std::shared_ptr<const DecodedTile>> decode_raw_tile(std::span<const uint8_t> payload);
Result<std::shared_ptr<const DecodedTile>> decode_mh_tile(std::span<const uint8_t> payload);
Result<std::shared_ptr<const DecodedTile>> decode_dagmh_tile(std::span<const uint8_t> payload);

}  // namespace shadowtiles
