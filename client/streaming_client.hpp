// The streaming client's entry points: one call opens a ShadowMap over a local store or a server,
// and prefetch helpers load the tiles a viewer is about to need (docs/architecture.md §1: "client/: stream +
// cache tiles, decode on CPU, answer queries locally").
//
//   auto map = open_shadow_map("http://127.0.0.1:8080", {});   // or a store directory
//   prefetch_frustum(**map, method, camera);                     // optional, ahead of a frame
//   auto answer = (*map)->query(point, method);                  // as with a local store
//
// Answers are identical whichever way the map is opened (same blobs, same decoder).
// Errors: those of ShadowMap::open and HttpTileSource::open; prefetch: the first tile's error.
// Thread safety: the functions are thread-safe; the returned ShadowMap is (see shadow_map.hpp).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "client/http_tile_source.hpp"
#include "client/shadow_map.hpp"
#include "client/streaming_camera.hpp"

namespace shadowtiles {

struct StreamingOptions {
  ShadowMap::Options map;       // memory cache of decoded tiles
  HttpTileSource::Options http; // server URLs only: retries, timeouts, disk cache
};

// True for http:// and https:// locations.
bool is_server_url(std::string_view location);

// A ShadowMap over the server at `location` (http[s]://host:port) or the store directory at it.
Result<std::unique_ptr<ShadowMap>> open_shadow_map(const std::string& location, const StreamingOptions& options);

// The HTTP source under `map`, or nullptr for a local store (for its fetch statistics).
const HttpTileSource* http_source(const ShadowMap& map);

// Tiles holding a texel within `radius_texels` (Chebyshev distance) of the point's texel, clipped to
// the map; empty when the point falls off the map.
std::vector<TileCoord> tiles_around(const ShadowMap& map, const Vec3& world, uint32_t radius_texels);

// Tiles whose light-space column (the tile's square over the whole depth range) may be seen by the
// camera: the column's corners are tested against the frustum's planes (near and the four sides;
// `far_distance` > 0 adds a far plane). Conservative: a tile is dropped only when the frustum
// cannot see any of it. Ordered by distance from the camera's line of sight, nearest first.
std::vector<TileCoord> tiles_under_frustum(const ShadowMap& map, const CameraView& camera, double far_distance = 0);

Status prefetch_around(const ShadowMap& map, store::Method method, const Vec3& world, uint32_t radius_texels);
Status prefetch_frustum(const ShadowMap& map, store::Method method, const CameraView& camera,
                        double far_distance = 0);

}  // namespace shadowtiles
