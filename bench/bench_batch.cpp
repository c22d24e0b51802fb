// ShadowMap::query_batch on the points of a binary batch body (little-endian float32 x, y, z triples,
// as POST /v1/shadow takes them), in process: the share of an HTTP batch request that is query work,
// for profiling (`perf record`, `valgrind --tool=callgrind`) and A/B runs without a server.
// Usage: bench_batch STORE POINTS.bin [METHOD=mh] [THREADS=2] [REPEATS=20] [KERNEL=1]
// Prints the median and best rate over REPEATS batches (after one warm-up batch).
#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "client/shadow_map.hpp"

namespace shadowtiles {
namespace {

int run(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s STORE POINTS.bin [METHOD] [THREADS] [REPEATS] [KERNEL]\n", argv[0]);
    return 2;
  }
  const std::string method_name = argc > 3 ? argv[3] : "mh";
  const unsigned threads = argc > 4 ? unsigned(std::stoul(argv[4])) : 2;
  const int repeats = argc > 5 ? std::max(1, std::stoi(argv[5])) : 20;
  const unsigned kernel = argc > 6 ? unsigned(std::stoul(argv[6])) : 1;
  auto method = store::parse_method(method_name);
  if (!method) {
    std::fprintf(stderr, "unknown method %s\n", method_name.c_str());
    return 2;
  }
  std::ifstream in(argv[2], std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", argv[2]);
    return 1;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.empty() || bytes.size() % 12 != 0) {
    std::fprintf(stderr, "%s: not a whole number of float32 triples\n", argv[2]);
    return 1;
  }
  std::vector<Vec3> points(bytes.size() / 12);
  for (size_t i = 0; i < points.size(); ++i)
    for (size_t axis = 0; axis < 3; ++axis) {
      float value;
      std::memcpy(&value, bytes.data() + i * 12 + axis * 4, 4);  // little-endian hosts only (bench)
      points[i][axis] = value;
    }
  ShadowMap::Options map_options;
  map_options.cache_bytes = size_t(8) << 30;  // as bench_api: measure the pipeline, not the cache's evictions
  auto map = ShadowMap::open(argv[1], map_options);
  if (!map) {
    std::fprintf(stderr, "%s\n", map.error().message.c_str());
    return 1;
  }
  ShadowMap::BatchOptions options;
  options.kernel = kernel;
  options.threads = threads;
  ShadowMap::BatchAnswers answers;
  std::vector<double> rates;
  for (int r = 0; r <= repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    if (Status s = (*map)->query_batch(points, *method, options, answers); !s) {
      std::fprintf(stderr, "%s\n", s.error().message.c_str());
      return 1;
    }
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (r > 0) rates.push_back(double(points.size()) / dt);  // the first batch decodes the tiles
  }
  std::sort(rates.begin(), rates.end());
  size_t lit = 0;
  for (float v : answers.lit) lit += v > 0.5f;
  std::printf("%s %zu points, %s, kernel %u, %u threads: median %.2f M/s, best %.2f M/s (%zu lit, %zu off the map)\n",
              argv[2], points.size(), method_name.c_str(), kernel, threads, rates[rates.size() / 2] / 1e6,
              rates.back() / 1e6, lit, answers.outside.size());
  return 0;
}

}  // namespace
}  // namespace shadowtiles

int main(int argc, char** argv) { return shadowtiles::run(argc, argv); }
