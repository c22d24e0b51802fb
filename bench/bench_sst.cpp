// SST beside MH on synthetic tiles: encode time and payload size (counters), parse rate, lookup
// rates (point row order / random, PCF 3x3 and 5x5 random; 1 and 2 threads).
//   build-release/bench/bench_sst --benchmark_filter=Lookup
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <mutex>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "bench/lookup_modes.hpp"
#include "bench/synthetic_tile_cache.hpp"
#include "builder/sst_encoder.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/sst_tile_view.hpp"

namespace st = shadowtiles;

namespace {

using st::bench::kSyntheticKinds;
const st::TileIntervals& tile(int kind, uint32_t size) { return st::bench::cached_synthetic_tile(kind, size); }

struct Encoded {
  std::vector<uint8_t> sst_bytes, mh_bytes;
  st::SstTileView sst;
  st::MhTileView mh;
};
const Encoded& encoded(int kind, uint32_t size) {
  static std::mutex mutex;
  static std::map<std::pair<int, uint32_t>, std::unique_ptr<Encoded>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[{kind, size}];
  if (!slot) {
    slot = std::make_unique<Encoded>();
    slot->sst_bytes = *st::encode_sst_tile(tile(kind, size));
    slot->sst = *st::SstTileView::parse(slot->sst_bytes);
    slot->mh_bytes = *st::encode_mh(*st::build_mh(tile(kind, size)));
    slot->mh = *st::MhTileView::parse(slot->mh_bytes);
  }
  return *slot;
}

void BM_SstEncode(benchmark::State& state) {
  const int kind = int(state.range(0));
  const uint32_t size = uint32_t(state.range(1));
  const st::TileIntervals& t = tile(kind, size);
  for (auto _ : state) benchmark::DoNotOptimize(st::encode_sst_tile(t));
  const Encoded& e = encoded(kind, size);
  const st::SstStats& s = e.sst.stats();
  state.SetLabel(st::synthetic_kind_name(kSyntheticKinds[kind]));
  state.counters["raw_B"] = double(size) * size * 4;
  state.counters["sst_B"] = double(e.sst_bytes.size());
  state.counters["mh_B"] = double(e.mh_bytes.size());
  state.counters["plane_texel_share"] = double(s.plane_texels) / (double(size) * size);
  state.counters["dense_texel_share"] = double(s.dense_texels) / (double(size) * size);
  state.counters["texels/s"] = benchmark::Counter(double(size) * size, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_SstParse(benchmark::State& state) {
  const Encoded& e = encoded(int(state.range(0)), uint32_t(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(st::SstTileView::parse(e.sst_bytes));
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(e.sst_bytes.size()));
  state.SetLabel(st::synthetic_kind_name(kSyntheticKinds[state.range(0)]));
}

// range: kind, size, method (0 SST, 1 MH), mode (0 point row order, 1 point random, 3 / 5 PCF k random).
void BM_Lookup(benchmark::State& state) {
  const uint32_t size = uint32_t(state.range(1));
  const Encoded& e = encoded(int(state.range(0)), size);
  const bool sst = state.range(2) == 0;
  const int mode = int(state.range(3));
  const uint32_t k = st::bench::kernel_of_mode(mode);
  auto point = [&](uint32_t u, uint32_t v) { return sst ? e.sst.lookup(u, v) : e.mh.lookup(u, v); };
  auto pcf = [&](uint32_t u, uint32_t v) {
    return sst ? float(e.sst.lit_count(u, v, k, k, 0.5f)) : float(e.mh.pcf_lit_count(u, v, k, k, 0.5f, 0.0f));
  };
  st::bench::run_lookup_mode(state, size, mode, point, pcf);
  state.SetLabel(std::string(st::synthetic_kind_name(kSyntheticKinds[state.range(0)])) + (sst ? " sst " : " mh ") +
                 st::bench::lookup_mode_name(mode));
}

}  // namespace

BENCHMARK(BM_SstEncode)->ArgsProduct({{0, 1, 2, 3}, {1024, 4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SstParse)->ArgsProduct({{0, 1, 3}, {4096}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lookup)->ArgsProduct({{0, 1, 3}, {4096}, {0, 1}, {0, 1, 3, 5}})->Threads(1)->Threads(2);
BENCHMARK_MAIN();
