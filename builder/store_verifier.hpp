// Store verification: recompute every tile's dual-depth intervals from the scene and check that
// every stored method's decoded value of every texel lies inside [lower, upper] under the store's
// receiver contract — the definition of lossless (docs/architecture.md §5, docs/receiver-contracts.md). The
// texel-centre intervals come from the ray caster; when the store was built with exit caps they are
// capped by an independent brute-force reference (builder/reference_caps: every triangle clipped to
// every texel's square in double), not by the build's fast cap pass. Also checks the consequence the
// user cares about: a shadow test at a depth just outside the interval answers as the exact entry
// depth does. CPVS stores visibility, not values: it is checked by its step rule instead (receivers
// 1.5 depth steps outside the interval get the exact answer; store_verifier.cpp, docs/cpvs.md).
// Thread safety: runs its own worker threads; the ShadowMap must not be closed meanwhile.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "builder/scene.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles {

struct MethodVerification {
  uint64_t texels = 0;
  uint64_t outside = 0;          // decoded value outside [lower, upper]
  uint64_t wrong_answers = 0;    // shadow test just outside the interval differs from the exact one
  uint64_t tiles = 0;
  std::string first_violation;   // where, for the log
};

// Float steps a decoded value may lie above a capped upper bound (see store_verifier.cpp).
constexpr unsigned kCapUlps = 2;

struct VerifyReport {
  std::map<store::Method, MethodVerification> methods;
  uint64_t tiles_checked = 0;
  ReceiverContract receivers = ReceiverContract::anywhere;  // the store's contract, as verified
  bool exit_caps = false;                                    // intervals capped by the reference
  double entry_slack = 0;  // world units; > 0: the interval methods checked against the entry rule's reference
  uint64_t reference_cap_texels = 0;                         // texels whose cap the reference computed
  bool ok() const {
    for (const auto& [method, v] : methods)
      if (v.outside || v.wrong_answers) return false;
    return true;
  }
};

// `scene` must be the scene the store was built from, loaded with the build's heightfield meshes.
// Errors: unreadable or corrupt tiles (corrupt_data), Embree failures.
Result<VerifyReport> verify_store(const ShadowMap& map, const Scene& scene, const std::vector<store::Method>& methods,
                                  unsigned threads = 2,
                                  const std::function<void(uint64_t done, uint64_t total)>& progress = {});

}  // namespace shadowtiles
