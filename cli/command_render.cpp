// `shadowtiles render (--server URL | --store STORE) [--scene SCENE] --out frame.png ...`: a picture
// of the scene shadowed by the build, so a person sees that the shadows are right. Primary rays with
// Embree (builder/frame_renderer.hpp), Lambert shading from the build's sun, shadows from the
// streaming client's lookups (receiver = hit point, the build's bias); `--ground-truth` also renders
// the frame with Embree occlusion rays and prints the disagreement; `--diff` writes where they differ.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "builder/frame_renderer.hpp"
#include "builder/frame_shading.hpp"
#include "builder/ground_truth.hpp"
#include "builder/png_image.hpp"
#include "builder/scene_loader.hpp"
#include "cli/cli_parsing.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "client/streaming_client.hpp"

namespace shadowtiles::cli {
namespace {

struct RenderFlags {
  std::string server, store, scene, camera, look_at, size = "1280x720", method, out, diff, up, disk_cache;
  unsigned pcf = 1;
  double fov = 50;
  unsigned threads = 2;
  uint64_t cache_mib = 512;
  bool ground_truth = false;
  double max_disagreement = -1;
  bool json = false;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Result<std::pair<uint32_t, uint32_t>> parse_size(const std::string& text) {
  unsigned w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    return make_error(ErrorCode::invalid_input, "--size must be WxH with 1..16384 each, e.g. 1280x720");
  return std::pair{uint32_t(w), uint32_t(h)};
}

// The scene's up axis: given, or the axis (y or z) the sun stands highest above. Builds do not
// record it; a sun above the horizon points up along it more than along the other.
UpAxis infer_up(const Vec3& light_direction) { return -light_direction[1] > -light_direction[2] ? UpAxis::y : UpAxis::z; }

std::filesystem::path truth_path_for(const std::filesystem::path& out) {
  return out.parent_path() / (out.stem().string() + ".truth" + out.extension().string());
}

int run(const RenderFlags& flags) {
  if (flags.server.empty() == flags.store.empty()) {
    spdlog::error("give --server URL or --store STORE (one of them)");
    return kInvalidInput;
  }
  auto size = parse_size(flags.size);
  if (!size) { spdlog::error("{}", size.error().message); return kInvalidInput; }
  if (flags.pcf == 0 || flags.pcf % 2 == 0 || flags.pcf > ShadowMap::kMaxPcfKernel) {
    spdlog::error("--pcf must be odd, 1..{}", ShadowMap::kMaxPcfKernel);
    return kInvalidInput;
  }
  if (flags.camera.empty() != flags.look_at.empty()) {
    spdlog::error("--camera and --look-at go together");
    return kInvalidInput;
  }
  const auto start = std::chrono::steady_clock::now();

  StreamingOptions options;
  options.map.cache_bytes = size_t(flags.cache_mib) << 20;
  options.http.disk_cache_dir = flags.disk_cache;
  const std::string location = flags.server.empty() ? flags.store : flags.server;
  auto map = open_shadow_map(location, options);
  if (!map) { spdlog::error("cannot open {}: {}", location, map.error().message); return exit_code_for(map.error()); }
  const StoreMeta& meta = (*map)->meta();
  store::Method method = (*map)->default_method();
  if (!flags.method.empty()) {
    auto parsed = store::parse_method(flags.method);
    if (!parsed) { spdlog::error("--method: {}", parsed.error().message); return kInvalidInput; }
    method = *parsed;
  }
  if (!meta.has_method(method)) {
    spdlog::error("method '{}' is not in this build", store::method_name(method));
    return kInvalidInput;
  }

  // The scene as the build loaded it (path and heightfield names from meta unless --scene is given).
  UpAxis up = infer_up((*map)->frame().direction());
  if (!flags.up.empty()) {
    auto parsed = parse_up_axis(flags.up);
    if (!parsed) { spdlog::error("{}", parsed.error().message); return kInvalidInput; }
    up = *parsed;
  }
  LoadOptions load;
  load.up = up;
  load.heightfield_meshes = meta.heightfield_meshes;
  const std::string scene_path = flags.scene.empty() ? meta.scene_path : flags.scene;
  if (flags.scene.empty() && !std::filesystem::exists(scene_path)) {
    spdlog::error("the build's scene {} is not here (paths are as the build was given them): give --scene", scene_path);
    return kInvalidInput;
  }
  auto scene = load_scene(scene_path, load);
  if (!scene) { spdlog::error("{}", scene.error().message); return exit_code_for(scene.error()); }
  if (scene->triangle_count() != meta.scene_triangles)
    spdlog::warn("{} has {} triangles, the build had {}: is it the same scene?", scene_path, scene->triangle_count(),
                 meta.scene_triangles);

  CameraView camera = default_camera(scene->bounds, up, size->first, size->second);
  camera.vertical_fov_deg = flags.fov;
  if (!flags.camera.empty()) {
    auto eye = parse_vec3(flags.camera, "--camera");
    auto target = parse_vec3(flags.look_at, "--look-at");
    if (!eye || !target) { spdlog::error("{}", (!eye ? eye : target).error().message); return kInvalidInput; }
    camera.eye = *eye;
    camera.target = *target;
  }

  auto device = EmbreeDevice::create();
  if (!device) { spdlog::error("{}", device.error().message); return kFailure; }
  FrameRenderer renderer(*device, *scene);
  const auto trace_start = std::chrono::steady_clock::now();
  auto frame = renderer.trace(camera, flags.threads);
  if (!frame) { spdlog::error("{}", frame.error().message); return exit_code_for(frame.error()); }
  const double trace_seconds = seconds_since(trace_start);

  const auto lookup_start = std::chrono::steady_clock::now();
  auto visibility = visibility_from_map(**map, method, flags.pcf, *frame, flags.threads);
  if (!visibility) {
    spdlog::error("shadow lookups failed: {}", visibility.error().message);
    return exit_code_for(visibility.error());
  }
  const double lookup_seconds = seconds_since(lookup_start);
  const Vec3& light = (*map)->frame().direction();
  if (Status s = write_png(flags.out, shade_frame(*frame, *visibility, light)); !s) {
    spdlog::error("{}", s.error().message);
    return exit_code_for(s.error());
  }

  nlohmann::json summary = {{"out", flags.out},
                            {"source", (*map)->source().describe()},
                            {"method", store::method_name(method)},
                            {"pcf", flags.pcf},
                            {"size", {frame->width, frame->height}},
                            {"camera", {{"eye", camera.eye}, {"look_at", camera.target}, {"fov", camera.vertical_fov_deg}}},
                            {"hit_pixels", frame->hit_count()},
                            {"trace_seconds", trace_seconds},
                            {"lookup_seconds", lookup_seconds}};
  const CacheStats cache = (*map)->cache_stats();
  summary["cache"] = {{"tiles_loaded", cache.misses}, {"hits", cache.hits}, {"bytes", cache.bytes}};
  if (const HttpTileSource* http = http_source(**map)) {
    const HttpFetchStats fetched = http->stats();
    summary["fetched"] = {{"requests", fetched.requests},       {"tiles", fetched.tiles_fetched},
                          {"bytes", fetched.bytes_received},    {"retries", fetched.retries},
                          {"not_modified", fetched.not_modified}, {"disk_hits", fetched.disk_hits}};
  }

  int exit_code = kOk;
  if (flags.ground_truth || !flags.diff.empty()) {
    const auto truth_start = std::chrono::steady_clock::now();
    GroundTruth truth(*device, *scene, light);
    const std::vector<float> truth_visibility = visibility_from_ground_truth(truth, *frame, light, flags.threads);
    const std::filesystem::path truth_out = truth_path_for(flags.out);
    if (Status s = write_png(truth_out, shade_frame(*frame, truth_visibility, light)); !s) {
      spdlog::error("{}", s.error().message);
      return exit_code_for(s.error());
    }
    FrameDiff diff = diff_frames(*frame, *visibility, truth_visibility, light);
    if (!flags.diff.empty())
      if (Status s = write_png(flags.diff, diff.image); !s) {
        spdlog::error("{}", s.error().message);
        return exit_code_for(s.error());
      }
    summary["ground_truth"] = {{"out", truth_out.string()},
                               {"diff", flags.diff},
                               {"seconds", seconds_since(truth_start)},
                               {"compared_pixels", diff.compared},
                               {"false_lit", diff.false_lit},
                               {"false_shadowed", diff.false_shadowed},
                               {"disagreement", diff.fraction_of_compared()},
                               {"disagreement_of_frame", diff.fraction_of_frame()}};
    if (flags.max_disagreement >= 0 && diff.fraction_of_compared() > flags.max_disagreement) exit_code = kCheckFailed;
  }
  summary["seconds"] = seconds_since(start);

  if (flags.json) {
    std::cout << summary.dump(2) << "\n";
  } else {
    std::printf("wrote %s: %ux%u, %s, pcf %u, %llu pixels see the scene (trace %.2f s, lookups %.2f s)\n",
                flags.out.c_str(), frame->width, frame->height, store::method_name(method), flags.pcf,
                static_cast<unsigned long long>(frame->hit_count()), trace_seconds, lookup_seconds);
    if (summary.contains("fetched"))
      std::printf("fetched %llu tiles, %.2f MiB in %llu requests from %s\n",
                  static_cast<unsigned long long>(summary["fetched"]["tiles"].get<uint64_t>()),
                  double(summary["fetched"]["bytes"].get<uint64_t>()) / (1 << 20),
                  static_cast<unsigned long long>(summary["fetched"]["requests"].get<uint64_t>()),
                  (*map)->source().describe().c_str());
    if (summary.contains("ground_truth")) {
      const auto& g = summary["ground_truth"];
      std::printf("ground truth: %s; disagreement %.4f%% of %llu sunward pixels (%llu false lit, %llu false "
                  "shadowed), %.4f%% of the frame%s%s\n",
                  g["out"].get<std::string>().c_str(), 100 * g["disagreement"].get<double>(),
                  static_cast<unsigned long long>(g["compared_pixels"].get<uint64_t>()),
                  static_cast<unsigned long long>(g["false_lit"].get<uint64_t>()),
                  static_cast<unsigned long long>(g["false_shadowed"].get<uint64_t>()),
                  100 * g["disagreement_of_frame"].get<double>(), flags.diff.empty() ? "" : "; diff: ",
                  flags.diff.c_str());
    }
  }
  if (exit_code == kCheckFailed)
    spdlog::error("disagreement {:.4f} exceeds --max-disagreement {}", summary["ground_truth"]["disagreement"].get<double>(),
                  flags.max_disagreement);
  return exit_code;
}

}  // namespace

void add_render_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<RenderFlags>();
  CLI::App* cmd = app.add_subcommand("render", "Render a frame of a scene shadowed by a server's or a store's build");
  cmd->add_option("--server", flags->server, "Stream the build from this server (http://host:port)");
  cmd->add_option("--store", flags->store, "Read the build from this store directory");
  cmd->add_option("--scene", flags->scene, "Scene file (default: the path the build recorded)");
  cmd->add_option("--camera", flags->camera, "Eye position X,Y,Z (with --look-at; default: a view of the whole scene)");
  cmd->add_option("--look-at", flags->look_at, "Point the camera looks at, X,Y,Z");
  cmd->add_option("--fov", flags->fov, "Vertical field of view, degrees")->capture_default_str();
  cmd->add_option("--up", flags->up, "Scene up axis z|y (default: the axis the sun stands highest above)");
  cmd->add_option("--size", flags->size, "Frame size WxH")->capture_default_str();
  cmd->add_option("--pcf", flags->pcf, "PCF kernel side (odd; 1 = point lookups)")->capture_default_str();
  cmd->add_option("--method,-m", flags->method, "Method to answer from (default: the first stored)");
  cmd->add_option("--out,-o", flags->out, "PNG file to write")->required();
  cmd->add_flag("--ground-truth", flags->ground_truth,
                "Also render with Embree occlusion rays (to OUT's name + .truth.png) and print the disagreement");
  cmd->add_option("--diff", flags->diff, "PNG marking pixels where the lookups and the ground truth disagree "
                                         "(red: false lit, blue: false shadowed); implies --ground-truth");
  cmd->add_option("--max-disagreement", flags->max_disagreement,
                  "Exit 3 when the disagreement fraction (of sunward pixels) exceeds this");
  cmd->add_option("--threads", flags->threads, "Worker threads for rays and lookups")->capture_default_str();
  cmd->add_option("--cache-mib", flags->cache_mib, "Decoded tile cache, MiB")->capture_default_str();
  cmd->add_option("--disk-cache", flags->disk_cache, "Directory caching fetched tiles between runs (servers only)");
  cmd->add_flag("--json", flags->json, "Print the summary as JSON");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
