#include "builder/frame_shading.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

namespace shadowtiles {
namespace {

constexpr double kAmbient = 0.25;
constexpr double kAlbedo[3] = {0.86, 0.80, 0.70};

Vec3 to_sun_of(const Vec3& light_direction) {
  const double l = std::sqrt(light_direction[0] * light_direction[0] + light_direction[1] * light_direction[1] +
                             light_direction[2] * light_direction[2]);
  return {-light_direction[0] / l, -light_direction[1] / l, -light_direction[2] / l};
}

uint8_t to_byte(double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

// Runs body(first_row, step) on `threads` workers, rows interleaved (coherent screen order per worker).
template <class Body>
void over_rows(unsigned threads, Body body) {
  threads = std::max(1u, threads);
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < threads; ++t) workers.emplace_back(body, t, threads);
  body(0, threads);
  for (std::thread& worker : workers) worker.join();
}

}  // namespace

std::vector<float> sun_facing(const FrameHits& frame, const Vec3& light_direction) {
  const Vec3 to_sun = to_sun_of(light_direction);
  std::vector<float> facing(frame.pixels.size(), 0.0f);
  for (size_t i = 0; i < frame.pixels.size(); ++i) {
    const PrimaryHit& p = frame.pixels[i];
    if (!p.hit) continue;
    facing[i] = float(std::max(0.0, p.normal[0] * to_sun[0] + p.normal[1] * to_sun[1] + p.normal[2] * to_sun[2]));
  }
  return facing;
}

Result<std::vector<float>> visibility_from_map(const ShadowMap& map, store::Method method, unsigned pcf_kernel,
                                               const FrameHits& frame, unsigned threads) {
  const std::vector<float> facing = sun_facing(frame, map.frame().direction());
  std::vector<float> visibility(frame.pixels.size(), 0.0f);
  // One batch of the sunward pixels: sorted by tile and Morton order, shared descents, both cores.
  std::vector<Vec3> points;
  std::vector<uint32_t> pixel;
  for (size_t i = 0; i < frame.pixels.size(); ++i)
    if (facing[i] > 0) points.push_back(frame.pixels[i].position), pixel.push_back(uint32_t(i));
  ShadowMap::BatchOptions options;
  options.kernel = std::max(1u, pcf_kernel);
  options.threads = std::max(1u, threads);
  ShadowMap::BatchAnswers answers;
  if (Status s = map.query_batch(points, method, options, answers); !s) return s.error();
  for (size_t j = 0; j < points.size(); ++j) visibility[pixel[j]] = answers.lit[j];
  return visibility;
}

std::vector<float> visibility_from_ground_truth(const GroundTruth& truth, const FrameHits& frame,
                                                const Vec3& light_direction, unsigned threads) {
  const std::vector<float> facing = sun_facing(frame, light_direction);
  std::vector<float> visibility(frame.pixels.size(), 0.0f);
  over_rows(threads, [&](uint32_t first_row, uint32_t step) {
    for (uint32_t y = first_row; y < frame.height; y += step)
      for (uint32_t x = 0; x < frame.width; ++x) {
        const size_t i = size_t(y) * frame.width + x;
        if (facing[i] > 0) visibility[i] = truth.lit(frame.pixels[i].position) ? 1.0f : 0.0f;
      }
  });
  return visibility;
}

RgbImage shade_frame(const FrameHits& frame, const std::vector<float>& visibility, const Vec3& light_direction) {
  const std::vector<float> facing = sun_facing(frame, light_direction);
  RgbImage image(frame.width, frame.height);
  for (uint32_t y = 0; y < frame.height; ++y) {
    for (uint32_t x = 0; x < frame.width; ++x) {
      const size_t i = size_t(y) * frame.width + x;
      if (!frame.pixels[i].hit) {
        const double t = double(y) / std::max(1u, frame.height - 1);  // sky: lighter toward the horizon
        image.set(x, y, to_byte(0.45 + 0.35 * t), to_byte(0.62 + 0.25 * t), to_byte(0.85 + 0.1 * t));
        continue;
      }
      const double light = kAmbient + (1 - kAmbient) * facing[i] * std::clamp(double(visibility[i]), 0.0, 1.0);
      image.set(x, y, to_byte(kAlbedo[0] * light), to_byte(kAlbedo[1] * light), to_byte(kAlbedo[2] * light));
    }
  }
  return image;
}

FrameDiff diff_frames(const FrameHits& frame, const std::vector<float>& tested, const std::vector<float>& truth,
                      const Vec3& light_direction) {
  FrameDiff diff;
  diff.pixels = frame.pixels.size();
  const RgbImage base = shade_frame(frame, truth, light_direction);
  const std::vector<float> facing = sun_facing(frame, light_direction);
  diff.image = RgbImage(frame.width, frame.height);
  for (size_t i = 0; i < frame.pixels.size(); ++i) {
    const uint32_t x = uint32_t(i % frame.width), y = uint32_t(i / frame.width);
    const uint8_t* b = &base.rgb[i * 3];
    const uint8_t grey = uint8_t((int(b[0]) + b[1] + b[2]) / 6);  // dimmed, so marks stand out
    diff.image.set(x, y, grey, grey, grey);
    if (facing[i] <= 0) continue;
    ++diff.compared;
    const bool tested_lit = tested[i] > 0.5f, truth_lit = truth[i] > 0.5f;
    if (tested_lit && !truth_lit) {
      ++diff.false_lit;
      diff.image.set(x, y, 255, 40, 40);
    } else if (!tested_lit && truth_lit) {
      ++diff.false_shadowed;
      diff.image.set(x, y, 40, 110, 255);
    }
  }
  return diff;
}

}  // namespace shadowtiles
