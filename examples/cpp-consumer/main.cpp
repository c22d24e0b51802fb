// cpp-consumer: the C++ client from an installed shadowtiles (find_package(shadowtiles),
// shadowtiles::client).
//
//   cpp-consumer LOCATION POINTS_FILE METHOD          one "lit value" line per "x y z" point
//   cpp-consumer --bench LOCATION POINTS_BIN METHOD   times a warm pass of query() over float64 xyz
//                                                     triples and one query_batch (one thread each):
//                                                     "seconds S points N lit L batch_seconds B"
#include <chrono>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "client/streaming_client.hpp"

namespace st = shadowtiles;

static int fail(const std::string& what, const st::Error& error) {
  std::cerr << "cpp-consumer: " << what << ": " << error.message << " (" << st::error_code_name(error.code) << ")\n";
  return 1;
}

int main(int argc, char** argv) {
  const bool bench = argc == 5 && std::string(argv[1]) == "--bench";
  if (argc != 4 && !bench) {
    std::cerr << "usage: cpp-consumer [--bench] LOCATION POINTS_FILE METHOD\n";
    return 2;
  }
  const int a = bench ? 2 : 1;
  auto map = st::open_shadow_map(argv[a], st::StreamingOptions{});
  if (!map) return fail("open", map.error());
  auto method = st::store::parse_method(argv[a + 2]);
  if (!method) return fail("method", method.error());

  std::vector<st::Vec3> points;
  if (bench) {
    std::ifstream in(argv[a + 1], std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    points.resize(bytes.size() / sizeof(st::Vec3));
    std::memcpy(points.data(), bytes.data(), points.size() * sizeof(st::Vec3));
  } else {
    std::ifstream in(argv[a + 1]);
    st::Vec3 p;
    while (in >> p[0] >> p[1] >> p[2]) points.push_back(p);
    if (!in.eof()) { std::cerr << "cpp-consumer: malformed points file\n"; return 1; }
  }

  std::vector<uint8_t> lit(points.size());
  std::vector<float> values(points.size());
  // --bench: a first pass loads and decodes the tiles, the second is timed (warm cache, as a
  // long-running consumer sees it).
  double seconds = 0;
  for (int pass = bench ? 0 : 1; pass < 2; ++pass) {
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < points.size(); ++i) {
      auto answer = (*map)->query(points[i], *method);
      if (!answer) return fail("query of point " + std::to_string(i), answer.error());
      lit[i] = answer->lit;
      values[i] = answer->value;
    }
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  if (bench) {
    size_t lit_count = 0;
    for (uint8_t l : lit) lit_count += l;
    // The batch path on the same points, one thread (tiles are warm from the passes above).
    st::ShadowMap::BatchOptions options;
    options.threads = 1;
    st::ShadowMap::BatchAnswers answers;
    const auto start = std::chrono::steady_clock::now();
    if (st::Status s = (*map)->query_batch(points, *method, options, answers); !s) return fail("query_batch", s.error());
    const double batch_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    size_t batch_lit = 0;
    for (float l : answers.lit) batch_lit += l != 0;
    if (batch_lit != lit_count) { std::cerr << "cpp-consumer: query_batch disagrees with query\n"; return 1; }
    std::printf("seconds %.6f points %zu lit %zu batch_seconds %.6f\n", seconds, points.size(), lit_count,
                batch_seconds);
    return 0;
  }
  for (size_t i = 0; i < points.size(); ++i) std::printf("%d %.9g\n", lit[i], double(values[i]));
  return 0;
}
