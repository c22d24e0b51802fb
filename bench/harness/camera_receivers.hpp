// Camera receivers: the surface points seen by the pixels of a fixed perspective camera, in screen
// order (row by row). They are the receivers a renderer would query, so they measure accuracy where
// a viewer looks and give the "coherent screen order" of the lookup-rate figures.
// The camera sits on the scene's bounding sphere (1.3 radii from the centre), at `azimuth`
// (clockwise from north) and `elevation` above the horizon, looking at the centre; pixels whose
// primary ray misses are dropped. Deterministic.
// Errors: none (an empty vector when nothing is seen).
// Thread safety: pure function (builds and releases its own Embree scene).
#pragma once

#include <vector>

#include "bench/harness/bench_config.hpp"
#include "builder/embree_device.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene.hpp"

namespace shadowtiles::bench {

std::vector<Receiver> camera_receivers(const EmbreeDevice& device, const Scene& scene, UpAxis up,
                                       const CameraSpec& camera);

}  // namespace shadowtiles::bench
