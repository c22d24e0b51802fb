// DAG-MH beside MH/MMH on synthetic tiles: encode and parse times, sizes as counters, lookup rates
// (point coherent/random, PCF 3x3 and 5x5; 1 and 2 threads), one run for all three methods.
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
#include "builder/mmh_merger.hpp"
#include "client/dagmh_decoder.hpp"
#include "client/mh_decoder.hpp"

namespace st = shadowtiles;

namespace {

const st::MhSyntheticKind kKinds[] = {st::MhSyntheticKind::steps, st::MhSyntheticKind::closed_plane,
                                      st::MhSyntheticKind::noisy_plane, st::MhSyntheticKind::random_intervals};

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
    auto tree = *st::build_mh(st::make_synthetic_tile(kKinds[kind], size, 42));
    if (method == 2) {
      slot->bytes = *st::encode_dagmh(tree);
      slot->dag = *st::DagMhTileView::parse(slot->bytes);
    } else {
      slot->bytes = *st::encode_mh(method == 1 ? *st::merge_mmh(tree) : tree);
      slot->mh = *st::MhTileView::parse(slot->bytes);
    }
  }
  return *slot;
}

void BM_EncodeDagMh(benchmark::State& state) {
  auto tree = *st::build_mh(st::make_synthetic_tile(kKinds[state.range(0)], uint32_t(state.range(1)), 42));
  std::vector<uint8_t> bytes;
  for (auto _ : state) bytes = *st::encode_dagmh(tree);
  state.counters["bytes"] = double(bytes.size());
  state.counters["mh_bytes"] = double(st::encode_mh(tree)->size());
  state.counters["mmh_bytes"] = double(st::encode_mh(*st::merge_mmh(tree))->size());
  state.SetLabel(st::synthetic_kind_name(kKinds[state.range(0)]));
}

void BM_ParseDagMh(benchmark::State& state) {
  const Encoded& e = encoded(int(state.range(0)), uint32_t(state.range(1)), 2);
  for (auto _ : state) benchmark::DoNotOptimize(st::DagMhTileView::parse(e.bytes).ok());
}

// range: kind, size, method, mode (0 point row order, 1 point random, 3 / 5 PCF k random).
void BM_Lookup(benchmark::State& state) {
  const uint32_t size = uint32_t(state.range(1));
  const int method = int(state.range(2)), mode = int(state.range(3));
  const Encoded& e = encoded(int(state.range(0)), size, method);
  auto point = [&](uint32_t u, uint32_t v) { return method == 2 ? e.dag.lookup(u, v) : e.mh.lookup(u, v); };
  auto pcf = [&](uint32_t u, uint32_t v, uint32_t k) {
    return method == 2 ? e.dag.pcf_lit_count(u, v, k, k, 0.5f, 1e-4f) : e.mh.pcf_lit_count(u, v, k, k, 0.5f, 1e-4f);
  };
  std::mt19937 rng(unsigned(state.thread_index()) + 1);
  std::vector<uint32_t> coords(1 << 16);
  for (auto& c : coords) c = rng();
  const uint32_t k = mode >= 3 ? uint32_t(mode) : 1;
  uint64_t n = 0, i = 0, row = 0;
  float sum = 0;
  for (auto _ : state) {
    if (mode == 0) {
      const uint32_t v = uint32_t(row++ % size);
      for (uint32_t u = 0; u < size; ++u) sum += point(u, v);
      n += size;
    } else {
      for (int j = 0; j < 1024; ++j, i += 2) {
        const uint32_t u = coords[i & 0xffff] % (size - k + 1), v = coords[(i + 1) & 0xffff] % (size - k + 1);
        sum += mode == 1 ? point(u, v) : float(pcf(u, v, k));
      }
      n += 1024;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["lookups/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate);
  static const char* methods[] = {" mh ", " mmh ", " dagmh "};
  static const char* modes[] = {"point row-order", "point random", "", "pcf3 random", "", "pcf5 random"};
  state.SetLabel(std::string(st::synthetic_kind_name(kKinds[state.range(0)])) + methods[method] + modes[mode]);
}

}  // namespace

BENCHMARK(BM_EncodeDagMh)->ArgsProduct({{0, 1, 2, 3}, {1024, 4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParseDagMh)->ArgsProduct({{0, 3}, {4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lookup)->ArgsProduct({{0, 3}, {4096}, {0, 1, 2}, {0, 1, 3, 5}})->Threads(1)->Threads(2);
BENCHMARK_MAIN();
