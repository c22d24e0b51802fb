// CPVS encoder (docs/architecture.md §8, seed 004): a tile's dual depth -> voxelized-shadow DAG payload
// (format: codec/cpvs_format.hpp, docs/cpvs.md). Binary visibility over (u, v, depth step) with the
// map's side as depth resolution: lossy by that quantisation only (see cpvs::step_bounds).
// Errors: invalid_input for malformed intervals or a map resolution outside [tile side, 2^20].
// Thread safety: stateless; call concurrently.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/cpvs_dag_builder.hpp"
#include "builder/depth_interval.hpp"
#include "common/result.hpp"

namespace shadowtiles {

bool cpvs_encoder_available();
// `map_resolution`: side of the whole map; depth is quantised to that many steps.
Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals& intervals, uint32_t map_resolution);
// Same, with the leaf layout and test hooks chosen; `stats` (optional) receives the build figures.
Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals& intervals, uint32_t map_resolution,
                                              const CpvsBuildOptions& options, CpvsBuildStats* stats = nullptr);

}  // namespace shadowtiles
