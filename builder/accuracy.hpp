// Accuracy of a stored method against ground truth (docs/architecture.md §11): for receiver points on the
// scene's surfaces, the store's lit/shadowed answer vs an Embree occlusion ray toward the sun.
// Thread safety: evaluate_accuracy reads its arguments only; the ShadowMap and GroundTruth it uses
// are themselves thread-safe.
#pragma once

#include <cstdint>
#include <span>

#include "builder/ground_truth.hpp"
#include "builder/receiver_sampler.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles {

struct AccuracyCounts {
  uint64_t receivers = 0;
  uint64_t agree = 0;
  uint64_t false_lit = 0;       // store says lit, ground truth shadowed (a light leak)
  uint64_t false_shadowed = 0;  // store says shadowed, ground truth lit (acne, lost detail)
  uint64_t truth_lit = 0;       // how many the ground truth calls lit (for the trivial baselines)
  uint64_t outside_map = 0;

  double agreement() const { return receivers ? double(agree) / double(receivers) : 0.0; }
};

// `bias`: world units, default the store's. Errors: the store's (corrupt tile, unknown method).
Result<AccuracyCounts> evaluate_accuracy(const ShadowMap& map, store::Method method, const GroundTruth& truth,
                                         std::span<const Receiver> receivers, std::optional<double> bias = {});

}  // namespace shadowtiles
