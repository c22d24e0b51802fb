// Scenario 5: precision. (a) oahu (100 x 80 km) at 2^18 and 2^20 texels per side: the whole map
// would be 2^36 / 2^40 rays, so a window of tiles around a mountain top is rendered with the real
// pipeline (light frame of the whole map, tile-local BVH, every method's encoder and decoder) and
// judged on receivers sampled on the triangles inside the window. (b) The scene translated by 10^6
// in memory (the loader reads float files, so a translated file would already be rounded before
// our code sees it) must give the same intervals and answers. (c) float32's depth step over each
// scene's depth range, against the texel and the bias.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "builder/accuracy.hpp"
#include "bench/harness/stability_scenarios.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/tile_encoder.hpp"
#include "codec/decoded_tile.hpp"
#include "store/blob.hpp"

namespace shadowtiles::bench {
namespace {

constexpr double kBiasTexels = 2.0, kExitMarginTexels = 4.0;  // the build's defaults

struct WindowTile {
  TileCoord coord;
  TileIntervals intervals;
  std::vector<std::pair<store::Method, std::shared_ptr<const DecodedTile>>> decoded;
  std::map<store::Method, uint64_t> blob_bytes;
};

struct Window {
  LightFrame frame;
  TileLayout layout;
  std::vector<WindowTile> tiles;
  double seconds = 0;
};

Result<Window> render_window(const EmbreeDevice& device, const Scene& scene, const Vec3& light, uint32_t resolution,
                             uint32_t tile_size, const Vec3& centre, unsigned side) {
  auto frame = LightFrame::fit(light, scene.bounds, resolution);
  if (!frame) return frame.error();
  auto layout = TileLayout::make(resolution, tile_size);
  if (!layout) return layout.error();
  Window window{*frame, *layout, {}, 0};
  auto start = std::chrono::steady_clock::now();
  LightSpaceScene light_scene(scene, *frame, *layout);
  DualDepthOptions options;
  options.exit_margin = float(frame->depth_from_world(kExitMarginTexels * frame->texel_size()));
  options.cap_exits_at_receiver_surfaces = true;  // as the build job renders
  DualDepthRenderer renderer(device, light_scene, options);
  const LightSpacePoint c = frame->to_light(centre);
  // The side x side tiles whose common corner is nearest the centre point.
  const int64_t corner_x = std::llround(c.u / tile_size), corner_y = std::llround(c.v / tile_size);
  const int64_t half = side / 2, last = layout->tiles_per_side() - 1;
  for (int64_t y = corner_y - half; y < corner_y - half + side; ++y)
    for (int64_t x = corner_x - half; x < corner_x - half + side; ++x) {
      TileCoord coord{uint32_t(std::clamp<int64_t>(x, 0, last)), uint32_t(std::clamp<int64_t>(y, 0, last))};
      bool seen = false;
      for (const WindowTile& t : window.tiles) seen |= t.coord == coord;
      if (seen) continue;
      auto intervals = renderer.render(coord);
      if (!intervals) return intervals.error();
      WindowTile tile{coord, std::move(*intervals), {}, {}};
      TileEncodeOptions encode_options;
      encode_options.map_resolution = resolution;
      auto encoding = encode_tile(supported_methods(), tile.intervals, encode_options);
      if (!encoding) return encoding.error();
      for (const EncodedPayload& p : encoding->payloads) {
        auto decoded = decode_tile(p.method, p.payload);
        if (!decoded) return decoded.error();
        tile.decoded.push_back({p.method, *decoded});
        tile.blob_bytes[p.method] = store::encode_blob(p.method, p.payload).size();
      }
      window.tiles.push_back(std::move(tile));
    }
  window.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return window;
}

// The window tile holding a light-space point, or null.
const WindowTile* tile_at(const Window& window, const LightSpacePoint& p) {
  if (!(p.u >= 0 && p.v >= 0)) return nullptr;
  const uint32_t size = window.layout.tile_size();
  TileCoord coord{uint32_t(p.u / size), uint32_t(p.v / size)};
  for (const WindowTile& t : window.tiles)
    if (t.coord == coord) return &t;
  return nullptr;
}

// A scene of the triangles that may cover the window's texels (for sampling receivers there).
Scene window_scene(const Scene& scene, const Window& window) {
  LightSpaceScene light_scene(scene, window.frame, window.layout);
  std::set<uint32_t> triangles;
  for (const WindowTile& t : window.tiles)
    for (uint32_t tri : light_scene.triangles_of(t.coord)) triangles.insert(tri);
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> faces;
  for (uint32_t tri : triangles) {
    for (int k = 0; k < 3; ++k) vertices.push_back(scene.vertices[scene.triangles[tri][k]]);
    const uint32_t base = uint32_t(vertices.size() - 3);
    faces.push_back({base, base + 1, base + 2});
  }
  Scene sub;
  sub.add_mesh("window", vertices, faces);
  return sub;
}

Status window_rows(StabilityContext& context, const Scene& scene, uint32_t resolution, unsigned side,
                   ScenarioResult& result) {
  const Vec3 light = *light_direction_from_sun(135, 30, UpAxis::z);
  // Centre: the highest of the scene's receivers (a mountain top, so ridges cast shadows nearby).
  auto loaded = context.shared_scene("oahu/oahu_w158n21.ply", UpAxis::z, true);
  if (!loaded) return loaded.error();
  Vec3 centre = (*loaded)->receivers.front().position;
  for (const Receiver& r : (*loaded)->receivers)
    if (r.position[2] > centre[2]) centre = r.position;
  const uint32_t tile_size = 1024;
  auto window = render_window(context.device(), scene, light, resolution, tile_size, centre, side);
  if (!window) return window.error();
  Scene sub = window_scene(scene, *window);
  std::vector<Receiver> receivers;
  for (const Receiver& r : sample_receivers(sub, context.options().receivers * 4, context.options().seed))
    if (tile_at(*window, window->frame.to_light(r.position))) receivers.push_back(r);
  GroundTruth truth(context.device(), scene, light);
  // The default epsilon (1e-5 of the 130 km diagonal, 1.3 m) is ten texels at 2^20; a quarter texel
  // is still far above float's step at 50 km from the centre (4 mm).
  truth.set_epsilon(0.25 * window->frame.texel_size());
  const std::vector<uint8_t> lit = point_truth(truth, receivers);
  const double bias = window->frame.depth_from_world(kBiasTexels * window->frame.texel_size());
  const std::string subject = fmt::format("oahu window {}x{} tiles of 1024^2", side, side);
  std::vector<uint8_t> raw_answers(receivers.size());
  for (store::Method method : supported_methods()) {
    StabilityRow row;
    row.subject = subject;
    row.method = store::method_name(method);
    row.resolution = resolution;
    row.build_seconds = window->seconds;
    for (const WindowTile& t : window->tiles) row.bytes += t.blob_bytes.at(method);
    for (size_t i = 0; i < receivers.size(); ++i) {
      const LightSpacePoint p = window->frame.to_light(receivers[i].position);
      const WindowTile* t = tile_at(*window, p);
      const uint32_t u = uint32_t(p.u) % tile_size, v = uint32_t(p.v) % tile_size;
      std::shared_ptr<const DecodedTile> decoded;
      for (auto& [m, d] : t->decoded)
        if (m == method) decoded = d;
      const bool answer = decoded->lit(u, v, float(p.depth - bias));
      ++row.receivers;
      row.false_lit += answer && !lit[i];
      row.false_shadowed += !answer && lit[i];
      if (method == store::Method::raw) raw_answers[i] = answer;
      else if (answer != bool(raw_answers[i])) {
        ++row.differs_from_raw;
        row.worse_than_raw += bool(raw_answers[i]) == bool(lit[i]);
      }
    }
    row.note = fmt::format("texel {:.3g} m; bytes: window tiles only; seconds: window render + encode (all methods)",
                           window->frame.texel_size());
    result.rows.push_back(row);
  }
  spdlog::info("  oahu {}^2 window: {} receivers, {:.1f} s", resolution, receivers.size(), window->seconds);
  result.check(fmt::format("oahu {}^2: the window holds receivers", resolution), receivers.size() > 100,
               fmt::format("{} receivers", receivers.size()));
  return {};
}

Status translation_check(StabilityContext& context, const StabilityContext::LoadedScene& loaded, uint32_t resolution,
                         ScenarioResult& result) {
  const double offset = 1e6;
  Scene moved = loaded.scene;
  for (Vec3& p : moved.vertices)
    for (double& x : p) x += offset;
  for (int k = 0; k < 3; ++k) moved.bounds.min[k] += offset, moved.bounds.max[k] += offset;
  const Vec3 light = *light_direction_from_sun(135, 30, UpAxis::z);
  const uint32_t tile_size = std::min<uint32_t>(resolution, 1024);
  auto frame_a = LightFrame::fit(light, loaded.scene.bounds, resolution);
  auto frame_b = LightFrame::fit(light, moved.bounds, resolution);
  if (!frame_a) return frame_a.error();
  if (!frame_b) return frame_b.error();
  auto layout = TileLayout::make(resolution, tile_size);
  if (!layout) return layout.error();
  LightSpaceScene scene_a(loaded.scene, *frame_a, *layout), scene_b(moved, *frame_b, *layout);
  DualDepthOptions options;
  options.exit_margin = float(frame_a->depth_from_world(kExitMarginTexels * frame_a->texel_size()));
  options.cap_exits_at_receiver_surfaces = true;
  DualDepthRenderer renderer_a(context.device(), scene_a, options), renderer_b(context.device(), scene_b, options);
  uint64_t texels = 0, different = 0, answers = 0, answer_mismatches = 0;
  double max_difference = 0;
  const double bias = frame_a->depth_from_world(kBiasTexels * frame_a->texel_size());
  for (uint32_t ty = 0; ty < layout->tiles_per_side(); ++ty)
    for (uint32_t tx = 0; tx < layout->tiles_per_side(); ++tx) {
      auto a = renderer_a.render({tx, ty});
      auto b = renderer_b.render({tx, ty});
      if (!a) return a.error();
      if (!b) return b.error();
      for (size_t i = 0; i < a->texels.size(); ++i) {
        const DepthInterval &x = a->texels[i], &y = b->texels[i];
        ++texels;
        if (x.lower != y.lower || x.upper != y.upper) ++different;
        if (x.lower < 1) max_difference = std::max(max_difference, double(std::fabs(x.lower - y.lower)));
      }
      for (const Receiver& r : loaded.receivers) {
        LightSpacePoint pa = frame_a->to_light(r.position);
        LightSpacePoint pb = frame_b->to_light({r.position[0] + offset, r.position[1] + offset, r.position[2] + offset});
        if (uint32_t(pa.u) / tile_size != tx || uint32_t(pa.v) / tile_size != ty) continue;
        ++answers;
        const bool lit_a = float(pa.depth - bias) <= a->at(uint32_t(pa.u) % tile_size, uint32_t(pa.v) % tile_size).lower;
        if (!(pb.u >= 0 && pb.v >= 0 && pb.u < resolution && pb.v < resolution)) {
          ++answer_mismatches;
          continue;
        }
        const bool lit_b = float(pb.depth - bias) <= b->at(uint32_t(pb.u) % tile_size, uint32_t(pb.v) % tile_size).lower;
        answer_mismatches += lit_a != lit_b;
      }
    }
  result.tables.push_back({fmt::format("oahu translated by 10^6 on every axis, {}^2 (sun 135, 30)", resolution),
                           {"texels", "texels whose interval differs", "max |lower difference| (normalised)",
                            "receivers", "raw answers that differ"},
                           {{std::to_string(texels), std::to_string(different), fmt::format("{:.3g}", max_difference),
                             std::to_string(answers), std::to_string(answer_mismatches)}}});
  result.check("oahu + 10^6: same answers", answer_mismatches == 0 && answers > 0,
               fmt::format("{} of {} answers differ; {} of {} texels differ (max {:.3g})", answer_mismatches, answers,
                           different, texels, max_difference));
  return {};
}

void depth_precision_table(StabilityContext& context, ScenarioResult& result) {
  StabilityTable table{"float32 depth precision (depth normalised to [0, 1] over the depth range; "
                       "step = 2^-24 x range just below 1)",
                       {"scene", "sun", "depth range (world)", "float32 step at depth 1 (world)",
                        "texel at 2^18", "texel at 2^20", "step / bias at 2^20"},
                       {}};
  struct Subject {
    std::string name, file;
    UpAxis up;
    double elevation;
  };
  for (const Subject& s : {Subject{"oahu", "oahu/oahu_w158n21.ply", UpAxis::z, 30},
                           Subject{"oahu", "oahu/oahu_w158n21.ply", UpAxis::z, 2},
                           Subject{"terragen", "terragen/RealisticTerrain.ter", UpAxis::z, 30},
                           Subject{"nefertiti", "nefertiti/nefertiti.obj", UpAxis::z, 45}}) {
    auto scene = context.shared_scene(s.file, s.up, s.name != "nefertiti");
    if (!scene) continue;
    const Vec3 light = *light_direction_from_sun(135, s.elevation, s.up);
    auto f18 = LightFrame::fit(light, (*scene)->scene.bounds, 1u << 18);
    auto f20 = LightFrame::fit(light, (*scene)->scene.bounds, 1u << 20);
    if (!f18 || !f20) continue;
    const double step = std::ldexp(1.0, -24) * f20->depth_range();
    table.rows.push_back({s.name, fmt::format("135, {:g}", s.elevation), fmt::format("{:.6g}", f20->depth_range()),
                          fmt::format("{:.3g}", step), fmt::format("{:.3g}", f18->texel_size()),
                          fmt::format("{:.3g}", f20->texel_size()),
                          fmt::format("{:.3g}", step / (kBiasTexels * f20->texel_size()))});
    result.check(fmt::format("{} sun {:g}: float32 depth step below the 2^20 bias", s.name, s.elevation),
                 step < kBiasTexels * f20->texel_size(),
                 fmt::format("step {:.3g} vs bias {:.3g}", step, kBiasTexels * f20->texel_size()));
  }
  result.tables.push_back(std::move(table));
}

}  // namespace

Result<ScenarioResult> run_precision(StabilityContext& context) {
  ScenarioResult result("precision", "5. Precision");
  const bool quick = context.options().quick;
  const unsigned side = quick ? 1 : 2;
  auto oahu = context.shared_scene("oahu/oahu_w158n21.ply", UpAxis::z, true);
  if (!oahu) return oahu.error();
  result.setup = fmt::format(
      "oahu, sun 135, 30, heightfield; 2^18 and 2^20: a window of {0}x{0} tiles of 1024^2 around the highest "
      "receiver, rendered and encoded with the real pipeline, judged on receivers sampled on the window's "
      "triangles (ground-truth epsilon a quarter texel); translation: whole map at {1}^2",
      side, quick ? 1024 : 4096);
  for (uint32_t resolution : {1u << 18, 1u << 20})
    if (Status s = window_rows(context, (*oahu)->scene, resolution, side, result); !s) return s.error();
  if (Status s = translation_check(context, **oahu, quick ? 1024 : 4096, result); !s) return s.error();
  depth_precision_table(context, result);
  return result;
}

}  // namespace shadowtiles::bench
