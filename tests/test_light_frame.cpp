// Light frame: world <-> light space, basis, fitting, resolution from texel size, tiling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "codec/light_frame.hpp"
#include "codec/tile_layout.hpp"

namespace shadowtiles {
namespace {

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

TEST(LightFrame, BasisIsOrthonormalAndRightHanded) {
  for (Vec3 dir : {Vec3{0, 0, -1}, Vec3{1, 2, -3}, Vec3{0, 1, 0}, Vec3{0, 0, 1}, Vec3{-5, 0.1, 0}}) {
    WorldBounds bounds{{-1, -1, -1}, {1, 1, 1}};
    auto frame = LightFrame::fit(dir, bounds, 256);
    ASSERT_TRUE(frame.ok());
    const Vec3 &x = frame->axis_x(), &y = frame->axis_y(), &z = frame->direction();
    EXPECT_NEAR(dot(x, x), 1, 1e-12);
    EXPECT_NEAR(dot(y, y), 1, 1e-12);
    EXPECT_NEAR(dot(z, z), 1, 1e-12);
    EXPECT_NEAR(dot(x, y), 0, 1e-12);
    EXPECT_NEAR(dot(x, z), 0, 1e-12);
    Vec3 cross{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
    EXPECT_NEAR(dot(cross, z), 1, 1e-12) << "x cross y must be z";
    double len = std::sqrt(dot(dir, dir));
    EXPECT_NEAR(dot(z, dir) / len, 1, 1e-12) << "z is the light direction";
  }
}

TEST(LightFrame, RoundTripsWorldPointsIncludingHugeCoordinates) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (double offset : {0.0, 1e6, -3e6}) {
    WorldBounds bounds{{offset - 500, offset - 400, -50}, {offset + 500, offset + 400, 300}};
    auto frame = LightFrame::fit({0.3, -0.2, -1}, bounds, 1u << 20);
    ASSERT_TRUE(frame.ok());
    for (int i = 0; i < 1000; ++i) {
      Vec3 p{offset + 500 * unit(random), offset + 400 * unit(random), 100 + 150 * unit(random)};
      Vec3 back = frame->to_world(frame->to_light(p));
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[k], p[k], 1e-6);
    }
  }
}

TEST(LightFrame, BoundsMapInsideTheMapAndDepthRange) {
  WorldBounds bounds{{-10, -20, 0}, {30, 5, 8}};
  auto frame = LightFrame::fit({1, 1, -2}, bounds, 1024);
  ASSERT_TRUE(frame.ok());
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 p{(corner & 1) ? bounds.max[0] : bounds.min[0], (corner & 2) ? bounds.max[1] : bounds.min[1],
           (corner & 4) ? bounds.max[2] : bounds.min[2]};
    LightSpacePoint l = frame->to_light(p);
    EXPECT_GT(l.u, 0);
    EXPECT_LT(l.u, 1024);
    EXPECT_GT(l.v, 0);
    EXPECT_LT(l.v, 1024);
    EXPECT_GT(l.depth, 0);
    EXPECT_LT(l.depth, 1);
  }
}

TEST(LightFrame, DepthGrowsAlongTheLight) {
  WorldBounds bounds{{-1, -1, -1}, {1, 1, 1}};
  auto frame = LightFrame::fit({0, 0, -1}, bounds, 64);  // sun straight above
  ASSERT_TRUE(frame.ok());
  EXPECT_LT(frame->to_light({0, 0, 1}).depth, frame->to_light({0, 0, -1}).depth);
  EXPECT_NEAR(frame->to_light({0, 0, -1}).depth - frame->to_light({0, 0, 1}).depth,
              frame->depth_from_world(2.0), 1e-12);
}

TEST(LightFrame, RejectsBadInput) {
  WorldBounds bounds{{0, 0, 0}, {1, 1, 1}};
  EXPECT_FALSE(LightFrame::fit({0, 0, 0}, bounds, 64).ok());
  EXPECT_FALSE(LightFrame::fit({NAN, 0, -1}, bounds, 64).ok());
  EXPECT_FALSE(LightFrame::fit({0, 0, -1}, bounds, 100).ok()) << "not a power of two";
  EXPECT_FALSE(LightFrame::fit({0, 0, -1}, bounds, 1u << 21).ok());
  EXPECT_FALSE(LightFrame::fit({0, 0, -1}, WorldBounds{{1, 0, 0}, {0, 1, 1}}, 64).ok());
  EXPECT_TRUE(LightFrame::fit({0, 0, -1}, bounds, 1).ok()) << "a 1x1 map is valid";
}

