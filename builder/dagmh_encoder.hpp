// DAG-MH encoder (docs/architecture.md §7; SE21): an MhHierarchy (MH tree or MMH; shared blocks are expanded)
// becomes the payload of codec/dagmh_format.hpp (docs/dagmh.md), read by codec/dagmh_decoder.
// - Topology only goes into a DAG: identical subtree shapes (node kinds, not values) share one node.
//   Deduplication compares keys in full; the hash only buckets (options.hash_bits is a test hook).
// - Subtrees of at most `treelet_height` levels become depth-first valued-node bitmaps (treelets),
//   deduplicated too.
// - Values, in depth-first order, are compressed in chunks: a representative, a bitmap of the
//   values that differ from it, and for those b-bit multipliers (or raw floats). Each value may be
//   re-chosen anywhere inside its node's validity interval; every coded value is checked with the
//   decoder's exact float expression, so the encoding is lossless.
// Errors: invalid_input for a malformed hierarchy (check_structure), bad options, or a payload
// whose sections overflow 32-bit sizes. Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "builder/mh_hierarchy.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct DagMhOptions {
  unsigned treelet_height = 4;  // 2..5 levels per treelet (4: 85-bit bitmaps)
  unsigned chunk_size = 32;     // values per chunk, 1..1024
  // Bits of the structural hash used for bucketing (1..64). Test hook: few bits force collisions,
  // which the full key comparison must resolve.
  unsigned hash_bits = 64;
};

Result<std::vector<uint8_t>> encode_dagmh(const MhHierarchy& hierarchy, const DagMhOptions& options = {});

// Every (treelet height, chunk size) payload of `hierarchy`, byte-identical to encode_dagmh with
// those options, handed to `visit` (heights outer) and valid only during the call. Cheaper than
// separate encodes: the topology is built once per height and the value chunks once per size.
// Stops at the first error (invalid_input as encode_dagmh, or what `visit` returns).
Status for_each_dagmh_parameter(const MhHierarchy& hierarchy, const std::vector<unsigned>& heights,
                                const std::vector<unsigned>& chunks,
                                const std::function<Status(unsigned, unsigned, std::span<const uint8_t>)>& visit);

// One tile's deduplicated topology as encode_dagmh builds it, for studies (builder/dagmh_sharing_study):
// DAG nodes in creation order (children before parents; child_id indexes `nodes` for code 3 and
// `treelets` for code 2), treelet bitmaps, the root's code and id, the tile's value count.
struct DagMhTopology {
  struct Node {
    uint8_t mask = 0;  // 2-bit child codes (codec/dagmh_format.hpp)
    bool valued = false;
    uint32_t child_id[4] = {0, 0, 0, 0};
  };
  std::vector<Node> nodes;
  std::vector<std::string> treelets;
  unsigned root_code = 0;
  uint32_t root_id = 0;
  uint64_t values = 0;
};
Result<DagMhTopology> dagmh_topology(const MhHierarchy& hierarchy, unsigned treelet_height = 4);

// Parameter study: payload bytes for every treelet height in `heights` x chunk size in `chunks`
// (row-major: heights outer). Errors as encode_dagmh.
struct DagMhStudyPoint {
  unsigned treelet_height = 0, chunk_size = 0;
  uint64_t bytes = 0;
};
Result<std::vector<DagMhStudyPoint>> dagmh_parameter_study(const MhHierarchy& hierarchy,
                                                           const std::vector<unsigned>& heights = {2, 3, 4, 5},
                                                           const std::vector<unsigned>& chunks = {16, 32, 64, 128});

}  // namespace shadowtiles
