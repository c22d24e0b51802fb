// The one accuracy evaluator (docs/architecture.md §11), used by the bench, the stability suite and
// the tests, so every method is judged on the same receivers with the same truth:
// - point: the store's lit/shadowed answer vs an Embree occlusion ray from the receiver toward the
//   sun (GroundTruth, one epsilon for every method); split into false-lit (light leaks) and
//   false-shadowed; also how often a method's answer differs from raw's and who was right.
// - PCF k x k: mean absolute difference between the store's lit fraction and a supersampled
//   ground-truth visibility of the receiver's surface around it: the kernel's light-space footprint
//   (the k x k texels centred on the receiver's texel, s x s stratified jittered points per texel,
//   seeded per receiver) projected along the light onto the receiver's tangent plane, each point
//   traced toward the sun with GroundTruth. It measures compression error plus the map's own
//   filtering error (texel-centre values, one depth for the whole kernel, i.e. PCF's slope acne).
// Errors: the store's (corrupt tile, unknown method).
// Thread safety: reads its arguments only; ShadowMap and GroundTruth are themselves thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "builder/ground_truth.hpp"
#include "builder/receiver_sampler.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles {

struct PointAccuracy {
  uint64_t receivers = 0;
  uint64_t false_lit = 0;       // store lit, truth shadowed
  uint64_t false_shadowed = 0;  // store shadowed, truth lit
  uint64_t truth_lit = 0;
  uint64_t differs_from_raw = 0;  // answers unlike raw's (0 when no raw answers are given)
  uint64_t worse_than_raw = 0;    // ... of which raw was right
  uint64_t outside_map = 0;       // receivers that project off the map (answered lit)
  double error_rate() const { return receivers ? double(false_lit + false_shadowed) / double(receivers) : 0.0; }
  double agreement() const { return receivers ? 1.0 - error_rate() : 0.0; }
};

// Truth per receiver (1 = lit).
std::vector<uint8_t> point_truth(const GroundTruth& truth, std::span<const Receiver> receivers);

// `answers_out` (optional) receives the method's answers; `raw_answers` (optional, same length as
// receivers) are compared with them; `worse_out` (optional) receives the indices of the receivers
// counted in worse_than_raw, in order.
Result<PointAccuracy> point_accuracy(const ShadowMap& map, store::Method method, std::span<const Receiver> receivers,
                                     std::span<const uint8_t> truth, std::span<const uint8_t> raw_answers = {},
                                     std::vector<uint8_t>* answers_out = nullptr,
                                     std::vector<size_t>* worse_out = nullptr);

// Supersampled ground-truth PCF fraction per receiver, for `map`'s frame and default bias.
std::vector<float> pcf_truth(const ShadowMap& map, const GroundTruth& truth, std::span<const Receiver> receivers,
                             unsigned kernel, unsigned supersample, uint64_t seed);

struct PcfAccuracy {
  double mean_abs_error = 0;
  double max_abs_error = 0;
};
Result<PcfAccuracy> pcf_accuracy(const ShadowMap& map, store::Method method, std::span<const Receiver> receivers,
                                 unsigned kernel, std::span<const float> truth);

}  // namespace shadowtiles
