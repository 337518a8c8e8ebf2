// Two rigid_body settings that trade work for accuracy or save it: substeps
// (several ODE steps per coupling window, queued forces held) and auto_disable
// (bodies at rest sleep until something disturbs them).
#include <gtest/gtest.h>

#include <cmath>

#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::RigidBodyResolver;

constexpr double g = 9.81;

RigidBodyResolver& rigid_of(World& w) {
  return dynamic_cast<RigidBodyResolver&>(*w.stage("rigid_body"));
}

WorldDef with_substeps(int n) {
  WorldDef def;
  def.settings["rigid_body"].set("substeps", std::int64_t(n));
  return def;
}

TEST(RigidBodySubsteps, FreeFallErrorShrinksWithTheSubstep) {
  // Gravity is a force queued once per window by rigid_body_from_gravity and
  // held over the substeps: semi-implicit Euler's error is then that of the
  // substep, 1/2 g T h.
  for (int n : {1, 4}) {
    Sim s(with_substeps(n));
    const FreeFall ff = build_free_fall(*s, 10);
    const double T = 2.0;
    s.run_for(T);
    const double exact = ff.start.y - 0.5 * g * T * T;
    const double expected = 0.5 * g * T * s->dt() / n;
    EXPECT_NEAR(exact - s.position(ff.ball).y, expected, 0.01 * expected) << n;
  }
}

TEST(RigidBodySubsteps, RestingContactReportsTheWindowsImpulse) {
  // Contacts found once per window are kept over its substeps; the published
  // impulse is the window's, the weight times the world's step.
  WorldDef def = with_substeps(4);
  def.settings["collisions"].set("impulses", true);  // read below: computed for readers only
  Sim s(def);
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(1.0);
  const auto imp = rigid_of(*s).impulses();
  ASSERT_EQ(imp.size(), 1u);
  EXPECT_NEAR(imp[0].normal_impulse, 0.5 * g * s->dt(), 1e-2 * 0.5 * g * s->dt());
  // The carried depth keeps the ball resting, not pushed out once per substep.
  EXPECT_NEAR(std::get<Vec3>(s->get(b.ball, "velocity")).y, 0, 1e-3);
  EXPECT_NEAR(s.position(b.ball).y, b.radius, 1e-3);
}

TEST(RigidBodySubsteps, StackStandsWithSubsteps) {
  Sim s(with_substeps(4));
  const Stack st = build_stack(*s, 10);
  const Vec3 top0 = s.position(st.boxes.back());
  s.run_for(5.0);
  EXPECT_LT(length(s.position(st.boxes.back()) - top0), 0.01);
}

TEST(RigidBodySubsteps, BadValuesAreRefused) {
  for (std::int64_t n : {0, -2, 5000}) {
    Sim s(with_substeps(int(n)));
    add_sphere(*s, {}, 0.1, 1.0);
    EXPECT_THROW(s->start(), InputError) << n;
  }
}

WorldDef sleepy() {
  WorldDef def;
  def.settings["rigid_body"].set("auto_disable", true);
  return def;
}

TEST(RigidBodySleep, SettledPileSleepsAndStaysPut) {
  Sim s(sleepy());
  build_pile(*s, pile_layout(64, 3));
  s->start();
  RigidBodyResolver& rb = rigid_of(*s);
  EXPECT_EQ(rb.awake_count(), 64u);
  s.run_for(6.0);
  EXPECT_EQ(rb.awake_count(), 0u);
  // Asleep, nothing moves any more, and nothing is written.
  const auto pos = s->store().column(s->properties().find("position").value()).version();
  s.run_for(0.5);
  EXPECT_EQ(s->store().column(s->properties().find("position").value()).version(), pos);
}

TEST(RigidBodySleep, ASleepingPileRunsNoDerivedSet) {
  // No contact joints between sleepers: no impulses change, so the collisions
  // set (and what reads it) is skipped while the pile sleeps.
  Sim s(sleepy());
  build_pile(*s, pile_layout(64, 3));
  s.run_for(6.0);
  ASSERT_EQ(rigid_of(*s).awake_count(), 0u);
  auto collision_runs = [&] {
    for (const StageTiming& t : s->profile().stages)
      if (t.name == "collisions") return t.runs;
    return std::uint64_t(0);
  };
  const std::uint64_t before = collision_runs();
  s.run_for(1.0);
  EXPECT_EQ(collision_runs(), before);
  // A ball dropped on it: the pile's top wakes, and the ball comes to rest on it.
  const ObjectId ball = add_sphere(*s, {0, 3, 0}, 0.1, 1.0, "ball");
  s.run_for(0.6);
  EXPECT_GT(collision_runs(), before);
  EXPECT_GT(rigid_of(*s).awake_count(), 0u);
  s.run_for(3.0);
  EXPECT_GT(s.position(ball).y, 0.2) << "it lands on the pile, not through it";
}

TEST(RigidBodySleep, AnEditWakesABody) {
  Sim s(sleepy());
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(3.0);
  ASSERT_EQ(rigid_of(*s).awake_count(), 0u);
  s->set(b.ball, "velocity", Vec3{1, 0, 0});
  s->step();
  EXPECT_EQ(rigid_of(*s).awake_count(), 1u);
  EXPECT_GT(s.position(b.ball).x, 0.0);
}

TEST(RigidBodySleep, ANewLoadWakesABodyButItsOwnWeightDoesNot) {
  Sim s(sleepy());
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(3.0);
  RigidBodyResolver& rb = rigid_of(*s);
  ASSERT_EQ(rb.awake_count(), 0u);
  s.run_for(1.0);  // gravity is queued every step: the same load, it sleeps on
  EXPECT_EQ(rb.awake_count(), 0u);
  rb.add_force(b.ball, {20, 0, 0});
  s->step();
  EXPECT_EQ(rb.awake_count(), 1u);
  EXPECT_GT(std::get<Vec3>(s->get(b.ball, "velocity")).x, 0.0);
}

TEST(RigidBodySleep, AFallingBodyWakesTheOneItHits) {
  Sim s(sleepy());
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(3.0);
  ASSERT_EQ(rigid_of(*s).awake_count(), 0u);
  const ObjectId rock = add_sphere(*s, s.position(b.ball) + Vec3{0.05, 0.5, 0}, 0.1, 5.0, "rock");
  s.run_for(0.4);
  EXPECT_GT(length(s.position(b.ball) - Vec3{0, b.radius, 0}), 1e-3);  // pushed aside
  (void)rock;
}

}  // namespace
}  // namespace alloy::scenes
