// The rigid body's multi-rate couplings (docs/performance.md "Multi-rate
// coupling"): a load queued with its rate is followed over the substeps (a
// first-order hold), and substep_contacts = "found" finds the window's
// contact points again before each substep.
#include <gtest/gtest.h>

#include <cmath>

#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::RigidBodyResolver;

RigidBodyResolver& rigid_of(World& w) {
  return dynamic_cast<RigidBodyResolver&>(*w.stage("rigid_body"));
}

WorldDef weightless(int substeps, const char* contacts = "kept") {
  WorldDef def;
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  def.settings["rigid_body"].set("substeps", std::int64_t(substeps));
  def.settings["rigid_body"].set("substep_contacts", std::string(contacts));
  return def;
}

TEST(RigidBodyLoadRates, SubstepsFollowTheRateAndOneSubstepHoldsTheValue) {
  // A free sphere, one window, force F + R t along x and torque T + S t about
  // z: substep s applies the value at s h, so the window's impulse is
  // F dt + R h^2 n (n - 1) / 2 (and the same for the torque); with one
  // substep it is exactly the value's.
  constexpr double m = 2.0, r = 0.1, F = 3.0, R = 400.0, T = 0.02, S = 5.0;
  const double I = 0.4 * m * r * r;
  for (int n : {1, 4}) {
    Sim s(weightless(n));
    const ObjectId ball = add_sphere(*s, {0, 1, 0}, r, m);
    s->start();
    rigid_of(*s).add_load(ball, {F, 0, 0}, {0, 0, T}, {R, 0, 0}, {0, 0, S});
    s->step();
    const double dt = s->dt(), h = dt / n, ramp = h * h * n * (n - 1) / 2;
    EXPECT_NEAR(s.velocity(ball).x, (F * dt + R * ramp) / m, 1e-12) << n;
    EXPECT_NEAR(std::get<Vec3>(s->get(ball, "angular_velocity")).z, (T * dt + S * ramp) / I, 1e-9)
        << n;
    // Performed once: the next window has no load.
    const Vec3 v = s.velocity(ball);
    s->step();
    EXPECT_EQ(s.velocity(ball), v) << n;
  }
}

TEST(RigidBodyLoadRates, AStaleObjectIsRefused) {
  Sim s(weightless(2));
  const ObjectId ball = add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
  s->start();
  s->destroy(ball);
  EXPECT_THROW(rigid_of(*s).add_load(ball, {}, {}, {}, {}), AccessError);
}

TEST(RigidBodySubstepContacts, FoundContactsKeepARestingBallAtRestAndReportTheImpulse) {
  WorldDef def;
  def.settings["rigid_body"].set("substeps", std::int64_t(4));
  def.settings["rigid_body"].set("substep_contacts", std::string("found"));
  def.settings["collisions"].set("impulses", true);  // read below: computed for readers only
  Sim s(def);
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(1.0);
  const auto imp = rigid_of(*s).impulses();
  ASSERT_EQ(imp.size(), 1u);
  EXPECT_NEAR(imp[0].normal_impulse, 0.5 * 9.81 * s->dt(), 1e-2 * 0.5 * 9.81 * s->dt());
  EXPECT_NEAR(s.velocity(b.ball).y, 0, 1e-3);
  EXPECT_NEAR(s.position(b.ball).y, b.radius, 1e-3);
}

TEST(RigidBodySubstepContacts, BadValuesAreRefused) {
  Sim s(weightless(2, "sometimes"));
  add_sphere(*s, {}, 0.1, 1.0);
  EXPECT_THROW(s->start(), InputError);
}

}  // namespace
}  // namespace alloy::scenes
