// The inspector's routes (issue 17):
//   GET /v1/render/{method}/{z}/{x}/{y}.png[?layer=value|depth|coverage|bytes|diff][&against=M]
//       (and /v1/builds/{build}/render/...: immutable) a 256x256 PNG map tile (tile_renderer.hpp),
//       drawn on the render pool; ETag from the build, request and renderer version; 304 on a match
//   GET /v1/render/legend?layer=L   the layer's legend (JSON)
//   GET /v1/texel?u=&v=             one texel: its tile, each method's value and tile bytes, the world
//                                   point of its surface
//   GET / and /inspector/           the page; /inspector/{app.js, app.css}; /inspector/leaflet/...
//                                   Debian's libjs-leaflet files (leaflet_dir)
// Errors (JSON): 400 malformed numbers, unknown layer, method name or parameter, `against` without
// diff or diff without it; 404 a method not in the store, z beyond max_render_zoom, x/y outside
// 2^z, a texel outside the map; 503 when the render queue is full or a render runs out of time.
// Thread safety: handlers run concurrently on the HTTP workers; rendering on state.render_pool.
#pragma once

#include <httplib.h>

#include "server/service_state.hpp"

namespace shadowtiles::server {

void register_render_routes(httplib::Server& http, ServiceState& state);

}  // namespace shadowtiles::server
