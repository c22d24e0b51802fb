#include "builder/cpvs_serializer.hpp"

#include <algorithm>
#include <cstring>

namespace shadowtiles {

Result<std::vector<uint8_t>> serialize_cpvs_dag(const CpvsDag& dag) {
  const size_t levels = dag.levels.size();
  if (levels != cpvs::level_count_for(dag.depth_steps))
    return make_error(ErrorCode::invalid_input, "cpvs: DAG level count does not match its depth steps");
  // Bottom-up: a level's ref width depends on the byte offsets of the level below.
  std::vector<std::vector<uint32_t>> offsets(levels);
  std::vector<unsigned> widths(levels);
  std::vector<uint64_t> level_bytes(levels);
  for (size_t l = levels; l-- > 0;) {
    uint32_t max_ref = 0;
    if (l + 1 == levels) {
      max_ref = dag.leaves.empty() ? 0 : uint32_t(dag.leaves.size() - 1);
    } else if (!offsets[l + 1].empty()) {
      max_ref = offsets[l + 1].back();
    }
    widths[l] = cpvs::ref_width_for(max_ref);
    uint64_t bytes = 0;
    offsets[l].reserve(dag.levels[l].size());
    for (const CpvsNode& node : dag.levels[l]) {
      offsets[l].push_back(uint32_t(bytes));
      bytes += 2 + uint64_t(node.ref_count) * widths[l];
      if (bytes > UINT32_MAX) return make_error(ErrorCode::invalid_input, "cpvs: a DAG level exceeds 4 GiB");
    }
    level_bytes[l] = bytes;
  }
  if (dag.root_code == cpvs::kCodeRef && (dag.levels.empty() || dag.levels[0].size() != 1))
    return make_error(ErrorCode::invalid_input, "cpvs: the root level must hold exactly the root");

  uint64_t total = cpvs::kHeaderBytes + levels * cpvs::kLevelEntryBytes + 8 * uint64_t(dag.leaves.size());
  for (uint64_t b : level_bytes) total += b;
  std::vector<uint8_t> out(total, 0);
  uint8_t* p = out.data();
  std::memcpy(p + cpvs::kOffMagic, cpvs::kMagic, 4);
  bytes::store_le<uint16_t>(p + cpvs::kOffVersion, cpvs::kFormatVersion);
  p[cpvs::kOffLayout] = uint8_t(dag.layout);
  p[cpvs::kOffRootCode] = uint8_t(dag.root_code);
  bytes::store_le<uint32_t>(p + cpvs::kOffTileSize, dag.tile_size);
  bytes::store_le<uint32_t>(p + cpvs::kOffDepthSteps, dag.depth_steps);
  bytes::store_le<uint32_t>(p + cpvs::kOffLevelCount, uint32_t(levels));
  bytes::store_le<uint32_t>(p + cpvs::kOffLeafCount, uint32_t(dag.leaves.size()));
  size_t at = cpvs::kHeaderBytes;
  for (size_t l = 0; l < levels; ++l, at += cpvs::kLevelEntryBytes) {
    bytes::store_le<uint32_t>(p + at, uint32_t(level_bytes[l]));
    p[at + 4] = uint8_t(widths[l]);
  }
  for (size_t l = 0; l < levels; ++l) {
    const bool last = l + 1 == levels;
    for (const CpvsNode& node : dag.levels[l]) {
      bytes::store_le<uint16_t>(p + at, node.codes);
      at += 2;
      for (unsigned i = 0; i < node.ref_count; ++i) {
        uint32_t target = node.refs[i];
        uint32_t ref = last ? target : offsets[l + 1].at(target);
        for (unsigned b = 0; b < widths[l]; ++b) p[at++] = uint8_t(ref >> (8 * b));
      }
    }
  }
  for (uint64_t mask : dag.leaves) {
    bytes::store_le<uint64_t>(p + at, mask);
    at += 8;
  }
  return out;
}

}  // namespace shadowtiles
