// The GET /v1/meta document: TileJSON 3.0.0-like fields (tilejson, tiles URL template, bounds,
// scheme "xyz", minzoom = maxzoom = the tile level) plus a namespaced "shadow" object with what a
// client needs to query or decode tiles itself: the light frame, resolution, tile size, levels,
// methods, format version and build stats (docs/architecture.md §10).
// "bounds" are in light-space texel units, [0, 0, R, R] (the grid the tile URLs address); the world
// bounds of the scene are in shadow.world_bounds. The scene's file path is reduced to its file name
// so the document does not reveal the server's directory layout.
// Thread safety: pure function of an open ShadowMap.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "client/shadow_map.hpp"

namespace shadowtiles::server {

// Tile URL template of a build: under the build id, so caches may keep tiles for good.
std::string tiles_url_template(const std::string& build_id);

nlohmann::json meta_document(const ShadowMap& map);

}  // namespace shadowtiles::server
