// Service routes (docs/architecture.md §10):
//   GET /v1/meta   the TileJSON-like metadata document (meta_document.hpp); 503 until attached
//   GET /healthz   200 {"status": "ok"} once the store is open and its meta validated, else 503
//   GET /metrics   Prometheus text (metrics.hpp)
//   OPTIONS *      CORS preflight (cors.hpp)
//   PUT / PATCH / DELETE *  405 with Allow
// Thread safety: handlers run concurrently; they only use ServiceState.
#pragma once

#include <httplib.h>

#include "server/service_state.hpp"

namespace shadowtiles::server {

void register_info_routes(httplib::Server& http, ServiceState& state);

}  // namespace shadowtiles::server
