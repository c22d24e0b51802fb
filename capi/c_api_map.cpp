// The C API's map lifetime and read-outs: open, close, meta, info, tile values, surface points.
#include <cmath>
#include <cstring>
#include <limits>

#include "capi/c_api_support.hpp"
#include "client/streaming_client.hpp"

using namespace shadowtiles;
using capi::fail;
using capi::guarded;

extern "C" {

const char* shadowtiles_version(void) { return SHADOWTILES_VERSION_STRING; }
int shadowtiles_abi_version(void) { return SHADOWTILES_ABI_VERSION; }

const char* shadowtiles_status_name(shadowtiles_status status) {
  switch (status) {
    case SHADOWTILES_OK: return "ok";
    case SHADOWTILES_INVALID_INPUT: return "invalid_input";
    case SHADOWTILES_CORRUPT_DATA: return "corrupt_data";
    case SHADOWTILES_NOT_FOUND: return "not_found";
    case SHADOWTILES_IO_ERROR: return "io_error";
    case SHADOWTILES_OUT_OF_SPACE: return "out_of_space";
    case SHADOWTILES_UNSUPPORTED: return "unsupported";
    case SHADOWTILES_OUT_OF_MEMORY: return "out_of_memory";
    case SHADOWTILES_INTERNAL: return "internal";
  }
  return "unknown";
}

shadowtiles_status shadowtiles_open(const char* location, uint64_t cache_bytes, shadowtiles_map** out) {
  return guarded([&] {
    if (location == nullptr || out == nullptr) return fail(SHADOWTILES_INVALID_INPUT, "open: location and out must not be NULL");
    StreamingOptions options;
    if (cache_bytes > 0) options.map.cache_bytes = size_t(cache_bytes);
    auto opened = open_shadow_map(location, options);
    if (!opened) return fail(opened.error().code == ErrorCode::invalid_input ? SHADOWTILES_INVALID_INPUT
                                                                              : capi::status_of(opened.error().code),
                             std::string("cannot open ") + location + ": " + opened.error().message);
    auto handle = std::make_unique<shadowtiles_map>();
    handle->meta_json = (*opened)->meta().to_json().dump();
    handle->map = std::move(*opened);
    *out = handle.release();
    return SHADOWTILES_OK;
  });
}

void shadowtiles_close(shadowtiles_map* map) { delete map; }

shadowtiles_status shadowtiles_meta_json(const shadowtiles_map* map, const char** json) {
  if (map == nullptr || json == nullptr) return fail(SHADOWTILES_INVALID_INPUT, "meta_json: map and json must not be NULL");
  *json = map->meta_json.c_str();
  return SHADOWTILES_OK;
}

shadowtiles_status shadowtiles_get_info(const shadowtiles_map* map, shadowtiles_info* info) {
  if (map == nullptr || info == nullptr) return fail(SHADOWTILES_INVALID_INPUT, "get_info: map and info must not be NULL");
  const ShadowMap& m = *map->map;
  info->resolution = m.layout().resolution();
  info->tile_size = m.layout().tile_size();
  info->tiles_per_side = m.layout().tiles_per_side();
  info->levels = m.level_count();
  info->default_bias = m.meta().default_bias;
  info->texel_size = m.frame().texel_size();
  return SHADOWTILES_OK;
}

shadowtiles_status shadowtiles_tile_values(const shadowtiles_map* map, const char* method, uint32_t x, uint32_t y,
                                           float* values, size_t capacity) {
  return guarded([&] {
    if (map == nullptr || values == nullptr) return fail(SHADOWTILES_INVALID_INPUT, "tile_values: map and values must not be NULL");
    const ShadowMap& m = *map->map;
    auto parsed = capi::method_named(m, method);
    if (!parsed) return fail(parsed.error());
    const uint32_t size = m.layout().tile_size();
    if (capacity < size_t(size) * size)
      return fail(SHADOWTILES_INVALID_INPUT, "tile_values: capacity " + std::to_string(capacity) + " < tile_size^2 = " +
                                                 std::to_string(size_t(size) * size));
    auto tile = m.tile(*parsed, TileCoord{x, y});
    if (!tile) return fail(tile.error());
    const float empty = std::numeric_limits<float>::infinity();
    for (uint32_t v = 0; v < size; ++v)
      for (uint32_t u = 0; u < size; ++u) values[size_t(v) * size + u] = *tile ? (*tile)->value(u, v) : empty;
    return SHADOWTILES_OK;
  });
}

shadowtiles_status shadowtiles_surface_points(const shadowtiles_map* map, uint32_t x, uint32_t y, double* points,
                                              uint8_t* hit, size_t capacity) {
  return guarded([&] {
    if (map == nullptr || points == nullptr || hit == nullptr)
      return fail(SHADOWTILES_INVALID_INPUT, "surface_points: map, points and hit must not be NULL");
    const ShadowMap& m = *map->map;
    if (!m.meta().has_method(store::Method::raw))
      return fail(SHADOWTILES_UNSUPPORTED,
                  "surface_points needs the lower-bound depths of method raw, which this build does not store "
                  "(build with -m raw,...)");
    const uint32_t size = m.layout().tile_size();
    if (capacity < size_t(size) * size)
      return fail(SHADOWTILES_INVALID_INPUT, "surface_points: capacity " + std::to_string(capacity) +
                                                 " < tile_size^2 = " + std::to_string(size_t(size) * size));
    auto tile = m.tile(store::Method::raw, TileCoord{x, y});
    if (!tile) return fail(tile.error());
    for (uint32_t v = 0; v < size; ++v) {
      for (uint32_t u = 0; u < size; ++u) {
        const size_t i = size_t(v) * size + u;
        // No geometry along the ray: the lower bound reaches the far plane (or the tile is empty).
        const float lower = *tile ? (*tile)->value(u, v) : 1.0f;
        hit[i] = std::isfinite(lower) && lower < 1.0f;
        const Vec3 world = m.frame().to_world(
            LightSpacePoint{double(x) * size + u + 0.5, double(y) * size + v + 0.5, hit[i] ? double(lower) : 1.0});
        std::memcpy(points + 3 * i, world.data(), sizeof(double) * 3);
      }
    }
    return SHADOWTILES_OK;
  });
}

}  // extern "C"
