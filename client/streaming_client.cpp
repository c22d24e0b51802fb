#include "client/streaming_client.hpp"

#include <algorithm>
#include <cmath>

namespace shadowtiles {
namespace {

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// A half-space {p : dot(p - origin, normal) <= 0}.
struct Plane {
  Vec3 origin, normal;
  bool outside(const Vec3& p) const { return dot(minus(p, origin), normal) > 0; }
};

}  // namespace

bool is_server_url(std::string_view location) {
  return location.starts_with("http://") || location.starts_with("https://");
}

Result<std::unique_ptr<ShadowMap>> open_shadow_map(const std::string& location, const StreamingOptions& options) {
  if (!is_server_url(location)) return ShadowMap::open(std::filesystem::path(location), options.map);
  auto source = HttpTileSource::open(location, options.http);
  if (!source) return source.error();
  return ShadowMap::open(std::shared_ptr<const TileSource>(std::move(*source)), options.map);
}

const HttpTileSource* http_source(const ShadowMap& map) {
  return dynamic_cast<const HttpTileSource*>(&map.source());
}

std::vector<TileCoord> tiles_around(const ShadowMap& map, const Vec3& world, uint32_t radius_texels) {
  std::vector<TileCoord> tiles;
  if (!map.tile_of(world)) return tiles;
  const LightSpacePoint light = map.frame().to_light(world);
  const int64_t side = map.layout().resolution(), size = map.layout().tile_size();
  const int64_t u = int64_t(light.u), v = int64_t(light.v), r = radius_texels;
  const int64_t tx0 = std::max<int64_t>(u - r, 0) / size, tx1 = std::min<int64_t>(u + r, side - 1) / size;
  const int64_t ty0 = std::max<int64_t>(v - r, 0) / size, ty1 = std::min<int64_t>(v + r, side - 1) / size;
  for (int64_t ty = ty0; ty <= ty1; ++ty)
    for (int64_t tx = tx0; tx <= tx1; ++tx) tiles.push_back({uint32_t(tx), uint32_t(ty)});
  return tiles;
}

std::vector<TileCoord> tiles_under_frustum(const ShadowMap& map, const CameraView& camera, double far_distance) {
  std::vector<TileCoord> tiles;
  auto basis = CameraBasis::of(camera);
  if (!basis) return tiles;
  // Corner directions of the view; each side plane holds the eye and two neighbouring corners.
  const double sx = basis->tan_half_fov * basis->aspect, sy = basis->tan_half_fov;
  auto corner = [&](double a, double b) {
    return Vec3{basis->forward[0] + a * sx * basis->right[0] + b * sy * basis->up[0],
                basis->forward[1] + a * sx * basis->right[1] + b * sy * basis->up[1],
                basis->forward[2] + a * sx * basis->right[2] + b * sy * basis->up[2]};
  };
  const Vec3 corners[4] = {corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)};
  std::vector<Plane> planes;
  planes.push_back({camera.eye, {-basis->forward[0], -basis->forward[1], -basis->forward[2]}});
  for (int i = 0; i < 4; ++i) {
    Vec3 normal = cross(corners[i], corners[(i + 1) % 4]);
    if (dot(normal, basis->forward) > 0) normal = {-normal[0], -normal[1], -normal[2]};
    planes.push_back({camera.eye, normal});
  }
  if (far_distance > 0) {
    const Vec3 far_point{camera.eye[0] + basis->forward[0] * far_distance,
                         camera.eye[1] + basis->forward[1] * far_distance,
                         camera.eye[2] + basis->forward[2] * far_distance};
    planes.push_back({far_point, basis->forward});
  }
  const LightFrame& frame = map.frame();
  const uint32_t per_side = map.layout().tiles_per_side();
  const double size = map.layout().tile_size();
  std::vector<std::pair<double, TileCoord>> seen;
  for (uint32_t ty = 0; ty < per_side; ++ty) {
    for (uint32_t tx = 0; tx < per_side; ++tx) {
      Vec3 box[8];
      for (int c = 0; c < 8; ++c)
        box[c] = frame.to_world({(tx + (c & 1)) * size, (ty + ((c >> 1) & 1)) * size, double((c >> 2) & 1)});
      bool culled = std::any_of(planes.begin(), planes.end(), [&](const Plane& plane) {
        return std::all_of(std::begin(box), std::end(box), [&](const Vec3& p) { return plane.outside(p); });
      });
      if (culled) continue;
      // Distance of the column's centre line from the camera's line of sight, for the order.
      const Vec3 centre = frame.to_world({(tx + 0.5) * size, (ty + 0.5) * size, 0.5});
      const Vec3 offset = minus(centre, camera.eye);
      const Vec3 off_axis = cross(offset, basis->forward);
      seen.push_back({dot(off_axis, off_axis) + dot(offset, offset) * 1e-3, {tx, ty}});
    }
  }
  std::sort(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [distance, tile] : seen) tiles.push_back(tile);
  return tiles;
}

Status prefetch_around(const ShadowMap& map, store::Method method, const Vec3& world, uint32_t radius_texels) {
  auto tiles = tiles_around(map, world, radius_texels);
  return map.prefetch(method, tiles);
}

Status prefetch_frustum(const ShadowMap& map, store::Method method, const CameraView& camera, double far_distance) {
  auto tiles = tiles_under_frustum(map, camera, far_distance);
  return map.prefetch(method, tiles);
}

}  // namespace shadowtiles
