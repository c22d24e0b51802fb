// The timed lookup loop of the MH and SST microbenchmarks (bench_mh, bench_sst), one per mode:
// 0 point lookups along a row (one row per iteration, rows in turn), 1 point lookups at random
// texels, 3 / 5 PCF k x k boxes at random corners (1024 per iteration). The random coordinates are
// per thread (seed: thread index + 1). Sets the lookups/s counter; the lambdas are inlined, so the
// loop costs what a hand-written one does.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

namespace shadowtiles::bench {

// The PCF kernel side of a mode (1 for the point modes).
inline uint32_t kernel_of_mode(int mode) { return mode >= 3 ? uint32_t(mode) : 1; }

// `point(u, v)` returns a stored value, `pcf(u, v)` the k x k answer (as a float) with its corner at
// (u, v), k = kernel_of_mode(mode); `size` is the tile's side.
template <typename Point, typename Pcf>
void run_lookup_mode(benchmark::State& state, uint32_t size, int mode, const Point& point, const Pcf& pcf) {
  std::mt19937 rng(unsigned(state.thread_index()) + 1);
  std::vector<uint32_t> coords(1 << 16);
  for (auto& c : coords) c = rng();
  const uint32_t k = kernel_of_mode(mode);
  uint64_t n = 0, i = 0, row = 0;
  float sum = 0;
  for (auto _ : state) {
    if (mode == 0) {  // coherent: one row
      const uint32_t v = uint32_t(row++ % size);
      for (uint32_t u = 0; u < size; ++u) sum += point(u, v);
      n += size;
    } else {
      for (int j = 0; j < 1024; ++j, i += 2) {
        const uint32_t u = coords[i & 0xffff] % (size - k + 1), v = coords[(i + 1) & 0xffff] % (size - k + 1);
        sum += mode == 1 ? point(u, v) : pcf(u, v);
      }
      n += 1024;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["lookups/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate);
}

// The label suffix of each mode.
inline const char* lookup_mode_name(int mode) {
  static const char* names[] = {"point row-order", "point random", "", "pcf3 random", "", "pcf5 random"};
  return names[mode];
}

}  // namespace shadowtiles::bench
