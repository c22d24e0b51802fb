// Answers shadow queries for the HTTP layer: resolves QueryOptions against the open store (default
// method, method present) and runs point or PCF queries through ShadowMap, one point or a batch
// split across a BatchPool.
// "lit" is 1 or 0 for a point query and the lit fraction of the k x k kernel for PCF; points
// outside the map are lit (1) and flagged.
// Errors: invalid_input / unsupported (options the store cannot answer: absent method, level out of
// range) → the client's fault; corrupt_data / io_error from the store → the server's.
// Thread safety: all functions may be called concurrently (ShadowMap and BatchPool are).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "client/shadow_map.hpp"
#include "server/batch_pool.hpp"
#include "server/request_parsing.hpp"

namespace shadowtiles::server {

struct ResolvedQuery {
  store::Method method;
  unsigned pcf = 0;  // 0: point query
  std::optional<unsigned> level;
  std::optional<double> bias;
};

Result<ResolvedQuery> resolve_query(const ShadowMap& map, const QueryOptions& options);

struct PointResult {
  double lit = 1;
  ShadowAnswer answer;
};
Result<PointResult> answer_point(const ShadowMap& map, const Vec3& point, const ResolvedQuery& query);

struct BatchResult {
  std::vector<float> lit;         // one per point
  std::vector<uint32_t> outside;  // indices of points outside the map, ascending
};
Result<BatchResult> answer_batch(const ShadowMap& map, std::span<const Vec3> points, const ResolvedQuery& query,
                                 BatchPool& pool);

}  // namespace shadowtiles::server
