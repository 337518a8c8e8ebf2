// Guards that both rigid-body engines share (the adversary's F14 and F15,
// docs/security.md): the bound on contact pairs a step (a heap of parts
// placed through each other must not cost seconds and gigabytes), and the
// screen of queued loads on Box2D (ODE's: load_screen.hpp), with the event
// for loads the plane drops.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "resolvers/rigid_body/engine.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
#include "runtime/contact_set.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

struct Engine {
  const char* name;
  const char* rigid_body;
  const char* collisions;
};
const Engine kEngines[] = {{"ode", "rigid_body", "collisions"},
                           {"box2d", "rigid_body.box2d", "collisions.box2d"}};

WorldDef on(const Engine& e) {
  WorldDef def;
  def.dt = 1.0 / 240;
  if (std::string(e.rigid_body) != "rigid_body")
    def.use = {{"rigid_body", e.rigid_body}, {"collisions", e.collisions}};
  return def;
}

class ContactLimit : public ::testing::TestWithParam<Engine> {};

/// n spheres of 5 cm within 1 mm of one spot (the adversary's heap1000,
/// smaller): n^2 / 2 pairs overlap.
std::vector<ObjectId> heap(World& w, int n) {
  std::vector<ObjectId> parts;
  for (int i = 0; i < n; ++i) {
    const double a = 2.399963 * i, r = 1e-3 * std::sqrt((i + 0.5) / n);  // a sunflower
    parts.push_back(add_sphere(w, {r * std::cos(a), 0.3 + r * std::sin(a), 0}, 0.05, 0.1,
                               "g" + std::to_string(i)));
  }
  return parts;
}

TEST_P(ContactLimit, AHeapOfPartsThroughEachOtherIsBoundedAndNamed) {
  // 200 parts: 19,900 overlapping pairs; a pair is kept while one of its
  // parts touches fewer than 32 moving parts. (On ODE since session 18 all
  // but 33 wait before any pair is left out, with a `crowded` event instead:
  // tests/resolvers/rigid_body/heap_guard_test.cpp; its limit there too.)
  const Engine& e = GetParam();
  Sim s(on(e));
  add_floor(*s);
  const std::vector<ObjectId> parts = heap(*s, 200);
  std::vector<Event> limits;
  s->add_observer([&](const Event& ev) {
    if (ev.type == "contact_limit") limits.push_back(ev);
  });
  s->start();
  const auto& set = dynamic_cast<const ContactSet&>(*s->stage(e.collisions));
  const std::size_t limit = rigid::limits::contact_pairs_per_part * 201;
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t most = 0;
  for (int i = 0; i < 3; ++i) {
    s->step();
    most = std::max(most, set.touching().size());
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s: heap of 200: %.3f s for 3 steps, at most %zu touching pairs (bound %zu)\n",
              e.name, seconds, most, limit);
  EXPECT_LE(most, limit);
  if (std::string(e.name) == "ode") {  // its heap waits: no pair is left out
    EXPECT_TRUE(limits.empty());
    return;
  }
  // Reported once, when it began, naming a part of the heap and the limit.
  ASSERT_EQ(limits.size(), 1u);
  // At the start (the set primes itself) or step 1; on Box2D, where all but
  // 33 of the heap wait outside the world (ContactLimitBox2D below), when
  // the first waiting parts come back, at step 2.
  EXPECT_LE(limits[0].step, std::string(e.name) == "box2d" ? 2u : 1u);
  EXPECT_NE(std::find(parts.begin(), parts.end(), limits[0].a), parts.end());
  EXPECT_EQ(limits[0].value("per_part"), 32.0);
  EXPECT_GT(limits[0].value("left_out"), 0.0);
  EXPECT_TRUE(contains(limits[0].text, "parts placed through each other in a heap?"))
      << limits[0].text;
  EXPECT_TRUE(contains(limits[0].text, "'" + s->describe(limits[0].a) + "' is in "))
      << limits[0].text;
}