// Receivers beyond the far plane are queried as on it (ShadowMap), which is right only when no
// surface reaches depth 1: the deepest corner stays the far margin (in texels) and two quantisation
// steps (CPVS: max(resolution, 8) steps) short of it, also for a flat scene and a 1x1 map.
TEST(LightFrame, DeepestGeometryStaysTheFarMarginShortOfDepthOne) {
  struct Case {
    WorldBounds bounds;
    Vec3 direction;
    uint32_t resolution;
    double margin_texels;
  };
  for (const Case& c : {Case{{{-10, -20, 0}, {30, 5, 8}}, {1, 1, -2}, 1024, LightFrame::kDefaultFarMarginTexels},
                        Case{{{0, 0, 0}, {10, 10, 0}}, {0, 0, -1}, 64, LightFrame::kDefaultFarMarginTexels},
                        Case{{{0, 0, 0}, {1, 1, 100}}, {0, 0, -1}, 4096, 0},  // deep scene: the steps decide
                        Case{{{0, 0, 0}, {10, 10, 1}}, {0.2, 0.1, -1}, 1, 40}}) {
    auto frame = LightFrame::fit(c.direction, c.bounds, c.resolution, c.margin_texels);
    ASSERT_TRUE(frame.ok());
    double deepest = 0;
    for (int corner = 0; corner < 8; ++corner) {
      Vec3 p{(corner & 1) ? c.bounds.max[0] : c.bounds.min[0], (corner & 2) ? c.bounds.max[1] : c.bounds.min[1],
             (corner & 4) ? c.bounds.max[2] : c.bounds.min[2]};
      deepest = std::max(deepest, frame->to_light(p).depth);
    }
    EXPECT_LE(deepest, 1 - frame->depth_from_world(c.margin_texels * frame->texel_size()) - 2.0 / std::max(c.resolution, 8u));
    if (c.resolution >= 1024) {
      EXPECT_GT(deepest, 0.95) << "the margin must not swallow a real scene's depth range";
    }
  }
  EXPECT_FALSE(LightFrame::fit({0, 0, -1}, WorldBounds{{0, 0, 0}, {1, 1, 1}}, 64, -1).ok());
  EXPECT_FALSE(LightFrame::fit({0, 0, -1}, WorldBounds{{0, 0, 0}, {1, 1, 1}}, 64, NAN).ok());
}

TEST(LightFrame, DegenerateBoundsStillGiveAPositiveExtent) {
  WorldBounds point{{5, 5, 5}, {5, 5, 5}};
  auto frame = LightFrame::fit({0, 0, -1}, point, 16);
  ASSERT_TRUE(frame.ok());
  EXPECT_GT(frame->extent(), 0);
  EXPECT_GT(frame->depth_range(), 0);
}

TEST(LightFrame, ResolutionForTexelSizeIsTheSmallestPowerOfTwoThatReaches) {
  WorldBounds bounds{{0, 0, 0}, {100, 100, 10}};
  Vec3 dir{0, 0, -1};
  auto resolution = LightFrame::resolution_for_texel_size(dir, bounds, 0.5);
  ASSERT_TRUE(resolution.ok());
  auto frame = LightFrame::fit(dir, bounds, *resolution);
  EXPECT_LE(frame->texel_size(), 0.5);
  EXPECT_GT(frame->extent() / (*resolution / 2), 0.5) << "half the resolution would not reach";
  EXPECT_FALSE(LightFrame::resolution_for_texel_size(dir, bounds, 1e-9).ok()) << "beyond 2^20";
  EXPECT_FALSE(LightFrame::resolution_for_texel_size(dir, bounds, -1).ok());
}

TEST(LightFrame, SunDirectionFollowsAzimuthAndElevation) {
  auto overhead = light_direction_from_sun(0, 90, UpAxis::z);
  ASSERT_TRUE(overhead.ok());
  EXPECT_NEAR((*overhead)[2], -1, 1e-12);
  auto east_low = light_direction_from_sun(90, 10, UpAxis::z);  // sun in the east: light travels west
  ASSERT_TRUE(east_low.ok());
  EXPECT_LT((*east_low)[0], -0.9);
  auto y_up = light_direction_from_sun(0, 90, UpAxis::y);
  EXPECT_NEAR((*y_up)[1], -1, 1e-12);
  EXPECT_FALSE(light_direction_from_sun(0, 0, UpAxis::z).ok());
  EXPECT_FALSE(light_direction_from_sun(0, -5, UpAxis::z).ok());
}

TEST(TileLayout, TilesAndMortonOrder) {
  auto layout = TileLayout::make(1u << 16, 4096);
  ASSERT_TRUE(layout.ok());
  EXPECT_EQ(layout->tiles_per_side(), 16u);
  EXPECT_EQ(layout->tile_level(), 4);
  EXPECT_EQ(layout->levels_in_tile(), 12);
  for (uint64_t i = 0; i < 256; ++i)
    EXPECT_EQ(TileLayout::morton_index(TileLayout::from_morton_index(i)), i);
  EXPECT_EQ(TileLayout::morton_index({1, 0}), 1u);
  EXPECT_EQ(TileLayout::morton_index({0, 1}), 2u);
  auto clamped = TileLayout::make(256, 4096);
  ASSERT_TRUE(clamped.ok());
  EXPECT_EQ(clamped->tile_size(), 256u) << "a tile larger than the map is the map";
  EXPECT_FALSE(TileLayout::make(300, 64).ok());
}

}  // namespace
}  // namespace shadowtiles
