// Routes serving stored records unchanged (docs/architecture.md §9, §10):
//   GET|HEAD /v1/tiles/{method}/{level}/{x}/{y}   a tile blob of the `tiles` database
//   GET|HEAD /v1/skiplist[?method=]               the method's top tree (tile roots + embedded skip
//                                                 list), `top` key "top/<method>"
//   GET|HEAD /v1/builds/{build}/tiles/... and /v1/builds/{build}/skiplist: the same, under the build
//            id (meta `config_hash`); 404 for any other build, so these URLs are immutable
//   GET|HEAD /v1/build                            the build's meta record (JSON) as stored; ETag = build id
// Every blob is checked (store::check_blob: magic, version, sizes, checksum) before it is served; a
// blob failing its checks is never sent: 500 with a JSON error, a log line and a metric (the one
// 5xx the server gives, since the fault is the store's). The strong ETag is the blob checksum
// ("<16 hex digits>"), so If-None-Match → 304. Cache-Control: "public, max-age=N, immutable" under
// /v1/builds/{build}/, "public, no-cache" (revalidate: a reload may change them) on unversioned URLs.
// Tiles: 204 for an in-bounds tile with no blob (empty: all lit), 404 for a level other than the
// store's tile level, x/y outside the grid or a method not in the store, 400 for a malformed URL
// (non-numeric coordinates, unknown method name). Skip list: 404 until one is stored.
// Thread safety: handlers run concurrently; each reads in its own short LMDB snapshot.
#pragma once

#include <httplib.h>

#include "server/service_state.hpp"

namespace shadowtiles::server {

void register_blob_routes(httplib::Server& http, ServiceState& state);

// Whether an If-None-Match header value matches `etag` ("*", or a list of tags; weak comparison as
// RFC 9110 §13.1.2 prescribes for If-None-Match). Exposed for tests.
bool if_none_match_matches(std::string_view header, std::string_view etag);

}  // namespace shadowtiles::server
