// Streaming client figures (printed, not asserted): for one 1280x720 frame of a build's scene from
// the default viewpoint,
//   - lookups/s decoding locally, 1 and 2 threads, coherent screen order (point and PCF 3x3), with
//     the tiles already decoded (warm) — the client's steady state;
//   - tiles and bytes the frame needs (blob bytes, what a cold client downloads);
//   - time to first frame from a cold cache: open + fetch + decode + lookups, from the store and,
//     when a server URL is given, over HTTP (no disk cache).
// Usage: bench_streaming STORE [SERVER_URL] [SCENE]   (SCENE defaults to the path the build recorded)
// e.g.   shadowtiles serve out/haus.store --port 8080 &
//        build/bench/bench_streaming out/haus.store http://127.0.0.1:8080
#include <chrono>
#include <cstdio>
#include <set>
#include <string>
#include <thread>

#include "builder/frame_renderer.hpp"
#include "builder/frame_shading.hpp"
#include "builder/scene_loader.hpp"
#include "client/streaming_client.hpp"

namespace shadowtiles {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Lookups/s over the frame's sunward pixels, `threads` workers on interleaved rows.
double lookup_rate(const ShadowMap& map, store::Method method, unsigned pcf, const FrameHits& frame,
                   unsigned threads) {
  uint64_t lookups = 0;
  const std::vector<float> facing = sun_facing(frame, map.frame().direction());
  for (float f : facing) lookups += f > 0;
  double best = 0;
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto start = std::chrono::steady_clock::now();
    auto visibility = visibility_from_map(map, method, pcf, frame, threads);
    const double seconds = seconds_since(start);
    if (!visibility) {
      std::fprintf(stderr, "lookups failed: %s\n", visibility.error().message.c_str());
      return 0;
    }
    best = std::max(best, double(lookups) / seconds);
  }
  return best;
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s STORE [SERVER_URL] [SCENE]\n", argv[0]);
    return 2;
  }
  const std::string store = argv[1];
  const std::string server = argc > 2 ? argv[2] : "";
  auto map = open_shadow_map(store, {});
  if (!map) {
    std::fprintf(stderr, "%s\n", map.error().message.c_str());
    return 1;
  }
  const StoreMeta& meta = (*map)->meta();
  const store::Method method = (*map)->default_method();
  const Vec3 light = (*map)->frame().direction();
  const UpAxis up = -light[1] > -light[2] ? UpAxis::y : UpAxis::z;
  LoadOptions load;
  load.up = up;
  load.heightfield_meshes = meta.heightfield_meshes;
  auto scene = load_scene(argc > 3 ? argv[3] : meta.scene_path, load);
  if (!scene) {
    std::fprintf(stderr, "%s\n", scene.error().message.c_str());
    return 1;
  }
  auto device = EmbreeDevice::create();
  if (!device) return 1;
  FrameRenderer renderer(*device, *scene);
  const CameraView camera = default_camera(scene->bounds, up, 1280, 720);
  auto frame = renderer.trace(camera);
  if (!frame) return 1;
  std::printf("store %s: %u^2 in %u^2 tiles, method %s; frame 1280x720, %llu pixels see the scene\n", store.c_str(),
              meta.resolution, meta.tile_size, store::method_name(method),
              static_cast<unsigned long long>(frame->hit_count()));

  // Cold, local: open + decode + lookups of the whole frame.
  {
    const auto start = std::chrono::steady_clock::now();
    auto cold = open_shadow_map(store, {});
    if (!cold) return 1;
    auto visibility = visibility_from_map(**cold, method, 1, *frame, 2);
    if (!visibility) return 1;
    std::printf("first frame, cold, local store: %.3f s (%llu tiles decoded)\n", seconds_since(start),
                static_cast<unsigned long long>((*cold)->cache_stats().misses));
  }
  // The tiles the frame needs and their blob bytes (exactly what a cold HTTP client downloads).
  {
    std::set<TileCoord> tiles;
    const std::vector<float> facing = sun_facing(*frame, light);
    for (size_t i = 0; i < facing.size(); ++i)
      if (facing[i] > 0)
        if (auto t = (*map)->tile_of(frame->pixels[i].position)) tiles.insert(*t);
    uint64_t bytes = 0, stored = 0;
    for (const TileCoord& t : tiles) {
      auto blob = (*map)->source().tile_blob({method, (*map)->layout().tile_level(), t.x, t.y});
      if (blob && blob->has_value()) {
        bytes += (*blob)->size();
        ++stored;
      }
    }
    std::printf("frame needs %zu of %llu tiles (%llu stored, the rest empty), %.2f MiB of blobs\n", tiles.size(),
                static_cast<unsigned long long>((*map)->layout().tile_count()),
                static_cast<unsigned long long>(stored), double(bytes) / (1 << 20));
  }
  // Warm lookups/s, coherent screen order.
  for (unsigned pcf : {1u, 3u})
    for (unsigned threads : {1u, 2u})
      std::printf("lookups/s, warm, pcf %u, %u thread(s): %.3g\n", pcf, threads,
                  lookup_rate(**map, method, pcf, *frame, threads));

  if (!server.empty()) {
    const auto start = std::chrono::steady_clock::now();
    auto remote = open_shadow_map(server, {});
    if (!remote) {
      std::fprintf(stderr, "%s\n", remote.error().message.c_str());
      return 1;
    }
    auto visibility = visibility_from_map(**remote, method, 1, *frame, 2);
    if (!visibility) {
      std::fprintf(stderr, "%s\n", visibility.error().message.c_str());
      return 1;
    }
    const HttpFetchStats fetched = http_source(**remote)->stats();
    std::printf("first frame, cold, over HTTP from %s: %.3f s; %llu tiles, %.2f MiB in %llu requests\n",
                server.c_str(), seconds_since(start), static_cast<unsigned long long>(fetched.tiles_fetched),
                double(fetched.bytes_received) / (1 << 20), static_cast<unsigned long long>(fetched.requests));
  }
  return 0;
}

}  // namespace
}  // namespace shadowtiles

int main(int argc, char** argv) { return shadowtiles::run(argc, argv); }
