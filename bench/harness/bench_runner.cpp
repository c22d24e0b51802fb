#include "bench/harness/bench_runner.hpp"
#include "bench/harness/http_cold_start.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include <spdlog/spdlog.h>

#include "builder/accuracy.hpp"
#include "bench/harness/camera_receivers.hpp"
#include "builder/solid_interior.hpp"
#include "bench/harness/lookup_rate.hpp"
#include "bench/harness/machine_info.hpp"
#include "bench/harness/store_sizes.hpp"
#include "codec/morton.hpp"
#include "builder/build_job.hpp"
#include "builder/scene_loader.hpp"
#include "builder/tile_encoder.hpp"

namespace shadowtiles::bench {
namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;

double stat(const nlohmann::json& stats, const char* group, const char* key) {
  if (!stats.contains(group) || !stats[group].contains(key) || !stats[group][key].is_number()) return 0.0;
  return stats[group][key].get<double>();
}

// The three visiting orders of the lookup-rate figures.
struct PointOrders {
  std::vector<Vec3> rows;    // uniform receivers sorted along light-space rows (v, then u)
  std::vector<Vec3> random;  // the same receivers shuffled
  std::vector<Vec3> camera;  // camera pixels in screen order
};

PointOrders make_orders(const LightFrame& frame, const std::vector<Receiver>& uniform,
                        const std::vector<Receiver>& camera, uint64_t seed) {
  PointOrders orders;
  std::vector<std::pair<std::pair<double, double>, Vec3>> keyed;
  for (const Receiver& r : uniform) {
    LightSpacePoint p = frame.to_light(r.position);
    keyed.push_back({{std::floor(p.v), p.u}, r.position});
  }
  std::sort(keyed.begin(), keyed.end(), [](auto& a, auto& b) { return a.first < b.first; });
  for (auto& k : keyed) orders.rows.push_back(k.second);
  orders.random = orders.rows;
  std::shuffle(orders.random.begin(), orders.random.end(), std::mt19937_64(seed));
  for (const Receiver& r : camera) orders.camera.push_back(r.position);
  return orders;
}

struct SceneData {
  Scene scene;
  Vec3 light{};
  std::vector<Receiver> uniform, camera;
  std::vector<Vec3> batch;  // config.batch_points surface points, shuffled
  std::vector<uint8_t> uniform_truth, camera_truth;
  size_t uniform_inside_solids = 0, camera_inside_solids = 0;  // left out: no receiver places
};

// Everything measured on one built store, per method: one row each.
Status measure_store(const BenchConfig& config, const SceneSpec& spec, uint32_t resolution, SceneData& data,
                     const GroundTruth& truth, const std::vector<store::Method>& methods,
                     const nlohmann::json& build_stats, double build_peak_rss, const std::filesystem::path& store_dir,
                     Json& rows) {
  ShadowMap::Options options;
  options.cache_bytes = size_t(config.cache_mib) << 20;
  auto map = ShadowMap::open(store_dir, options);
  if (!map) return map.error();
  auto sizes = method_sizes(**map);
  if (!sizes) return sizes.error();
  auto nonempty = count_nonempty_texels(**map);
  if (!nonempty) return nonempty.error();
  const uint64_t float32_bytes = 4ull * resolution * resolution;

  auto t0 = Clock::now();
  std::map<unsigned, std::vector<float>> pcf_truths;
  for (unsigned k : config.pcf_kernels)
    pcf_truths[k] = pcf_truth(**map, truth, data.uniform, k, config.pcf_supersample, config.seed);
  spdlog::info("  ground-truth PCF: {:.1f} s", std::chrono::duration<double>(Clock::now() - t0).count());
  PointOrders orders = make_orders((*map)->frame(), data.uniform, data.camera, config.seed);

  // Every rate below is measured in interleaved rounds (lookup_rate.hpp): the store's methods, both
  // thread counts, point and PCF, and the peer a user would pick instead, one Embree occlusion ray
  // toward the sun per receiver (same receivers, orders and threads), so each ratio divides figures
  // of the same stretch of wall time.
  InterleavedRates rates;
  std::vector<std::pair<std::string, size_t>> embree_keys;  // key in every row -> measurement
  auto ray = [&truth](const Vec3& p) { return truth.lit(p) ? 1.0 : 0.0; };
  const std::vector<std::pair<const char*, const std::vector<Vec3>*>> order_points{
      {"rows", &orders.rows}, {"camera", &orders.camera}, {"random", &orders.random}};
  for (auto& [order, points] : order_points)
    for (unsigned threads : config.threads)
      embree_keys.push_back({"embree_lps_point_" + std::string(order) + "_t" + std::to_string(threads),
                             rates.add(point_rounds(*points, threads, ray))});
  // The batch points as query_batch orders them (tile, then Morton inside it), for the batch peer.
  std::vector<Vec3> batch_sorted = data.batch;
  {
    const LightFrame& frame = (*map)->frame();
    const double R = (*map)->layout().resolution();
    std::vector<std::pair<uint64_t, size_t>> keyed;
    for (size_t i = 0; i < data.batch.size(); ++i) {
      LightSpacePoint l = frame.to_light(data.batch[i]);
      const bool on = l.u >= 0 && l.u < R && l.v >= 0 && l.v < R;
      keyed.push_back({on ? morton_encode(uint32_t(l.u), uint32_t(l.v)) : ~uint64_t(0), i});
    }
    std::sort(keyed.begin(), keyed.end());
    for (size_t i = 0; i < keyed.size(); ++i) batch_sorted[i] = data.batch[keyed[i].second];
  }
  if (!batch_sorted.empty())
    for (unsigned threads : config.threads)
      embree_keys.push_back({"embree_lps_batch_t" + std::to_string(threads), rates.add(point_rounds(batch_sorted, threads, ray))});

  std::vector<uint8_t> raw_uniform, raw_camera;
  for (store::Method method : methods) {
    const char* name = store::method_name(method);
    Json row;
    row["scene"] = spec.name;
    row["contract"] = receiver_contract_name(spec.contract);
    row["resolution"] = resolution;
    row["tile_size"] = (*map)->layout().tile_size();
    row["method"] = name;
    const MethodSize size = sizes->count(method) ? sizes->at(method) : MethodSize{};
    row["tiles"] = size.tiles;
    row["blob_bytes"] = size.blob_bytes;
    row["payload_bytes"] = size.payload_bytes;
    row["float32_bytes"] = float32_bytes;
    row["nonempty_texels"] = *nonempty;
    row["bytes_per_nonempty_texel"] = *nonempty ? double(size.blob_bytes) / double(*nonempty) : 0.0;
    row["bits_per_texel"] = 8.0 * double(size.blob_bytes) / (double(resolution) * resolution);
    row["compression_ratio"] = size.blob_bytes ? double(float32_bytes) / double(size.blob_bytes) : 0.0;
    // Build phases are of the one build that encoded every method (encode is their sum).
    row["build_load_s"] = stat(build_stats, "seconds", "load");
    row["build_index_s"] = stat(build_stats, "seconds", "index");
    row["build_bvh_s"] = stat(build_stats, "seconds", "bvh_thread_sum");
    row["build_rays_s"] = stat(build_stats, "seconds", "rays_thread_sum");
    row["build_encode_s"] = stat(build_stats, "seconds", "encode_thread_sum");
    // This method's own share of the encode (the shared MH construction is counted under mh).
    row["build_method_encode_s"] = stat(build_stats, "encode_seconds_by_method", name);
    row["build_store_s"] = stat(build_stats, "seconds", "store_thread_sum");
    row["build_wall_s"] = stat(build_stats, "seconds", "total");
    row["build_peak_rss_mib"] = build_peak_rss;

    // Accuracy: raw first (methods are ordered so), the others compared with its answers.
    const bool is_raw = store::method_properties(method).reference;
    auto acc = point_accuracy(**map, method, data.uniform, data.uniform_truth, is_raw ? std::span<const uint8_t>{} : raw_uniform,
                              is_raw ? &raw_uniform : nullptr);
    if (!acc) return acc.error();
    row["receivers"] = acc->receivers;
    row["receivers_inside_solids"] = data.uniform_inside_solids;
    row["error_rate"] = acc->error_rate();
    row["false_lit"] = acc->false_lit;
    row["false_shadowed"] = acc->false_shadowed;
    row["truth_lit"] = acc->truth_lit;
    row["differs_from_raw"] = acc->differs_from_raw;
    row["worse_than_raw"] = acc->worse_than_raw;
    auto cam = point_accuracy(**map, method, data.camera, data.camera_truth, is_raw ? std::span<const uint8_t>{} : raw_camera,
                              is_raw ? &raw_camera : nullptr);
    if (!cam) return cam.error();
    row["camera_receivers"] = cam->receivers;
    row["camera_error_rate"] = cam->error_rate();
    row["camera_false_lit"] = cam->false_lit;
    row["camera_false_shadowed"] = cam->false_shadowed;
    row["camera_differs_from_raw"] = cam->differs_from_raw;
    row["camera_worse_than_raw"] = cam->worse_than_raw;
    for (unsigned k : config.pcf_kernels) {
      auto pcf = pcf_accuracy(**map, method, data.uniform, k, pcf_truths[k]);
      if (!pcf) return pcf.error();
      row["pcf" + std::to_string(k) + "_mae"] = pcf->mean_abs_error;
    }

    rows.push_back(std::move(row));
  }

  // Speed: every method's lookups scheduled beside Embree's, then run together.
  std::vector<std::vector<std::pair<std::string, size_t>>> method_keys(methods.size());
  std::vector<unsigned> kernels{1};
  kernels.insert(kernels.end(), config.pcf_kernels.begin(), config.pcf_kernels.end());
  for (size_t m = 0; m < methods.size(); ++m) {
    for (unsigned k : kernels) {
      const std::string kind = k == 1 ? "point" : "pcf" + std::to_string(k);
      for (auto& [order, points] : order_points)
        for (unsigned threads : config.threads) {
          auto round = lookup_rounds(**map, methods[m], *points, k, threads);
          if (!round) return round.error();
          method_keys[m].push_back({"lps_" + kind + "_" + order + "_t" + std::to_string(threads), rates.add(std::move(*round))});
        }
    }
    // Batch queries (query_batch) of the shuffled batch points, point and PCF 3x3.
    for (unsigned threads : config.threads) {
      if (data.batch.empty()) break;
      for (unsigned k : {1u, 3u}) {
        auto round = batch_rounds(**map, methods[m], data.batch, k, threads);
        if (!round) return round.error();
        method_keys[m].push_back({std::string(k == 1 ? "lps_batch" : "lps_batch_pcf3") + "_t" + std::to_string(threads),
                                  rates.add(std::move(*round))});
      }
    }
  }
  t0 = Clock::now();
  auto measured = rates.run(config.min_seconds);
  if (!measured) return measured.error();
  spdlog::info("  lookup rates: {} measurements in interleaved rounds, {:.1f} s", rates.size(),
               std::chrono::duration<double>(Clock::now() - t0).count());
  Json embree;
  for (auto& [key, index] : embree_keys) embree[key] = (*measured)[index].lookups_per_second;
  spdlog::info("  Embree occlusion rays: rows {:.2f} M/s, random {:.2f} M/s (1 thread)",
               embree.value("embree_lps_point_rows_t1", 0.0) / 1e6, embree.value("embree_lps_point_random_t1", 0.0) / 1e6);

  for (size_t m = 0; m < methods.size(); ++m) {
    const store::Method method = methods[m];
    const char* name = store::method_name(method);
    Json& row = rows[rows.size() - methods.size() + m];
    const MethodSize size = sizes->count(method) ? sizes->at(method) : MethodSize{};
    uint64_t misses = 0;
    for (auto& [key, index] : method_keys[m]) {
      row[key] = (*measured)[index].lookups_per_second;
      misses += (*measured)[index].cache_misses;
    }
    row["lookup_cache_misses"] = misses;
    for (auto& [key, value] : embree.items()) row[key] = value;
    auto ratio = [&](const std::string& a, const std::string& b) {
      const double x = row.value(a, 0.0), y = row.contains(b) ? row[b].get<double>() : 0.0;
      return y > 0 ? x / y : 0.0;
    };
    for (unsigned threads : config.threads) {
      const std::string t = "_t" + std::to_string(threads);
      for (const char* order : {"rows", "camera", "random"})
        row[std::string("vs_embree_point_") + order + t] =
            ratio(std::string("lps_point_") + order + t, std::string("embree_lps_point_") + order + t);
      row["vs_embree_batch" + t] = ratio("lps_batch" + t, "embree_lps_batch" + t);
    }
    row["pcf3_over_point_cost"] = ratio("lps_point_rows_t1", "lps_pcf3_rows_t1");
    row["batch_pcf3_over_point_cost"] = ratio("lps_batch_t1", "lps_batch_pcf3_t1");
    // Latency of single point queries (warm, one thread, random order).
    auto latency = measure_point_latency(**map, method, orders.random);
    if (!latency) return latency.error();
    row["point_latency_p50_us"] = latency->p50_us;
    row["point_latency_p99_us"] = latency->p99_us;
    // Memory: the cache's peak so far and the process RSS during the lookup runs.
    row["cache_peak_bytes"] = (*map)->cache_stats().peak_bytes;
    row["lookup_rss_mib"] = current_rss_mib();
    // Cold start: the first batch on a freshly opened store (tiles read, checked, decoded), then
    // every tile decoded for the decoded size.
    if (!data.batch.empty()) {
      auto cold = ShadowMap::open(store_dir, options);
      if (!cold) return cold.error();
      ShadowMap::BatchOptions batch;
      batch.threads = config.threads.empty() ? 2 : config.threads.back();
      ShadowMap::BatchAnswers answers;
      const auto start = Clock::now();
      if (Status st = (*cold)->query_batch(data.batch, method, batch, answers); !st) return st.error();
      row["cold_batch_s"] = std::chrono::duration<double>(Clock::now() - start).count();
      row["cold_batch_bytes_read"] = (*cold)->cache_stats().fetched_bytes;
      // The same first batch over loopback HTTP: POSTed to a fresh server, and by a streaming client.
      if (http_cold_start_available()) {
        auto http = measure_http_cold_start(store_dir, method, data.batch, batch.threads, options.cache_bytes);
        if (!http) return http.error();
        row["cold_http_post_s"] = http->post_seconds;
        row["cold_http_post_bytes_read"] = http->post_bytes_read;
        row["cold_http_stream_s"] = http->stream_seconds;
        row["cold_http_stream_bytes"] = http->stream_bytes_fetched;
        row["http_batch_points"] = http->warm_batch_points;
        row["http_batch_lps_median"] = http->warm_post_lps_median;
        row["http_batch_lps_best"] = http->warm_post_lps_best;
      }
      std::vector<TileCoord> all;
      for (uint32_t y = 0; y < (*cold)->layout().tiles_per_side(); ++y)
        for (uint32_t x = 0; x < (*cold)->layout().tiles_per_side(); ++x) all.push_back({x, y});
      if (Status st = (*cold)->prefetch(method, all); !st) return st.error();
      const CacheStats cs = (*cold)->cache_stats();
      row["decoded_bytes"] = cs.bytes;
      row["decoded_over_payload"] = size.payload_bytes ? double(cs.bytes) / double(size.payload_bytes) : 0.0;
    }
    spdlog::info("  {} {}^2 {}: {} B, error {:.3f}%, point rows {:.2f} M/s", spec.name, resolution, name,
                 size.blob_bytes, 100.0 * row.value("error_rate", 0.0), row.value("lps_point_rows_t1", 0.0) / 1e6);
  }
  return {};
}

}  // namespace

