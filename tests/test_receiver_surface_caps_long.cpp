// Receiver-surface exit caps at build resolutions (label `long`): every texel of every tile of the
// house, the bust and the terrain at 4096², fast caps vs the original per-texel clipping, bit for bit.
#include <gtest/gtest.h>

#include "receiver_surface_caps_reference.hpp"

namespace shadowtiles {
namespace {

using testing::expect_scene_identical;

TEST(ReceiverSurfaceCapsLong, HouseAt4096MatchesTheClipping) {
  expect_scene_identical("fzk_haus/fzk_haus.obj", UpAxis::y, {}, 135, 45, 4096, 2048);
}

TEST(ReceiverSurfaceCapsLong, BustAt4096MatchesTheClipping) {
  expect_scene_identical("nefertiti/nefertiti.obj", UpAxis::z, {}, 135, 45, 4096, 2048);
}

TEST(ReceiverSurfaceCapsLong, TerrainAt4096MatchesTheClipping) {
  expect_scene_identical("terragen/RealisticTerrain.ter", UpAxis::z, {"*"}, 135, 30, 4096, 2048);
}

}  // namespace
}  // namespace shadowtiles
