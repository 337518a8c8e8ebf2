// Tests for resolvers/rigid_body/rigid_body_from_magnetism.hpp with every native
// plugin: a soft-iron striker on a planar body is pulled toward an energised
// coil (the doorbell's frames 101-102, paper 4.1.3), the pull starts two steps
// after the current (electricity -> magnetism -> rigid body), and it stops
// when the current drops. Gravity is off so that only magnetism moves it.
#include "resolvers/rigid_body/rigid_body_from_magnetism.hpp"

#include <gtest/gtest.h>

#include "magnet_scene.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::magnetism {
namespace {

using namespace testing;

struct Doorbell {
  scenes::Sim sim;
  ObjectId coil, striker;
  CurrentSource* source = nullptr;

  static WorldDef no_gravity() {
    WorldDef def;
    def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
    return def;
  }
  Doorbell() : sim(no_gravity()) {
    register_current_source(sim.registry);
    World& w = *sim;
    // The coil has no mass: the rigid body does not move it. An iron core
    // (apparent permeability ~40) makes it a 100 A*m-per-ampere magnet.
    coil = add_coil(w, "coil", {0, 0, 0}, 0, 500);
    w.set(coil, prop::kCoilFactor, 0.2);
    w.set(coil, prop::kCurrent, 0.0);
    // The striker: a 50 g soft-iron bar on the play area, 15 cm away on the axis.
    striker = add_iron(w, "striker", {0.15, 0, 0}, 0, 1000);
    w.set(striker, "mass", 0.05);
    w.set(striker, "planar", true);
    w.start();
    source = &current_source_of(w);
  }
  Vec3 position() const { return sim.position(striker); }
  Vec3 velocity() const { return sim.velocity(striker); }
};

TEST(RigidBodyFromMagnetism, IsActiveOnlyWithMagnetsAndABody) {
  Doorbell bell;
  EXPECT_TRUE(bell.sim->has_stage(RigidBodyFromMagnetism::kName));
  scenes::Sim plain;
  scenes::add_box(*plain, {0, 1, 0}, {0.1, 0.1, 0.1}, 1.0);
  plain->run(2);
  EXPECT_FALSE(plain->has_stage(RigidBodyFromMagnetism::kName));
  EXPECT_FALSE(plain->has_stage(MagneticForces::kName));
}

TEST(RigidBodyFromMagnetism, SoftIronIsPulledTowardAnEnergisedCoilAndReleased) {
  Doorbell bell;
  World& w = *bell.sim;
  const Vec3 start = bell.position();
  w.run(24);
  EXPECT_EQ(bell.position(), start) << "no current, no pull";

  // Switch on: electricity publishes 3 A in step n, and magnetic_forces
  // makes the coil's pull from it at once (coils_from_current); the rigid
  // body moves the striker in n+1 (the method's one step from the
  // interaction to the resolver).
  bell.source->next = 3.0;
  w.step();
  EXPECT_EQ(bell.velocity(), Vec3{}) << "the force is still on its way";
  EXPECT_LT(forces_of(w).find(bell.striker)->force.x, 0);
  w.step();
  EXPECT_LT(bell.velocity().x, 0) << "pulled toward the coil";

  bell.sim.run_for(0.1);
  const Vec3 moved = bell.position();
  EXPECT_LT(moved.x, start.x - 0.005);
  EXPECT_NEAR(moved.y, 0, 1e-9);
  EXPECT_NEAR(moved.z, 0, 1e-12) << "planar";
  // The pull grows as the striker closes in (inverse-square-like).
  const double f_near = -forces_of(w).find(bell.striker)->force.x;

  // Switch off: the pull ends in the step the current does; the rigid body
  // still applies the force queued before it, in the next.
  bell.source->next = 0;
  w.step();
  EXPECT_EQ(forces_of(w).find(bell.striker)->force, Vec3{});
  w.step();
  const Vec3 v_off = bell.velocity();
  bell.sim.run_for(0.05);
  EXPECT_NEAR(bell.velocity().x, v_off.x, 1e-12) << "no more pull: it coasts";
  EXPECT_LT(v_off.x, 0);
  EXPECT_GT(f_near, 0);
}

TEST(RigidBodyFromMagnetism, ThePullGrowsAsTheStrikerApproaches) {
  Doorbell bell;
  World& w = *bell.sim;
  bell.source->next = 3.0;
  w.run(3);
  const double f0 = -forces_of(w).find(bell.striker)->force.x;
  bell.sim.run_for(0.15);
  const double f1 = -forces_of(w).find(bell.striker)->force.x;
  EXPECT_GT(bell.position().x, 0.1) << "not yet at the coil";
  EXPECT_GT(f1, f0);
}

}  // namespace
}  // namespace alloy::magnetism