TEST_P(ContactLimit, ThePartsOfAPackedBedStayFarBelowIt) {
  // 900 spheres touching in a 30 x 30 square on the floor: no pair is left out.
  const Engine& e = GetParam();
  Sim s(on(e));
  add_floor(*s);
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      add_sphere(*s, {0.1 * i, 0.05 + 0.0999 * j, 0}, 0.05, 0.1, "d" + std::to_string(30 * i + j));
  int reported = 0;
  s->add_observer([&](const Event& ev) { reported += ev.type == "contact_limit"; });
  s->run(3);
  EXPECT_EQ(reported, 0);
}

class Tunnelling : public ::testing::TestWithParam<Engine> {};

TEST_P(Tunnelling, AFastBallDoesNotPassThroughAThinWall) {
  // A 1 cm ball at 30 m/s moves 12.5 cm a step at 1/240 s, past a 2 cm wall
  // in one step: both engines sweep it (ODE's `ccd`; on Box2D the engine's
  // own sweep, since Box2D's time-of-impact sub-step, which moved a body
  // without its joints' partners, is off).
  const Engine& e = GetParam();
  Sim s(on(e));
  const ObjectId wall = add_box(*s, {1, 1, 0}, {0.02, 1, 0.1}, 1, {}, "wall");
  s->set(wall, "static", true);
  const ObjectId ball = add_sphere(*s, {0, 1, 0}, 0.01, 0.01, "ball");
  s->set(ball, "velocity", Vec3{30, 0, 0});
  s->set(ball, "restitution", 0.0);
  s.run_for(0.25);
  std::printf("%s: ball at 30 m/s against a 2 cm wall at x = 0.99: x = %.4f m after 0.25 s\n",
              e.name, s.position(ball).x);
  EXPECT_LT(s.position(ball).x, 0.99);
  if (auto* b = dynamic_cast<const box2d::Box2DEngine*>(s->stage(e.rigid_body))) {
    EXPECT_EQ(b->sweep_count(), 1u);  // moved back once, then the contact held it
  }
}

INSTANTIATE_TEST_SUITE_P(Engines, Tunnelling, ::testing::ValuesIn(kEngines),
                         [](const ::testing::TestParamInfo<Engine>& info) {
                           return std::string(info.param.name);
                         });

TEST(ContactLimitBox2D, AHeapOfThreeThousandWaitsOutsideTheWorldAndEachStepIsBounded) {
  // The adversary's heap at 3,000 parts (hostile: a mod spawning them at one
  // spot). Box2D's broad phase finds every overlapping pair and AddPair walks
  // a body's contacts for each before the contact filter is asked: 4.5 million
  // pairs a step, over 12 s. The engine takes every body sunk deep into more
  // than 32 moving ones out of Box2D's world until its spot clears: the
  // work is bounded by counts (the pairs Box2D puts to the filter, the shape
  // tests of the guard, Box2D's contacts), not by time.
  constexpr int n = 3000;
  Sim s(on(kEngines[1]));
  add_floor(*s);
  const std::vector<ObjectId> parts = heap(*s, n);
  std::vector<Event> crowded;
  s->add_observer([&](const Event& ev) {
    if (ev.type == "crowded") crowded.push_back(ev);
  });
  s->start();
  const auto& b = dynamic_cast<const box2d::Box2DEngine&>(*s->stage("rigid_body.box2d"));
  const std::size_t in_world = rigid::limits::contact_pairs_per_part + 1;  // 33
  EXPECT_EQ(b.waiting_count(), n - in_world);
  for (int i = 0; i < 2; ++i) s->step();
  std::printf(
      "box2d heap of %d, 2 steps: %zu waiting, %llu pairs put to the filter, %llu shape tests, "
      "%zu Box2D contacts (without the guard: %d pairs a step)\n",
      n, b.waiting_count(), (unsigned long long)b.pair_filter_calls(),
      (unsigned long long)b.crowd_tests(), b.box2d_contact_count(), n * (n - 1) / 2);
  // Measured 1,951 pairs, 253,290 shape tests (the waiting bodies' tests,
  // about 30 each a step), 1,300 contacts; without the guard the pairs alone
  // are 4.5 million a step.
  EXPECT_LT(b.pair_filter_calls(), 5000u);
  EXPECT_LT(b.crowd_tests(), 100u * n * 3);
  EXPECT_LT(b.box2d_contact_count(), 32u * in_world * 2);
  EXPECT_GT(b.waiting_count(), n - 4 * in_world);  // their spot is still full
  // Reported once, when it began, naming a part of the heap.
  ASSERT_EQ(crowded.size(), 1u);
  EXPECT_NE(std::find(parts.begin(), parts.end(), crowded[0].a), parts.end());
  EXPECT_EQ(crowded[0].value("went"), double(n - in_world));
  EXPECT_EQ(crowded[0].value("limit"), 32.0);
  EXPECT_TRUE(contains(crowded[0].text, "'" + s->describe(crowded[0].a) + "' among them"))
      << crowded[0].text;
}

