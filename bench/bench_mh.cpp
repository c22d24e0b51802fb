// MH / MMH on synthetic tiles: build phases (bottom-up, top-down, merge, encode, parse), sizes as
// counters, and lookup rates (point coherent/random, PCF 3x3 and 5x5; 1 and 2 threads).
//   build-release/bench/bench_mh --benchmark_filter=Lookup
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <mutex>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "bench/lookup_modes.hpp"
#include "bench/lossless_guard.hpp"
#include "bench/synthetic_tile_cache.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"

namespace st = shadowtiles;

namespace {

using st::bench::kSyntheticKinds;
const st::TileIntervals& tile(int kind, uint32_t size) { return st::bench::cached_synthetic_tile(kind, size); }

struct Encoded {
  std::vector<uint8_t> bytes;
  st::MhTileView view;
};
const Encoded& encoded(int kind, uint32_t size, bool merged) {
  static std::mutex mutex;
  static std::map<std::tuple<int, uint32_t, bool>, std::unique_ptr<Encoded>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[{kind, size, merged}];
  if (!slot) {
    slot = std::make_unique<Encoded>();
    auto tree = *st::build_mh(tile(kind, size));
    slot->bytes = *st::encode_mh(merged ? *st::merge_mmh(tree) : tree);
    slot->view = *st::MhTileView::parse(slot->bytes);
    st::bench::require_lookups_inside(tile(kind, size), [&](uint32_t u, uint32_t v) { return slot->view.lookup(u, v); },
                                      merged ? "bench_mh MMH" : "bench_mh MH");
  }
  return *slot;
}

void BM_Build(benchmark::State& state) {
  const int kind = int(state.range(0));
  const uint32_t size = uint32_t(state.range(1));
  const auto construction = state.range(2) ? st::MhConstruction::top_down : st::MhConstruction::bottom_up;
  const st::TileIntervals& t = tile(kind, size);
  st::MhHierarchy tree;
  for (auto _ : state) tree = *st::build_mh(t, {construction});
  const auto mh = *st::encode_mh(tree);
  st::MmhMergeStats stats;
  const auto mmh = *st::encode_mh(*st::merge_mmh(tree, {}, &stats));
  state.SetLabel(std::string(st::synthetic_kind_name(kSyntheticKinds[kind])) + (state.range(2) ? " top-down" : " bottom-up"));
  state.counters["raw_B"] = double(size) * size * 4;
  state.counters["mh_B"] = double(mh.size());
  state.counters["mmh_B"] = double(mmh.size());
  state.counters["sbe16a_mh_B"] = double(st::sbe16a_reference_bytes(tree));
  state.counters["nodes"] = double(st::count_nodes(tree).tree_nodes);
  state.counters["texels/s"] = benchmark::Counter(double(size) * size, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Merge(benchmark::State& state) {
  const auto tree = *st::build_mh(tile(int(state.range(0)), uint32_t(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(st::merge_mmh(tree));
  state.SetLabel(st::synthetic_kind_name(kSyntheticKinds[state.range(0)]));
}

void BM_Encode(benchmark::State& state) {
  const auto tree = *st::build_mh(tile(int(state.range(0)), uint32_t(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(st::encode_mh(tree));
  state.SetLabel(st::synthetic_kind_name(kSyntheticKinds[state.range(0)]));
}

void BM_Parse(benchmark::State& state) {
  const Encoded& e = encoded(int(state.range(0)), uint32_t(state.range(1)), state.range(2));
  for (auto _ : state) benchmark::DoNotOptimize(st::MhTileView::parse(e.bytes));
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(e.bytes.size()));
  state.SetLabel(std::string(st::synthetic_kind_name(kSyntheticKinds[state.range(0)])) + (state.range(2) ? " mmh" : " mh"));
}

// range: kind, size, merged, mode (0 point row order, 1 point random, 3 / 5 PCF k random).
void BM_Lookup(benchmark::State& state) {
  const uint32_t size = uint32_t(state.range(1));
  const Encoded& e = encoded(int(state.range(0)), size, state.range(2));
  const int mode = int(state.range(3));
  const uint32_t k = st::bench::kernel_of_mode(mode);
  st::bench::run_lookup_mode(
      state, size, mode, [&](uint32_t u, uint32_t v) { return e.view.lookup(u, v); },
      [&](uint32_t u, uint32_t v) { return e.view.pcf_lit_fraction(u, v, k, 0.5f, 1e-4f); });
  state.SetLabel(std::string(st::synthetic_kind_name(kSyntheticKinds[state.range(0)])) + (state.range(2) ? " mmh " : " mh ") +
                 st::bench::lookup_mode_name(mode));
}

}  // namespace

BENCHMARK(BM_Build)->ArgsProduct({{0, 1, 2, 3}, {1024, 4096}, {0}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Build)->ArgsProduct({{0, 1, 2, 3}, {1024}, {1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Merge)->ArgsProduct({{0, 1, 2, 3}, {1024, 4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Encode)->ArgsProduct({{0, 1, 3}, {4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Parse)->ArgsProduct({{0, 3}, {4096}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lookup)->ArgsProduct({{0, 3}, {4096}, {0, 1}, {0, 1, 3, 5}})->Threads(1)->Threads(2);
BENCHMARK_MAIN();
