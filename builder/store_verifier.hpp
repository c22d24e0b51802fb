// Store verification: recompute every tile's dual-depth intervals from the scene and check that
// every stored method's decoded value of every texel lies inside [lower, upper] — the definition of
// lossless (docs/architecture.md §5). Also checks the consequence the user cares about: a shadow test at a depth
// just outside the interval answers as the exact entry depth does. CPVS stores visibility, not
// values: it is checked by its step rule instead (receivers 1.5 depth steps outside the interval get
// the exact answer; store_verifier.cpp, docs/cpvs.md). Intervals are recomputed from the texel
// centre ray, the loosest a build may use, so builds with and without exit caps both verify.
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

struct VerifyReport {
  std::map<store::Method, MethodVerification> methods;
  uint64_t tiles_checked = 0;
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
