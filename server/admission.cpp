#include "server/admission.hpp"

#include <string>

namespace shadowtiles::server {

uint64_t batch_cost(uint64_t points, unsigned pcf) {
  const uint64_t kernel = pcf <= 1 ? 1 : uint64_t(pcf) * pcf;
  // Saturates instead of wrapping: a huge count must not look cheap.
  return points > UINT64_MAX / kernel ? UINT64_MAX : points * kernel;
}

Status admit_batch(uint64_t points, unsigned pcf, const ServerConfig& config) {
  if (points > config.max_batch_points)
    return make_error(ErrorCode::out_of_space,
                      "more than " + std::to_string(config.max_batch_points) + " points in one batch");
  if (uint64_t cost = batch_cost(points, pcf); cost > config.max_batch_cost)
    return make_error(ErrorCode::out_of_space,
                      "batch cost " + std::to_string(cost) + " (points x kernel^2) is above the limit of " +
                          std::to_string(config.max_batch_cost) + "; split it or use a smaller pcf");
  return {};
}

Status admit_body(uint64_t declared_bytes, const ServerConfig& config) {
  if (declared_bytes > config.max_body_bytes)
    return make_error(ErrorCode::out_of_space, "request body of " + std::to_string(declared_bytes) +
                                                   " bytes is larger than the limit of " +
                                                   std::to_string(config.max_body_bytes));
  return {};
}

}  // namespace shadowtiles::server
