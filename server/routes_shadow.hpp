// Routes of the query API (docs/architecture.md §10):
//   GET  /v1/shadow?x=&y=&z=[&pcf=k][&level=][&method=][&bias=]
//        → {"lit": 0..1, "shadowed", "outside_map", "empty_tile", "u", "v", "depth", "method", "receivers", "pcf"}
//   POST /v1/shadow, Content-Type application/json: {"points": [[x, y, z], ...], "pcf", "method",
//        "level", "bias"} → {"lit": [...], "outside_map": [indices], "count", "method", "receivers", "pcf"}
//   POST /v1/shadow, Content-Type application/octet-stream: little-endian float32 x, y, z triples,
//        options in the query string → one little-endian float32 lit value per point; header
//        X-Shadow-Outside-Map gives how many points were outside the map, X-Shadow-Receivers the contract.
// "receivers" (anywhere | surfaces) is the store's receiver contract (docs/receiver-contracts.md): which
// query points the answers are exact for.
// Bad input → 400 (malformed, unknown method or parameter, bad pcf/level/bias), 413 (body or point
// count over the configured limits), 415 (other content types); 503 until the store is attached.
// Thread safety: handlers run concurrently on httplib's workers; they only use ServiceState.
#pragma once

#include <httplib.h>

#include "server/service_state.hpp"

namespace shadowtiles::server {

void register_shadow_routes(httplib::Server& http, ServiceState& state);

}  // namespace shadowtiles::server
