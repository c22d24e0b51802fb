// Lookup rates through the public ShadowMap API on an existing store, for profiling and A/B runs
// (`farm-bench`, `perf record`) without rebuilding a store: point and PCF 3x3, row and random order,
// 1 and 2 threads, per method, plus query_batch when available.
// Receivers: texel centres drawn uniformly over the map's non-empty texels, placed on the stored
// surface (raw's lower depth), so every lookup descends to a real surface like the bench's receivers.
// Usage: bench_api STORE [METHODS=raw,mh,mmh,dagmh] [RECEIVERS=1000000] [SECONDS=0.5] [MODES=all]
//   MODES: comma list of point,pcf3,batch (default all); batch1: query_batch of points only
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench/harness/lookup_rate.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles {
namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s STORE [METHODS] [RECEIVERS] [SECONDS] [MODES]\n", argv[0]);
    return 2;
  }
  const std::vector<std::string> methods = split(argc > 2 ? argv[2] : "raw,mh,mmh,dagmh");
  const size_t receivers = argc > 3 ? std::stoul(argv[3]) : 1000000;
  const double seconds = argc > 4 ? std::stod(argv[4]) : 0.5;
  const std::vector<std::string> modes = split(argc > 5 ? argv[5] : "point,pcf3,batch");
  auto has_mode = [&](const char* m) { return std::find(modes.begin(), modes.end(), m) != modes.end(); };
  ShadowMap::Options options;
  options.cache_bytes = size_t(8) << 30;
  auto map = ShadowMap::open(argv[1], options);
  if (!map) {
    std::fprintf(stderr, "%s\n", map.error().message.c_str());
    return 1;
  }
  const ShadowMap& m = **map;
  const store::Method reference = m.meta().has_method(store::Method::raw) ? store::Method::raw : m.default_method();
  const uint32_t R = m.layout().resolution();
  std::mt19937_64 rng(7);
  std::vector<Vec3> rows;
  rows.reserve(receivers);
  for (size_t attempts = 0; rows.size() < receivers && attempts < receivers * 50; ++attempts) {
    const uint32_t u = uint32_t(rng() % R), v = uint32_t(rng() % R);
    auto value = m.texel_value(reference, u, v);
    if (!value) {
      std::fprintf(stderr, "%s\n", value.error().message.c_str());
      return 1;
    }
    if (!std::isfinite(*value) || *value >= 1) continue;
    rows.push_back(m.frame().to_world({u + 0.5, v + 0.5, double(*value)}));
  }
  std::vector<Vec3> random = rows;
  std::sort(rows.begin(), rows.end(), [&](const Vec3& a, const Vec3& b) {
    auto la = m.frame().to_light(a), lb = m.frame().to_light(b);
    return std::pair(std::floor(la.v), la.u) < std::pair(std::floor(lb.v), lb.u);
  });
  std::printf("store %s: %u^2, tiles %u^2, %zu receivers\n", argv[1], R, m.layout().tile_size(), rows.size());
  std::printf("%-6s %-6s %-7s %12s %12s %8s\n", "method", "mode", "order", "1 thread", "2 threads", "2t/1t");
  for (const std::string& name : methods) {
    auto method = store::parse_method(name);
    if (!method) {
      std::fprintf(stderr, "unknown method %s\n", name.c_str());
      return 1;
    }
    for (unsigned kernel : {1u, 3u}) {
      if (!has_mode(kernel == 1 ? "point" : "pcf3")) continue;
      for (auto [order, points] : {std::pair<const char*, const std::vector<Vec3>*>{"rows", &rows}, {"random", &random}}) {
        bench::InterleavedRates pair;  // 1 and 2 threads in alternate rounds: their ratio is of one stretch of time
        for (unsigned threads : {1u, 2u}) {
          auto round = bench::lookup_rounds(m, *method, *points, kernel, threads);
          if (!round) {
            std::fprintf(stderr, "%s\n", round.error().message.c_str());
            return 1;
          }
          pair.add(std::move(*round));
        }
        auto measured = pair.run(seconds);
        if (!measured) {
          std::fprintf(stderr, "%s\n", measured.error().message.c_str());
          return 1;
        }
        const double rate[2] = {(*measured)[0].lookups_per_second, (*measured)[1].lookups_per_second};
        std::printf("%-6s %-6s %-7s %10.2f M %10.2f M %8.2f\n", name.c_str(), kernel == 1 ? "point" : "pcf3", order,
                    rate[0] / 1e6, rate[1] / 1e6, rate[0] > 0 ? rate[1] / rate[0] : 0.0);
        std::fflush(stdout);
      }
    }
    // Decoded bytes this method's tiles hold in the cache (every tile the receivers touch).
    const uint64_t cached = m.cache_stats().bytes;
    std::printf("%-6s decoded tiles in cache: %.2f MiB (all methods so far)\n", name.c_str(), double(cached) / (1 << 20));
    if (has_mode("batch") || has_mode("batch1")) {
      // BATCH_REPEATS: more batches per rate, for `perf record` of the batch path alone.
      const char* repeats_env = std::getenv("BATCH_REPEATS");
      const int batch_repeats = repeats_env ? std::max(1, std::atoi(repeats_env)) : 5;
      // BATCH_SPLIT=k: the same points as k batches one after the other (how density matters).
      const char* split_env = std::getenv("BATCH_SPLIT");
      const size_t split = size_t(split_env ? std::max(1, std::atoi(split_env)) : 1);
      // MODES batch1: point batches only (for `perf record` of that path).
      for (unsigned kernel : {1u, 3u}) {
        if (kernel != 1 && !has_mode("batch")) continue;
        double rate[2] = {0, 0};
        for (unsigned threads : {1u, 2u}) {
          ShadowMap::BatchOptions batch;
          batch.kernel = kernel;
          batch.threads = threads;
          ShadowMap::BatchAnswers answers;
          double best = 0;
          for (int repeat = 0; repeat < batch_repeats; ++repeat) {
            const auto start = std::chrono::steady_clock::now();
            for (size_t part = 0; part < split; ++part) {
              const size_t a = random.size() * part / split, b = random.size() * (part + 1) / split;
              if (Status s = m.query_batch(std::span<const Vec3>(random).subspan(a, b - a), *method, batch, answers); !s) {
                std::fprintf(stderr, "%s\n", s.error().message.c_str());
                return 1;
              }
            }
            const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            best = std::max(best, double(random.size()) / dt);
          }
          rate[threads - 1] = best;
        }
        std::printf("%-6s %-6s %-7s %10.2f M %10.2f M %8.2f\n", name.c_str(), kernel == 1 ? "batch" : "batch3",
                    "random", rate[0] / 1e6, rate[1] / 1e6, rate[0] > 0 ? rate[1] / rate[0] : 0.0);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}

}  // namespace
}  // namespace shadowtiles

int main(int argc, char** argv) { return shadowtiles::run(argc, argv); }
