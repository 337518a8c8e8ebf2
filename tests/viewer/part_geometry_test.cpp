// Tests for apps/viewer/part_geometry and camera: shapes read from
// properties, hit tests, overlap depth, and the metres-to-pixels mapping.
#include "apps/viewer/part_geometry.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "apps/viewer/camera.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

Part2D box(Vec2 c, double hw, double hh, double angle = 0) {
  Part2D p;
  p.shape = Shape2D::Box;
  p.centre = c;
  p.half = {hw, hh};
  p.angle = angle;
  return p;
}

Part2D disk(Vec2 c, double r) {
  Part2D p;
  p.shape = Shape2D::Disk;
  p.centre = c;
  p.radius = r;
  return p;
}

TEST(PartGeometry, ReadsEveryKitPartOfTheDemo) {
  auto l = test::load(test::source("mods/rigid_demo"));
  const auto parts = read_parts(l.world());
  // floor, two walls, ramp, pendulum, two disks, ball, plank, wheel: the hinge
  // and the pin are joints, not parts.
  EXPECT_EQ(parts.size(), 10u);
  const auto floor = read_part(l.world(), l.world().find("floor"));
  ASSERT_TRUE(floor);
  EXPECT_EQ(floor->shape, Shape2D::Box);
  EXPECT_TRUE(floor->is_static);
  EXPECT_NEAR(floor->half.x, 3.0, 1e-12);
  const auto ramp = read_part(l.world(), l.world().find("ramp"));
  ASSERT_TRUE(ramp);
  EXPECT_NEAR(ramp->angle, -0.35, 1e-9);
  const auto ball = read_part(l.world(), l.world().find("ball"));
  ASSERT_TRUE(ball);
  EXPECT_EQ(ball->shape, Shape2D::Disk);
  EXPECT_NEAR(ball->radius, 0.08, 1e-12);
  EXPECT_FALSE(read_part(l.world(), l.world().find("pivot")));
}

TEST(PartGeometry, ContainsFollowsRotation) {
  const Part2D b = box({1, 1}, 0.5, 0.05, std::numbers::pi / 2);  // standing upright
  EXPECT_TRUE(contains(b, {1, 1.4}));
  EXPECT_FALSE(contains(b, {1.4, 1}));
  EXPECT_TRUE(contains(b, {1.06, 1}, 0.02));
  const Part2D d = disk({0, 0}, 0.1);
  EXPECT_TRUE(contains(d, {0.07, 0.07}));
  EXPECT_FALSE(contains(d, {0.08, 0.08}));
}

TEST(PartGeometry, OverlapDepthIsThePushThatSeparates) {
  EXPECT_NEAR(overlap_depth(box({0, 0}, 1, 0.1), box({0, 0.15}, 0.1, 0.1)), 0.05, 1e-9);
  EXPECT_LE(overlap_depth(box({0, 0}, 1, 0.1), box({0, 0.25}, 0.1, 0.1)), 0);
  EXPECT_NEAR(overlap_depth(disk({0, 0}, 0.1), disk({0.15, 0}, 0.1)), 0.05, 2e-3);
}

TEST(Camera, ScreenAndWorldAreInverse) {
  Camera c;
  c.fit({-3, 0}, {3, 2}, 100, 0, 1100, 800);
  const Vec2 p{1.25, 0.75};
  const ScreenPoint s = c.to_screen(p);
  const Vec2 back = c.to_world(s.x, s.y);
  EXPECT_NEAR(back.x, p.x, 1e-5);
  EXPECT_NEAR(back.y, p.y, 1e-5);
  EXPECT_LT(c.to_screen({0, 2}).y, c.to_screen({0, 0}).y) << "y is up in the play area";
  const ScreenPoint before = c.to_screen(p);
  c.zoom_at(before.x, before.y, 2);
  const ScreenPoint after = c.to_screen(p);
  EXPECT_NEAR(after.x, before.x, 1e-3);
  EXPECT_NEAR(after.y, before.y, 1e-3);
}

}  // namespace
}  // namespace alloy::viewer
