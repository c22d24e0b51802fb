// Shading of traced frames (builder/frame_renderer.hpp) for `shadowtiles render`: sun visibility
// per pixel from a ShadowMap (the product: point or PCF lookups) or from Embree occlusion rays
// (ground truth), Lambert shading from the sun, and the image of where two visibilities disagree.
// Only pixels whose surface faces the sun (n . to_sun > 0) are looked up: the others are dark
// whatever the shadow says, so their visibility is 0 and they never count as a disagreement.
// Receiver = the primary hit point; the map's bias is the build's default.
// Errors: visibility_from_map → the map's errors (the first one met; an error is never shaded).
// Thread safety: functions are reentrant; they run `threads` workers over rows.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/frame_renderer.hpp"
#include "builder/ground_truth.hpp"
#include "builder/png_image.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles {

// n . to_sun per pixel (0 for misses and for surfaces facing away). `light_direction`: travel direction.
std::vector<float> sun_facing(const FrameHits& frame, const Vec3& light_direction);

// Lit fraction per pixel in [0, 1]: the point query's answer (pcf_kernel 1) or the PCF fraction.
Result<std::vector<float>> visibility_from_map(const ShadowMap& map, store::Method method, unsigned pcf_kernel,
                                               const FrameHits& frame, unsigned threads = 2);
std::vector<float> visibility_from_ground_truth(const GroundTruth& truth, const FrameHits& frame,
                                                const Vec3& light_direction, unsigned threads = 2);

// Sky for misses; albedo * (ambient + (1 - ambient) * facing * visibility) for hits.
RgbImage shade_frame(const FrameHits& frame, const std::vector<float>& visibility, const Vec3& light_direction);

struct FrameDiff {
  RgbImage image;             // the ground truth dimmed; false lit red, false shadowed blue
  uint64_t compared = 0;      // pixels seeing a surface that faces the sun
  uint64_t false_lit = 0;     // tested says lit (fraction > 0.5), truth says shadowed
  uint64_t false_shadowed = 0;
  uint64_t pixels = 0;        // width * height
  uint64_t disagreeing() const { return false_lit + false_shadowed; }
  double fraction_of_compared() const { return compared ? double(disagreeing()) / double(compared) : 0; }
  double fraction_of_frame() const { return pixels ? double(disagreeing()) / double(pixels) : 0; }
};
FrameDiff diff_frames(const FrameHits& frame, const std::vector<float>& tested, const std::vector<float>& truth,
                      const Vec3& light_direction);

}  // namespace shadowtiles
