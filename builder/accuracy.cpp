#include "builder/accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace shadowtiles {

std::vector<uint8_t> point_truth(const GroundTruth& truth, std::span<const Receiver> receivers) {
  std::vector<uint8_t> lit(receivers.size());
  for (size_t i = 0; i < receivers.size(); ++i) lit[i] = truth.lit(receivers[i].position) ? 1 : 0;
  return lit;
}

Result<PointAccuracy> point_accuracy(const ShadowMap& map, store::Method method, std::span<const Receiver> receivers,
                                     std::span<const uint8_t> truth, std::span<const uint8_t> raw_answers,
                                     std::vector<uint8_t>* answers_out, std::vector<size_t>* worse_out) {
  PointAccuracy acc;
  if (answers_out) answers_out->assign(receivers.size(), 0);
  if (worse_out) worse_out->clear();
  for (size_t i = 0; i < receivers.size(); ++i) {
    auto answer = map.query(receivers[i].position, method);
    if (!answer) return answer.error();
    const bool lit = answer->lit, truly_lit = truth[i] != 0;
    ++acc.receivers;
    acc.truth_lit += truly_lit;
    acc.outside_map += answer->outside_map;
    if (lit && !truly_lit) ++acc.false_lit;
    if (!lit && truly_lit) ++acc.false_shadowed;
    if (!raw_answers.empty() && (raw_answers[i] != 0) != lit) {
      ++acc.differs_from_raw;
      if ((raw_answers[i] != 0) == truly_lit) {
        ++acc.worse_than_raw;
        if (worse_out) worse_out->push_back(i);
      }
    }
    if (answers_out) (*answers_out)[i] = lit ? 1 : 0;
  }
  return acc;
}

std::vector<float> pcf_truth(const ShadowMap& map, const GroundTruth& truth, std::span<const Receiver> receivers,
                             unsigned kernel, unsigned supersample, uint64_t seed) {
  const LightFrame& frame = map.frame();
  const Vec3& light = frame.direction();
  const int half = int(kernel / 2);
  const double step = 1.0 / supersample;
  std::vector<float> fractions(receivers.size());
  std::uniform_real_distribution<double> jitter(0.0, step);
  for (size_t i = 0; i < receivers.size(); ++i) {
    std::mt19937_64 random(seed * 1000003u + i);
    const Vec3& at = receivers[i].position;
    const Vec3& n = receivers[i].normal;
    const LightSpacePoint p = frame.to_light(at);
    const double n_dot_l = n[0] * light[0] + n[1] * light[1] + n[2] * light[2];
    const double cu = std::floor(p.u), cv = std::floor(p.v);
    uint64_t lit = 0, samples = 0;
    for (int dv = -half; dv <= half; ++dv)
      for (int du = -half; du <= half; ++du)
        for (unsigned sy = 0; sy < supersample; ++sy)
          for (unsigned sx = 0; sx < supersample; ++sx) {
            LightSpacePoint q{cu + du + sx * step + jitter(random), cv + dv + sy * step + jitter(random), p.depth};
            Vec3 w = frame.to_world(q);
            // Slide along the light onto the receiver's tangent plane (kept when grazing).
            if (std::abs(n_dot_l) > 1e-3) {
              const double t = ((at[0] - w[0]) * n[0] + (at[1] - w[1]) * n[1] + (at[2] - w[2]) * n[2]) / n_dot_l;
              for (int k = 0; k < 3; ++k) w[k] += t * light[k];
            }
            lit += truth.lit(w);
            ++samples;
          }
    fractions[i] = float(double(lit) / double(samples));
  }
  return fractions;
}

Result<PcfAccuracy> pcf_accuracy(const ShadowMap& map, store::Method method, std::span<const Receiver> receivers,
                                 unsigned kernel, std::span<const float> truth) {
  PcfAccuracy acc;
  double sum = 0;
  for (size_t i = 0; i < receivers.size(); ++i) {
    auto fraction = map.query_pcf(receivers[i].position, method, kernel);
    if (!fraction) return fraction.error();
    const double error = std::abs(*fraction - double(truth[i]));
    sum += error;
    acc.max_abs_error = std::max(acc.max_abs_error, error);
  }
  acc.mean_abs_error = receivers.empty() ? 0.0 : sum / double(receivers.size());
  return acc;
}

}  // namespace shadowtiles