TEST(ContactLimitBox2D, WaitingPartsComeBackWhenTheirSpotClears) {
  // 150 parts through each other: 117 wait at the start, and come back as
  // the 33 left in the world push each other apart, each when it is sunk
  // into at most 4 (32 steps); none is lost.
  Sim s(on(kEngines[1]));
  add_floor(*s);
  const std::vector<ObjectId> parts = heap(*s, 150);
  s->start();
  const auto& b = dynamic_cast<const box2d::Box2DEngine&>(*s->stage("rigid_body.box2d"));
  EXPECT_EQ(b.waiting_count(), 117u);
  std::size_t steps = 0;
  while (b.waiting_count() > 0 && steps < 240) s->step(), ++steps;
  std::printf("box2d heap of 150: every waiting part back after %zu steps\n", steps);
  EXPECT_EQ(b.waiting_count(), 0u);
  EXPECT_EQ(b.body_count(), 150u);
  for (ObjectId p : parts) EXPECT_FALSE(s->frozen(p));
}

TEST(ContactLimitBox2D, NoPartOfANormalSceneWaits) {
  // A bed of 900 disks touching, a 20-box stack, and a plank lying on 80
  // beads (it touches more than 32 moving parts, by Box2D's slop): nothing
  // is sunk deep into anything. (Counting every touch as deep, the plank
  // waited.)
  Sim s(on(kEngines[1]));
  add_floor(*s);
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      add_sphere(*s, {0.1 * i, 0.05 + 0.0999 * j, 0}, 0.05, 0.1, "d" + std::to_string(30 * i + j));
  for (int i = 0; i < 20; ++i)
    add_box(*s, {-1, 0.05 + 0.1 * i, 0}, {0.1, 0.1, 0.1}, 1, {}, "box" + std::to_string(i));
  for (int i = 0; i < 80; ++i)
    add_sphere(*s, {5 + 0.02 * i, 0.01, 0}, 0.01, 0.01, "bead" + std::to_string(i));
  add_box(*s, {5.79, 0.025, 0}, {1.62, 0.01, 0.1}, 1, {}, "plank");
  int reported = 0;
  s->add_observer([&](const Event& ev) { reported += ev.type == "crowded"; });
  s->start();
  const auto& b = dynamic_cast<const box2d::Box2DEngine&>(*s->stage("rigid_body.box2d"));
  s->run(3);
  EXPECT_EQ(b.waiting_count(), 0u);
  EXPECT_EQ(reported, 0);
}

INSTANTIATE_TEST_SUITE_P(Engines, ContactLimit, ::testing::ValuesIn(kEngines),
                         [](const ::testing::TestParamInfo<Engine>& info) {
                           return std::string(info.param.name);
                         });

// --- the load screen on Box2D ----------------------------------------------------------

struct Box2DWorld {
  Sim s{on(kEngines[1])};
  ObjectId ball, witness;
  std::vector<Event> events;
  Box2DWorld() {
    ball = add_sphere(*s, {0, 10, 0}, 0.05, 1.0, "ball");
    witness = add_sphere(*s, {5, 10, 0}, 0.05, 1.0, "witness");
    s->add_observer([&](const Event& e) {
      if (e.type != "contact_began" && e.type != "contact_ended") events.push_back(e);
    });
    s->start();
  }
  rigid::RigidBodyEngine& engine() {
    return dynamic_cast<rigid::RigidBodyEngine&>(*s->stage("rigid_body.box2d"));
  }
  std::vector<Event> of_type(const std::string& t) const {
    std::vector<Event> out;
    for (const Event& e : events)
      if (e.type == t) out.push_back(e);
    return out;
  }
};

