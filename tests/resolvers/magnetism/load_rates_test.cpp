// magnetic_forces `rates`: each part's force and torque rate along the
// present motion (velocity, angular velocity), which rigid_body_from_magnetism
// queues with the load for the rigid body's first-order hold over substeps.
// Checked against the change of the force over the next step of a heavy bar
// that barely accelerates, so that its motion is the present one.
#include <gtest/gtest.h>

#include "magnet_scene.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::magnetism {
namespace {

using namespace testing;

WorldDef def_with(bool rates) {
  WorldDef def;
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  def.settings["magnetic_forces"].set("rates", rates);
  return def;
}

struct Pair {
  scenes::Sim sim;
  ObjectId fixed, moving;
  explicit Pair(bool rates) : sim(def_with(rates)) {
    World& w = *sim;
    fixed = add_permanent(w, "fixed", {0, 0, 0}, 0, 50);
    moving = add_permanent(w, "moving", {0.12, 0.03, 0}, 0.3, 50);
    w.set(moving, "mass", 100.0);  // heavy: its velocity stays what it is given
    w.set(moving, "planar", true);
    w.set(moving, "velocity", Vec3{-0.2, 0.1, 0});
    w.set(moving, "angular_velocity", Vec3{0, 0, 3.0});
    w.start();
  }
};

TEST(MagneticForceRates, TheRateIsTheForcesChangeAlongThePresentMotion) {
  Pair p(true);
  World& w = *p.sim;
  w.step();  // forces and rates from the moved pose
  const MagneticBody before = *forces_of(w).find(p.moving);
  ASSERT_GT(length(before.force), 0.0);
  ASSERT_GT(length(before.force_rate), 0.0);
  w.step();
  const MagneticBody after = *forces_of(w).find(p.moving);
  const double dt = w.dt();
  // A first-order prediction: agrees to the second-order term (a few % here).
  const Vec3 df = after.force - before.force, dq = after.torque - before.torque;
  EXPECT_LT(length(df - dt * before.force_rate), 0.05 * length(df));
  EXPECT_LT(length(dq - dt * before.torque_rate), 0.05 * length(dq));
  // The part at rest has a rate from the other's motion only, opposite in force.
  const MagneticBody still = *forces_of(w).find(p.fixed);
  EXPECT_GT(length(still.force_rate), 0.0);
}

TEST(MagneticForceRates, OffByDefaultAndTheValuesAreTheSame) {
  Pair with(true), without(false);
  with.sim->run(3);
  without.sim->run(3);
  const MagneticBody* a = forces_of(*with.sim).find(with.moving);
  const MagneticBody* b = forces_of(*without.sim).find(without.moving);
  EXPECT_EQ(b->force_rate, Vec3{});
  EXPECT_EQ(b->torque_rate, Vec3{});
  EXPECT_FALSE(forces_of(*without.sim).rates());
  // With one rigid substep the hold is exactly the value: the runs agree.
  EXPECT_EQ(a->force, b->force);
  EXPECT_EQ(with.sim.position(with.moving), without.sim.position(without.moving));
}

}  // namespace
}  // namespace alloy::magnetism
