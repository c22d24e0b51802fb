#include "builder/cpvs_encoder.hpp"

#include "builder/cpvs_serializer.hpp"

namespace shadowtiles {

bool cpvs_encoder_available() { return true; }

Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals& intervals, uint32_t map_resolution) {
  return encode_cpvs_tile(intervals, map_resolution, CpvsBuildOptions{});
}

Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals& intervals, uint32_t map_resolution,
                                              const CpvsBuildOptions& options, CpvsBuildStats* stats) {
  auto dag = build_cpvs_dag(intervals, map_resolution, options);
  if (!dag) return dag.error();
  if (stats) *stats = dag->stats;
  return serialize_cpvs_dag(*dag);
}

}  // namespace shadowtiles
