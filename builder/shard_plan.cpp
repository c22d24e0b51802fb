#include "builder/shard_plan.hpp"

#include <algorithm>
#include <charconv>
#include <string>

namespace shadowtiles {
namespace {

// Ray-equivalents per unit of each part, chosen (bench/tile_cost_fit.py --search) on the measured CPU
// seconds of every tile of six shared scenes at 16384², tiles 1024, MMH + DAG-MH: the weighting whose
// worst shard max/mean over the scenes is lowest at N = 4 (1.15) and stays low at N = 8 (1.25). Rays
// alone (the old model with only triangle references and coverage) left honolulu_airport at 1.65:
// its cost follows the visible triangle edges (r = 0.90), not the covered texels (r = 0.62), while
// fzk_haus follows coverage and layers (r = 0.88, 0.82) more than edges (0.25).
constexpr double kPerTriangleReference = 8.0;  // BVH build and intersection work
constexpr double kPerCoveredTexel = 2.0;       // encoders and previews: a hit texel costs more than a miss
constexpr double kPerTriangleEdge = 10000.0;   // depth edges inside the tile: what the encoders cannot share
constexpr double kPerLayeredCell = 1000.0;     // surfaces behind surfaces: ray hits to sort, exit caps
// Reported with --tile-costs for fitting, weighed 0: they add nothing over the parts above.
constexpr double kPerPlaneEdge = 0;
constexpr double kPerVisibleTriangle = 0;

}  // namespace

double TileWork::work() const {
  return double(rays) + kPerTriangleReference * double(triangle_refs) + kPerCoveredTexel * double(covered_texels) +
         kPerTriangleEdge * double(triangle_edges) + kPerPlaneEdge * double(plane_edges) +
         kPerVisibleTriangle * double(visible_triangles) + kPerLayeredCell * double(layered_cells);
}

Result<ShardSpec> parse_shard_spec(std::string_view text) {
  auto bad = [&] {
    return make_error(ErrorCode::invalid_input,
                      "--shard '" + std::string(text) + "': expected I/N with 0 <= I < N <= 65536, e.g. 0/4");
  };
  size_t slash = text.find('/');
  if (slash == std::string_view::npos) return bad();
  ShardSpec spec;
  auto parse = [](std::string_view part, uint32_t& out) {
    auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
    return ec == std::errc{} && end == part.data() + part.size() && !part.empty();
  };
  if (!parse(text.substr(0, slash), spec.index) || !parse(text.substr(slash + 1), spec.count)) return bad();
  if (spec.count < 1 || spec.count > 65536 || spec.index >= spec.count) return bad();
  return spec;
}

std::vector<ShardRange> plan_shards(std::span<const TileWork> tiles, uint64_t tile_count, uint32_t shards) {
  std::vector<ShardRange> ranges(std::max<uint32_t>(shards, 1));
  double total = 0;
  for (const TileWork& t : tiles) total += t.work();
  std::vector<uint32_t> owner(tiles.size(), 0);
  double before = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    double w = tiles[i].work();
    double midpoint = before + w / 2;
    before += w;
    uint32_t shard = total > 0 ? uint32_t(std::min<double>(ranges.size() - 1, midpoint / total * double(ranges.size()))) : 0;
    if (i > 0) shard = std::max(shard, owner[i - 1]);  // stays monotone under rounding
    owner[i] = shard;
    ranges[shard].tiles += 1;
    ranges[shard].work += w;
  }
  // Boundaries: a shard ends where the first tile of a later shard starts (empty tiles between two
  // shards go to the earlier one); the first starts at 0, the last ends the map.
  uint64_t begin = 0;
  size_t j = 0;
  for (uint32_t s = 0; s < ranges.size(); ++s) {
    while (j < tiles.size() && owner[j] <= s) ++j;
    uint64_t end = s + 1 == ranges.size() || j == tiles.size() ? tile_count : tiles[j].morton_index;
    ranges[s].morton_begin = begin;
    ranges[s].morton_end = std::max(begin, end);
    begin = ranges[s].morton_end;
  }
  return ranges;
}

double shard_imbalance(std::span<const ShardRange> ranges) {
  if (ranges.empty()) return 1;
  double total = 0, most = 0;
  for (const ShardRange& r : ranges) {
    total += r.work;
    most = std::max(most, r.work);
  }
  return total > 0 ? most / (total / double(ranges.size())) : 1;
}

}  // namespace shadowtiles
