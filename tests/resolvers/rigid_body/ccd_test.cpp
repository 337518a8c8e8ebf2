// Continuous collision detection (rigid_body setting `ccd`): a part that would
// cross a thin wall in one step is moved back to where it first touches it,
// the contact is reported as any other, and what is not a projectile's flight
// (an edit that carries a part through a wall) is left alone.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kWall = 0.05;     // thickness, m; its front face is at x = 0
constexpr double kRadius = 0.02;   // the ball's
constexpr double kSpeed = 100;     // m/s: 0.42 m a step at 240 Hz, 8 times the wall

struct Range {
  Sim sim;
  ObjectId wall, ball;
  explicit Range(bool ccd, double restitution = 0) : sim(def(ccd)) {
    World& w = *sim;
    wall = w.create("wall");
    w.set(wall, "shape", std::string("box"));
    w.set(wall, "size", Vec3{kWall, 2, 2});
    w.set(wall, "position", Vec3{kWall / 2, 0, 0});
    w.set(wall, "static", true);
    w.set(wall, "restitution", restitution);
    // 0.3 m in front of the wall: the next step ends 0.12 m beyond its far face.
    ball = add_sphere(w, {-0.3, 0, 0}, kRadius, 0.05, "ball");
    w.set(ball, "velocity", Vec3{kSpeed, 0, 0});
    w.set(ball, "restitution", restitution);
  }
  static WorldDef def(bool ccd, bool gravity = false) {
    WorldDef d;
    d.settings["rigid_body"].set("ccd", ccd);
    if (!gravity) d.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
    return d;
  }
  double x() const { return sim.position(ball).x; }
};

TEST(RigidBodyCcd, AFastBallStopsAtAThinWall) {
  Range r(true);
  bool began = false;
  for (int i = 0; i < 24; ++i) {
    r.sim->step();
    for (const Event& e : r.sim->events())
      if (e.type == "contact_began" && (e.a == r.ball || e.b == r.ball)) began = true;
  }
  EXPECT_TRUE(began) << "the swept contact is reported as a contact";
  // Inelastic: it rests against the front face (within the resting overlap).
  EXPECT_NEAR(r.x(), -kRadius, 1e-3);
  EXPECT_LT(std::abs(r.sim.velocity(r.ball).x), 0.05);
}

TEST(RigidBodyCcd, WithoutItTheBallPassesThrough) {
  Range r(false);
  r.sim->run(24);
  EXPECT_GT(r.x(), kWall + kRadius) << "the control: the wall is thin enough to tunnel through";
}

TEST(RigidBodyCcd, AnElasticBallComesBackAtItsSpeed) {
  Range r(true, 1.0);
  r.sim->run(24);
  EXPECT_LT(r.x(), -kRadius);
  EXPECT_NEAR(r.sim.velocity(r.ball).x, -kSpeed, 0.05 * kSpeed);
}

TEST(RigidBodyCcd, AnEditThatCarriesAPartThroughTheWallStands) {
  Range r(true);
  r.sim->set(r.ball, "velocity", Vec3{0, 0, 0});
  r.sim->step();
  r.sim->set(r.ball, "position", Vec3{0.5, 0, 0});  // a player drags it behind the wall
  r.sim->run(4);
  EXPECT_NEAR(r.x(), 0.5, 1e-9);
}

TEST(RigidBodyCcd, SlowPartsAreNotDisturbed) {
  // A ball rolling on a floor at 3 m/s moves 12.5 mm a step, more than half
  // its radius, so it is swept every step; it crosses no surface, so its path
  // is the same with and without.
  auto roll = [](bool ccd) {
    Sim s(Range::def(ccd, true));
    add_floor(*s);
    const ObjectId ball = add_sphere(*s, {0, kRadius, 0}, kRadius, 0.05, "ball");
    s->set(ball, "velocity", Vec3{3, 0, 0});
    s.run_for(1);
    return s.position(ball);
  };
  const Vec3 a = roll(true), b = roll(false);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
}

}  // namespace
}  // namespace alloy::scenes