Status run_bench(const BenchConfig& config, const std::filesystem::path& out_dir, const std::filesystem::path& repo_dir,
                 BenchRun& run) {
  Json& doc = run.document;
  doc["machine"] = machine_info(repo_dir);
  doc["config"] = config.source;
  doc["notes"] = Json::array();
  doc["builds"] = Json::array();
  doc["rows"] = Json::array();

  // Methods: raw first (the reference the others are compared with), unsupported ones noted.
  std::vector<store::Method> methods;
  for (store::Method m : config.methods) {
    if (!builder_supports(m)) {
      std::string note = std::string("method '") + store::method_name(m) + "' skipped: the builder does not support it yet";
      spdlog::warn("{}", note);
      doc["notes"].push_back(note);
      continue;
    }
    methods.push_back(m);
  }
  std::stable_partition(methods.begin(), methods.end(), [](store::Method m) { return store::method_properties(m).reference; });

  std::error_code ec;
  std::filesystem::create_directories(out_dir / "stores", ec);
  if (ec) return make_error(ErrorCode::io_error, "cannot create " + (out_dir / "stores").string() + ": " + ec.message());
  auto device = EmbreeDevice::create();
  if (!device) return device.error();

  for (const SceneSpec& spec : config.scenes) {
    spdlog::info("bench: scene {} ({})", spec.name, spec.file.string());
    SceneData data;
    LoadOptions load;
    load.up = spec.up;
    load.heightfield_meshes = spec.heightfield;
    auto scene = load_scene(spec.file, load);
    if (!scene) return scene.error();
    data.scene = std::move(*scene);
    auto light = light_direction_from_sun(spec.sun_azimuth, spec.sun_elevation, spec.up);
    if (!light) return light.error();
    data.light = *light;
    data.uniform = sample_receivers(data.scene, spec.receivers, config.seed);
    for (const Receiver& r : sample_receivers(data.scene, config.batch_points, config.seed + 1))
      data.batch.push_back(r.position);
    std::shuffle(data.batch.begin(), data.batch.end(), std::mt19937_64(config.seed + 2));
    data.camera = camera_receivers(*device, data.scene, spec.up, spec.camera);
    // Receivers inside solids are no receivers under either contract (builder/solid_interior.hpp).
    data.uniform_inside_solids = drop_receivers_inside_solids(*device, data.scene, data.light, data.uniform);
    data.camera_inside_solids = drop_receivers_inside_solids(*device, data.scene, data.light, data.camera);
    GroundTruth truth(*device, data.scene, data.light);
    data.uniform_truth = point_truth(truth, data.uniform);
    data.camera_truth = point_truth(truth, data.camera);
    spdlog::info("  {} uniform receivers, {} camera receivers ({} and {} inside solids left out)", data.uniform.size(),
                 data.camera.size(), data.uniform_inside_solids, data.camera_inside_solids);

    Json scene_rows = Json::array();
    for (uint32_t resolution : spec.resolutions) {
      const std::filesystem::path store_dir = out_dir / "stores" / (spec.name + "-" + std::to_string(resolution));
      std::filesystem::remove_all(store_dir, ec);  // a fresh build, never a resumed one
      BuildConfig build;
      build.scene_path = spec.file;
      build.store_path = store_dir;
      build.light_direction = data.light;
      build.resolution = resolution;
      build.tile_size = std::min(config.tile_size, resolution);
      build.threads = config.build_threads;
      build.methods = methods;
      build.receivers = spec.contract;
      build.load = load;
      build.overwrite = true;
      spdlog::info("  building {}^2 (tiles {}^2)", resolution, build.tile_size);
      reset_peak_rss();
      auto summary = run_build(build);
      if (!summary) return summary.error();
      const double peak = peak_rss_mib();
      doc["builds"].push_back({{"scene", spec.name}, {"contract", receiver_contract_name(spec.contract)},
                               {"resolution", resolution}, {"peak_rss_mib", peak},
                               {"stats", summary->stats}});
      Json rows = Json::array();
      Status measured = measure_store(config, spec, resolution, data, truth, methods, summary->stats, peak, store_dir, rows);
      for (auto& r : rows) {
        doc["rows"].push_back(r);
        scene_rows.push_back(r);
      }
      if (!measured) return measured;
      if (!config.keep_stores) std::filesystem::remove_all(store_dir, ec);
    }
    if (run.on_scene_done) run.on_scene_done(spec.name, scene_rows);
  }
  return {};
}

}  // namespace shadowtiles::bench
