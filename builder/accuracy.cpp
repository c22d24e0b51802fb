#include "builder/accuracy.hpp"

namespace shadowtiles {

Result<AccuracyCounts> evaluate_accuracy(const ShadowMap& map, store::Method method, const GroundTruth& truth,
                                         std::span<const Receiver> receivers, std::optional<double> bias) {
  AccuracyCounts counts;
  for (const Receiver& receiver : receivers) {
    auto answer = map.query(receiver.position, method, bias);
    if (!answer) return answer.error();
    bool truth_lit = truth.lit(receiver.position);
    ++counts.receivers;
    counts.truth_lit += truth_lit;
    counts.outside_map += answer->outside_map;
    if (answer->lit == truth_lit) ++counts.agree;
    else if (answer->lit) ++counts.false_lit;
    else ++counts.false_shadowed;
  }
  return counts;
}

}  // namespace shadowtiles
