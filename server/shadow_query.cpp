#include "server/shadow_query.hpp"

#include <algorithm>
#include <mutex>

namespace shadowtiles::server {
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
  // ShadowMap::query_batch sorts the points by tile and Morton order and walks shared paths; the
  // pool's threads run its parallel phases (no threads started per request).
  ShadowMap::BatchOptions options;
  options.kernel = query.pcf == 0 ? 1 : query.pcf;
  options.bias = query.bias;
  options.level = query.level;
  options.parallel_for = [&pool](size_t count, const std::function<void(size_t, size_t)>& fn) {
    pool.parallel_for(count, 1, fn);
  };
  ShadowMap::BatchAnswers answers;
  if (Status s = map.query_batch(points, query.method, options, answers); !s) return s.error();
  BatchResult result;
  result.lit = std::move(answers.lit);
  result.outside = std::move(answers.outside);
  return result;
}

}  // namespace shadowtiles::server
