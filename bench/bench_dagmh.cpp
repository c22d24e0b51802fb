// DAG-MH beside MH/MMH on synthetic tiles: encode and parse times, sizes as counters, lookup rates
// (point, PCF 3x3 and 5x5; coherent and random; 1 and 2 threads), MMH and DAG-MH in one run
// (MH is encoded too, for the encode counters).
//   build-release/bench/bench_dagmh --benchmark_filter=Lookup
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "bench/lossless_guard.hpp"
#include "bench/synthetic_tile_cache.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/dagmh_decoder.hpp"
#include "codec/mh_decoder.hpp"

namespace st = shadowtiles;

namespace {

using st::bench::kSyntheticKinds;

// Method 0 MH, 1 MMH, 2 DAG-MH.
struct Encoded {
  std::vector<uint8_t> bytes;
  st::MhTileView mh;
  st::DagMhTileView dag;
};
const Encoded& encoded(int kind, uint32_t size, int method) {
  static std::mutex mutex;
  static std::map<std::tuple<int, uint32_t, int>, std::unique_ptr<Encoded>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[{kind, size, method}];
  if (!slot) {
    slot = std::make_unique<Encoded>();
    const st::TileIntervals& tile = st::bench::cached_synthetic_tile(kind, size);
    auto tree = *st::build_mh(tile);
    if (method == 2) {
      slot->bytes = *st::encode_dagmh(tree);
      slot->dag = *st::DagMhTileView::parse(slot->bytes);
      st::bench::require_lookups_inside(tile, [&](uint32_t u, uint32_t v) { return slot->dag.lookup(u, v); },
                                        "bench_dagmh DAG-MH");
    } else {
      slot->bytes = *st::encode_mh(method == 1 ? *st::merge_mmh(tree) : tree);
      slot->mh = *st::MhTileView::parse(slot->bytes);
      st::bench::require_lookups_inside(tile, [&](uint32_t u, uint32_t v) { return slot->mh.lookup(u, v); },
                                        method == 1 ? "bench_dagmh MMH" : "bench_dagmh MH");
    }
  }
  return *slot;
}

void BM_EncodeDagMh(benchmark::State& state) {
  auto tree = *st::build_mh(st::make_synthetic_tile(kSyntheticKinds[state.range(0)], uint32_t(state.range(1)), 42));
  std::vector<uint8_t> bytes;
  for (auto _ : state) bytes = *st::encode_dagmh(tree);
  state.counters["bytes"] = double(bytes.size());
  state.counters["mh_bytes"] = double(st::encode_mh(tree)->size());
  state.counters["mmh_bytes"] = double(st::encode_mh(*st::merge_mmh(tree))->size());
  state.SetLabel(st::synthetic_kind_name(kSyntheticKinds[state.range(0)]));
}

void BM_ParseDagMh(benchmark::State& state) {
  const Encoded& e = encoded(int(state.range(0)), uint32_t(state.range(1)), 2);
  for (auto _ : state) benchmark::DoNotOptimize(st::DagMhTileView::parse(e.bytes).ok());
}

// range: kind, size, method (0 MH, 1 MMH, 2 DAG-MH), kernel (1 point, 3 / 5 PCF k x k), order
// (0 coherent: texels along rows, 1 random). Lookups/s per thread in the counter.
void BM_Lookup(benchmark::State& state) {
  const uint32_t size = uint32_t(state.range(1));
  const int method = int(state.range(2));
  const uint32_t k = uint32_t(state.range(3));
  const bool random = state.range(4) != 0;
  const Encoded& e = encoded(int(state.range(0)), size, method);
  auto point = [&](uint32_t u, uint32_t v) { return method == 2 ? e.dag.lookup(u, v) : e.mh.lookup(u, v); };
  auto pcf = [&](uint32_t u, uint32_t v) {
    return method == 2 ? e.dag.pcf_lit_count(u, v, k, k, 0.5f, 1e-4f) : e.mh.pcf_lit_count(u, v, k, k, 0.5f, 1e-4f);
  };
  std::mt19937 rng(unsigned(state.thread_index()) + 1);
  std::vector<uint32_t> coords(1 << 16);
  for (auto& c : coords) c = rng();
  const uint32_t span = size - k + 1;
  // Coherent: each thread walks its own rows, one texel step at a time.
  uint64_t n = 0, i = 0, row = uint64_t(state.thread_index()) * 997;
  float sum = 0;
  for (auto _ : state) {
    if (!random) {
      const uint32_t v = uint32_t(row++ % span);
      for (uint32_t u = 0; u < span; ++u) sum += k == 1 ? point(u, v) : float(pcf(u, v));
      n += span;
    } else {
      for (int j = 0; j < 1024; ++j, i += 2) {
        const uint32_t u = coords[i & 0xffff] % span, v = coords[(i + 1) & 0xffff] % span;
        sum += k == 1 ? point(u, v) : float(pcf(u, v));
      }
      n += 1024;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["lookups/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate);
  static const char* methods[] = {" mh ", " mmh ", " dagmh "};
  state.SetLabel(std::string(st::synthetic_kind_name(kSyntheticKinds[state.range(0)])) + methods[method] +
                 (k == 1 ? "point" : k == 3 ? "pcf3" : "pcf5") + (random ? " random" : " coherent"));
}

}  // namespace

BENCHMARK(BM_EncodeDagMh)->ArgsProduct({{0, 1, 2, 3}, {1024, 4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParseDagMh)->ArgsProduct({{0, 3}, {4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lookup)
    ->ArgsProduct({{0, 2, 3}, {4096}, {1, 2}, {1, 3, 5}, {0, 1}})
    ->Threads(1)
    ->Threads(2)
    ->MinTime(0.2);
BENCHMARK_MAIN();
