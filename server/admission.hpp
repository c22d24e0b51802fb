// Admission checks that bound one request's work before it is done: the declared body size, and a
// batch's cost, points x kernel² texel lookups (a PCF k x k query reads k² texels per point), against
// the config (max_body_bytes, max_batch_points, max_batch_cost). Run on the headers alone where
// they suffice (a binary batch's point count is its Content-Length / 12), so an oversized request
// is refused before its body is read.
// Errors: out_of_space with a message for the client (the HTTP layer answers 413).
// Thread safety: pure functions.
#pragma once

#include <cstdint>

#include "common/result.hpp"
#include "server/server_config.hpp"

namespace shadowtiles::server {

// `pcf` 0 or 1: a point query (kernel 1).
uint64_t batch_cost(uint64_t points, unsigned pcf);
Status admit_batch(uint64_t points, unsigned pcf, const ServerConfig& config);
Status admit_body(uint64_t declared_bytes, const ServerConfig& config);

}  // namespace shadowtiles::server