TEST(Box2DLoadScreen, AHugeForceIsRefusedBeforeTheStepAsOnOde) {
  Box2DWorld w;
  w.engine().add_force(w.ball, {1e9, 0, 0});
  w.s->step();
  const auto refused = w.of_type("out_of_bounds");
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0].a, w.ball);
  EXPECT_TRUE(contains(refused[0].text,
                       "queued add_force {1e+09, 0, 0} N on it: its loads would change its speed "
                       "by 4.16667e+06 m/s (the limit is 100000 m/s)"))
      << refused[0].text;
  EXPECT_TRUE(w.s->frozen(w.ball));
  // It never moved; the witness fell as it would alone.
  EXPECT_NEAR(w.s.position(w.ball).x, 0.0, 1e-12);
  w.s->run(9);
  EXPECT_FALSE(w.s->frozen(w.witness));
  EXPECT_NEAR(w.s.velocity(w.witness).y, -9.81 * 10 / 240, 1e-4);
}

TEST(Box2DLoadScreen, AHugeTorqueAndAForceAtAPointBeyondTheWorldAreRefused) {
  Box2DWorld w;
  w.engine().add_torque(w.ball, {0, 0, 1e12});
  // No force at all, but at 1e300 m: single precision makes inf of the
  // point and NaN of the torque about it.
  w.engine().add_force(w.witness, {0, 0, 0}, {1e300, 0, 0});
  w.s->step();
  const auto refused = w.of_type("out_of_bounds");
  ASSERT_EQ(refused.size(), 2u);
  EXPECT_TRUE(contains(refused[0].text + refused[1].text,
                       "queued add_torque {0, 0, 1e+12} N m on it: its loads would change its "
                       "angular speed"));
  EXPECT_TRUE(contains(refused[0].text + refused[1].text,
                       "queued add_force_at {0, 0, 0} N at {1e+300, 0, 0} m"));
  EXPECT_TRUE(w.of_type("non_finite").empty());
}

TEST(Box2DLoadScreen, LoadsThePlaneDropsAreReportedOncePerStageAndKind) {
  Box2DWorld w;
  for (int i = 0; i < 10; ++i) {
    w.engine().add_torque(w.ball, {100, 0, 0});           // about x: dropped
    w.engine().add_force(w.ball, {0, 0, 1000});           // along z: dropped
    w.engine().add_force(w.ball, {0, 1, 0}, {0, 10, 5});  // a lever along z: dropped
    w.engine().add_torque(w.witness, {0, 0, 1e-3});       // about z: applied
    w.engine().add_force(w.witness, {1e-3, 0, 1e-15});    // round-off along z: not reported
    w.s->step();
  }
  const auto dropped = w.of_type("load_dropped");
  ASSERT_EQ(dropped.size(), 3u);
  std::string all;
  for (const Event& e : dropped) {
    all += e.text + "\n";
    EXPECT_EQ(e.a, w.ball);
    EXPECT_EQ(e.step, 1u);  // once, not once a step
  }
  EXPECT_TRUE(contains(all,
                       "a load from outside any stage queued add_torque {100, 0, 0} N m on "
                       "'ball': its torque about x and y was dropped (Box2D simulates the "
                       "z = 0 plane only"))
      << all;
  EXPECT_TRUE(contains(all, "add_force {0, 0, 1000} N on 'ball': its force along z")) << all;
  EXPECT_TRUE(contains(all,
                       "add_force_at {0, 1, 0} N at {0, 10, 5} m on 'ball': its force along z or "
                       "torque about x and y was dropped"))
      << all;
  EXPECT_TRUE(w.of_type("out_of_bounds").empty());
  EXPECT_GT(w.s->value<Vec3>(w.witness, "angular_velocity")->z, 0.0);
}

}  // namespace
}  // namespace alloy::scenes
