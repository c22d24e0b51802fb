// TileRenderer: one 256x256 slippy-map tile of a served build (/v1/render, issue 17). Zoom z shows
// the whole R x R light-space map in 2^z x 2^z tiles (z = 0: the whole map); tile (x, y) has x to
// the right (+u) and y down (+v). Each pixel point-samples the texel under its centre:
//   - at or coarser than the previews' resolution (256 * 2^z <= R / preview step) from the stored
//     previews: no tile is decompressed, so a 64K map's zoom 0 reads 256 small records;
//   - finer, the value and diff layers decode tiles through the ShadowMap cache (the query cache);
//   - finer than a texel, texels magnify (nearest).
// Layers:
//   value     the method's stored value (depth), viridis over the scene's depth range
//   depth     the first-hit depth seen from the light, relief-shaded, always from the previews
//   coverage  per tile: stored, empty, missing, no preview, corrupt; a tile grid when tiles are big
//   bytes     per tile: bits per texel of the stored blob, inferno on a log2 scale
//   diff      |value(method) - value(against)| in world units, inferno on a log10 scale
// Texels no geometry covers (misses) and empty tiles are transparent.
// Bounds: time, by a deadline checked every row (then timed_out, no image); memory, one image plus
// the shared caches (TileSummaryCache, ShadowMap), which are bounded in bytes.
// Thread safety: render_map_tile may run concurrently; it only reads the map and the cache.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "client/shadow_map.hpp"
#include "server/png_writer.hpp"
#include "server/tile_summary_cache.hpp"

namespace shadowtiles::server {

inline constexpr uint32_t kRenderTileSize = 256;
// Bumped when the pictures change, so ETags of old renders stop matching.
inline constexpr int kRendererVersion = 1;

enum class RenderLayer { value, depth, coverage, bytes, diff };
Result<RenderLayer> parse_render_layer(std::string_view name);
const char* render_layer_name(RenderLayer layer);

// The finest zoom served: texels magnified 8x (and at least zoom 0).
unsigned max_render_zoom(uint32_t resolution);

struct RenderRequest {
  store::Method method = store::Method::raw;
  RenderLayer layer = RenderLayer::value;
  std::optional<store::Method> against;  // diff only
  unsigned z = 0;
  uint32_t x = 0;
  uint32_t y = 0;
};

struct RenderOutput {
  RgbaImage image;
  bool timed_out = false;
  unsigned corrupt_tiles = 0;   // previews failing their checks (drawn in the corrupt colour)
  bool decoded_tiles = false;   // finer than the previews: tiles were decoded
};

// Preconditions: the request was validated (methods in the store, z <= max_render_zoom, x, y < 2^z).
// Errors: the store's and decoders' (a corrupt tile blob → corrupt_data).
Result<RenderOutput> render_map_tile(const ShadowMap& map, TileSummaryCache& cache, const RenderRequest& request,
                                     std::chrono::steady_clock::time_point deadline);

// The legend of a layer for this build: title, unit, scale (linear, log2, log10, categories), the
// domain in the unit shown, and the colour stops.
nlohmann::json render_legend(const ShadowMap& map, RenderLayer layer);

}  // namespace shadowtiles::server
