// The C API's queries: a point, a PCF kernel, and batches of either, answered by ShadowMap (batches
// through ShadowMap::query_batch unless the stored values are asked for).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <span>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "capi/c_api_support.hpp"

using namespace shadowtiles;
using capi::fail;
using capi::guarded;

namespace {

void fill_answer(const ShadowAnswer& a, shadowtiles_answer* out) {
  out->lit = a.lit;
  out->outside_map = a.outside_map;
  out->empty_tile = a.empty_tile;
  out->reserved = 0;
  out->value = a.value;
  out->u = a.light.u;
  out->v = a.light.v;
  out->depth = a.light.depth;
}

Vec3 point_at(const double* points, size_t i) { return {points[3 * i], points[3 * i + 1], points[3 * i + 2]}; }

// Splits [0, count) into contiguous chunks over `threads` threads (0: one per core; small batches
// stay on the caller's thread). `body(begin, end)` returns the first error of its chunk; the first
// error of any chunk is returned and stops the others at their next point.
template <class Body>
Status for_chunks(size_t count, uint32_t threads, Body body) {
  unsigned n = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  n = unsigned(std::min<size_t>(n, std::max<size_t>(1, count / 4096)));
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  std::optional<Error> first_error;
  auto run = [&](size_t begin, size_t end) {
    Status s = body(begin, end, failed);
    if (!s) {
      std::lock_guard lock(error_mutex);
      if (!first_error) first_error = s.error();
      failed = true;
    }
  };
  if (n <= 1) {
    run(0, count);
  } else {
    std::vector<std::thread> workers;
    const size_t step = (count + n - 1) / n;
    for (unsigned t = 1; t < n; ++t)
      workers.emplace_back(run, std::min(count, t * step), std::min(count, (t + 1) * step));
    run(0, std::min(count, step));
    for (auto& w : workers) w.join();
  }
  if (first_error) return *first_error;
  return {};
}

// ShadowMap::query_batch over the caller's xyz triples (Vec3 is three packed doubles). Its outside
// list holds 32-bit indices, hence the bound.
Status batch(const ShadowMap& map, store::Method method, const double* points, size_t count, unsigned kernel,
             std::optional<double> bias, uint32_t threads, ShadowMap::BatchAnswers& answers) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  if (count > std::numeric_limits<uint32_t>::max())
    return make_error(ErrorCode::invalid_input, "a batch holds at most 2^32 - 1 points; split it");
  // Named here so the caller learns which point is bad (query_batch fails the batch as a whole).
  for (size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]))
      return make_error(ErrorCode::invalid_input, "point " + std::to_string(i / 3) + ": coordinates must be finite");
  ShadowMap::BatchOptions options;
  options.kernel = kernel;
  options.bias = bias;
  options.threads = threads;
  return map.query_batch(std::span<const Vec3>(reinterpret_cast<const Vec3*>(points), count), method, options,
                         answers);
}

}  // namespace

extern "C" {

shadowtiles_status shadowtiles_query(const shadowtiles_map* map, const char* method, const double point[3], double bias,
                                     shadowtiles_answer* answer) {
  return guarded([&] {
    if (map == nullptr || point == nullptr || answer == nullptr)
      return fail(SHADOWTILES_INVALID_INPUT, "query: map, point and answer must not be NULL");
    auto m = capi::method_named(*map->map, method);
    if (!m) return fail(m.error());
    auto a = map->map->query(point_at(point, 0), *m, capi::bias_of(bias));
    if (!a) return fail(a.error());
    fill_answer(*a, answer);
    return SHADOWTILES_OK;
  });
}

shadowtiles_status shadowtiles_query_pcf(const shadowtiles_map* map, const char* method, const double point[3],
                                         uint32_t kernel, double bias, double* lit_fraction,
                                         shadowtiles_answer* answer) {
  return guarded([&] {
    if (map == nullptr || point == nullptr || lit_fraction == nullptr)
      return fail(SHADOWTILES_INVALID_INPUT, "query_pcf: map, point and lit_fraction must not be NULL");
    auto m = capi::method_named(*map->map, method);
    if (!m) return fail(m.error());
    ShadowAnswer a;
    auto f = map->map->query_pcf(point_at(point, 0), *m, kernel, capi::bias_of(bias), std::nullopt, &a);
    if (!f) return fail(f.error());
    *lit_fraction = *f;
    if (answer) fill_answer(a, answer);
    return SHADOWTILES_OK;
  });
}

shadowtiles_status shadowtiles_query_batch(const shadowtiles_map* map, const char* method, const double* points,
                                           size_t count, double bias, uint32_t threads, uint8_t* lit, float* values,
                                           uint8_t* outside_map) {
  return guarded([&] {
    if (map == nullptr || lit == nullptr || (points == nullptr && count > 0))
      return fail(SHADOWTILES_INVALID_INPUT, "query_batch: map, points and lit must not be NULL");
    auto m = capi::method_named(*map->map, method);
    if (!m) return fail(m.error());
    const ShadowMap& sm = *map->map;
    const auto b = capi::bias_of(bias);
    if (values == nullptr) {
      // Lit flags only: ShadowMap's batch path (points sorted by tile and Morton order, shared walks).
      ShadowMap::BatchAnswers answers;
      if (Status s = batch(sm, *m, points, count, 1, b, threads, answers); !s) return fail(s.error());
      for (size_t i = 0; i < count; ++i) lit[i] = answers.lit[i] != 0;
      if (outside_map) {
        std::fill(outside_map, outside_map + count, uint8_t(0));
        for (uint32_t i : answers.outside) outside_map[i] = 1;
      }
      return SHADOWTILES_OK;
    }
    // The stored values too: one full query per point (the batch path computes lit flags only).
    Status s = for_chunks(count, threads, [&](size_t begin, size_t end, const std::atomic<bool>& failed) -> Status {
      for (size_t i = begin; i < end; ++i) {
        if ((i & 1023) == 0 && failed.load(std::memory_order_relaxed)) return {};
        auto a = sm.query(point_at(points, i), *m, b);
        if (!a) return make_error(a.error().code, "point " + std::to_string(i) + ": " + a.error().message);
        lit[i] = a->lit;
        values[i] = a->value;
        if (outside_map) outside_map[i] = a->outside_map;
      }
      return {};
    });
    if (!s) return fail(s.error());
    return SHADOWTILES_OK;
  });
}

shadowtiles_status shadowtiles_query_pcf_batch(const shadowtiles_map* map, const char* method, const double* points,
                                               size_t count, uint32_t kernel, double bias, uint32_t threads,
                                               double* lit_fractions) {
  return guarded([&] {
    if (map == nullptr || lit_fractions == nullptr || (points == nullptr && count > 0))
      return fail(SHADOWTILES_INVALID_INPUT, "query_pcf_batch: map, points and lit_fractions must not be NULL");
    auto m = capi::method_named(*map->map, method);
    if (!m) return fail(m.error());
    const ShadowMap& sm = *map->map;
    const auto b = capi::bias_of(bias);
    ShadowMap::BatchAnswers answers;
    Status s = batch(sm, *m, points, count, kernel, b, threads, answers);
    if (s) std::copy(answers.lit.begin(), answers.lit.end(), lit_fractions);
    if (!s) return fail(s.error());
    return SHADOWTILES_OK;
  });
}

}  // extern "C"
