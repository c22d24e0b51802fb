#include "server/shadow_query.hpp"

#include <algorithm>
#include <mutex>

namespace shadowtiles::server {
namespace {
// Below this many points per share, splitting costs more than it saves (a point query is ~0.1 µs
// to a few µs once tiles are cached).
constexpr size_t kMinPointsPerShare = 2048;
}  // namespace

Result<ResolvedQuery> resolve_query(const ShadowMap& map, const QueryOptions& options) {
  ResolvedQuery query;
  query.method = options.method.value_or(map.default_method());
  if (!map.meta().has_method(query.method))
    return make_error(ErrorCode::unsupported,
                      std::string("method '") + store::method_name(query.method) + "' is not in this store");
  if (options.level && *options.level >= map.level_count())
    return make_error(ErrorCode::invalid_input,
                      "level must be in [0, " + std::to_string(map.level_count() - 1) + "]");
  query.pcf = options.pcf;
  query.level = options.level;
  query.bias = options.bias;
  return query;
}

Result<PointResult> answer_point(const ShadowMap& map, const Vec3& point, const ResolvedQuery& query) {
  PointResult result;
  if (query.pcf == 0) {
    auto answer = map.query(point, query.method, query.bias, query.level);
    if (!answer) return answer.error();
    result.answer = *answer;
    result.lit = answer->lit ? 1.0 : 0.0;
    return result;
  }
  auto fraction = map.query_pcf(point, query.method, query.pcf, query.bias, query.level, &result.answer);
  if (!fraction) return fraction.error();
  result.lit = *fraction;
  return result;
}

Result<BatchResult> answer_batch(const ShadowMap& map, std::span<const Vec3> points, const ResolvedQuery& query,
                                 BatchPool& pool) {
  BatchResult result;
  result.lit.assign(points.size(), 1.0f);
  std::vector<uint8_t> outside(points.size(), 0);
  std::mutex error_mutex;
  std::optional<Error> first_error;
  pool.parallel_for(points.size(), kMinPointsPerShare, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      auto answer = answer_point(map, points[i], query);
      if (!answer) {
        std::lock_guard lock(error_mutex);
        if (!first_error) first_error = answer.error();
        return;  // one error fails the batch: stop this share early
      }
      result.lit[i] = float(answer->lit);
      outside[i] = answer->answer.outside_map;
    }
  });
  if (first_error) return *first_error;
  for (size_t i = 0; i < points.size(); ++i)
    if (outside[i]) result.outside.push_back(uint32_t(i));
  return result;
}

}  // namespace shadowtiles::server
