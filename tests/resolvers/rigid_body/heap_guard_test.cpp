// ODE's guard against a heap of parts placed through each other (docs/security.md:
// a scene or a mod spawning thousands of parts at one spot must not hang the
// host): a part sunk deep into more than 32 moving parts waits outside
// collisions, held still by the rigid body, and comes back when sunk into at
// most 4; the same rule as rigid_body.box2d's (ContactLimitBox2D in
// tests/resolvers/rigid_body_box2d/guards_test.cpp). Bounded by counts, not by
// times.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

WorldDef at_240() {
  WorldDef def;
  def.dt = 1.0 / 240;
  return def;
}

/// n balls of 5 cm within 1 mm of one spot (the adversary's heap1000):
/// n^2 / 2 pairs overlap, each nearly all the way.
std::vector<ObjectId> heap(World& w, int n, double x = 0) {
  std::vector<ObjectId> parts;
  for (int i = 0; i < n; ++i) {
    const double a = 2.399963 * i, r = 1e-3 * std::sqrt((i + 0.5) / n);  // a sunflower
    parts.push_back(add_sphere(w, {x + r * std::cos(a), 0.3 + r * std::sin(a), 0}, 0.05, 0.1,
                               "g" + std::to_string(i)));
  }
  return parts;
}

const rigid::CollisionSet& collisions(Sim& s) {
  return dynamic_cast<const rigid::CollisionSet&>(*s->stage("collisions"));
}

constexpr std::size_t kInCollisions = rigid::limits::contact_pairs_per_part + 1;  // 33

TEST(ContactLimitOde, AHeapOfAThousandWaitsOutsideCollisionsAndEachStepIsBounded) {
  // Without the guard: 31,472 touching pairs a step (the pair limit keeps 32
  // a part), 4.6 to 7.3 s a step. With it, all but 33 wait from the start.
  constexpr int n = 1000;
  Sim s(at_240());
  add_floor(*s);
  const std::vector<ObjectId> parts = heap(*s, n);
  std::vector<Event> crowded, limits;
  s->add_observer([&](const Event& ev) {
    if (ev.type == "crowded") crowded.push_back(ev);
    if (ev.type == "contact_limit") limits.push_back(ev);
  });
  s->start();
  const rigid::CollisionSet& set = collisions(s);
  EXPECT_EQ(set.waiting().size(), n - kInCollisions);
  std::size_t most = set.touching().size();
  const std::uint64_t tests_at_start = set.crowd_tests();
  for (int i = 0; i < 3; ++i) {
    s->step();
    most = std::max(most, set.touching().size());
  }
  const std::uint64_t tests = set.crowd_tests() - tests_at_start;
  std::printf(
      "ode heap of %d, 3 steps: %zu waiting, at most %zu touching pairs, %llu shape tests at the "
      "start, %llu in 3 steps\n",
      n, set.waiting().size(), most, (unsigned long long)tests_at_start, (unsigned long long)tests);
  // The 33 at the spot touch each other and the floor: 33 * 32 / 2 + 33.
  EXPECT_LE(most, kInCollisions * (kInCollisions - 1) / 2 + kInCollisions);
  // Each waiting part tests the ones at its spot (33) a step, at most.
  EXPECT_LE(tests, 3u * n * (kInCollisions + 1));
  EXPECT_GT(set.waiting().size(), n - 4 * kInCollisions);  // their spot is still full
  // Reported once, when it began, naming a part of the heap; no pair is
  // left out (the waiting parts are not in collisions).
  ASSERT_EQ(crowded.size(), 1u);
  EXPECT_TRUE(limits.empty());
  EXPECT_NE(std::find(parts.begin(), parts.end(), crowded[0].a), parts.end());
  EXPECT_EQ(crowded[0].value("went"), double(n - kInCollisions));
  EXPECT_EQ(crowded[0].value("limit"), 32.0);
  EXPECT_TRUE(contains(crowded[0].text, "'" + s->describe(crowded[0].a) + "' among them"))
      << crowded[0].text;
}

TEST(ContactLimitOde, AWaitingPartIsHeldStillAndEveryOneComesBack) {
  // 150 balls through each other: 117 wait at the start, held where they are
  // (no fall under gravity, no velocity), and come back as the 33 left push
  // each other apart; none is lost or frozen.
  Sim s(at_240());
  add_floor(*s);
  const std::vector<ObjectId> parts = heap(*s, 150);
  s->start();
  const rigid::CollisionSet& set = collisions(s);
  ASSERT_EQ(set.waiting().size(), 117u);
  const ObjectId first = set.waiting().front();
  const Vec3 at = s.position(first);
  s->step();
  ASSERT_EQ(set.waiting().front(), first);  // still buried after one step
  EXPECT_EQ(s.position(first).y, at.y);
  EXPECT_EQ(s.velocity(first).y, 0.0);
  std::size_t steps = 1;
  while (!set.waiting().empty() && steps < 480) s->step(), ++steps;
  std::printf("ode heap of 150: every waiting part back after %zu steps\n", steps);
  EXPECT_TRUE(set.waiting().empty());
  for (ObjectId p : parts) {
    EXPECT_FALSE(s->frozen(p));
    EXPECT_TRUE(std::isfinite(s.position(p).y));
  }
  // Back in the simulation the heap spreads a few balls at a time. The 33
  // left at the spot still push apart from deep inside each other, so some
  // go through the floor; without the guard the whole heap explodes (75 of
  // the 150 below the floor and 31 above 0.5 m after 2 s; with it 12 and 0).
  s.run_for(2.0);
  int below = 0, above = 0;
  for (ObjectId p : parts) below += s.position(p).y<0, above += s.position(p).y> 0.5;
  std::printf("ode heap of 150, 2 s later: %d balls below the floor, %d above 0.5 m\n", below,
              above);
  EXPECT_LE(below, 15);
  EXPECT_EQ(above, 0);
}

TEST(ContactLimitOde, NoPartOfANormalSceneWaits) {
  // A bed of 900 balls touching, a 20-box stack, and a plank lying on 50
  // beads (it touches more than 32 moving parts): nothing is sunk deep. The
  // beads and the plank lie in one cell of the collisions' grid (60 crates
  // of 1 m make it 2 m wide), so the guard checks them (its shape tests).
  Sim s(at_240());
  add_floor(*s);
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      add_sphere(*s, {0.1 * i, 0.05 + 0.0999 * j, 0}, 0.05, 0.1, "d" + std::to_string(30 * i + j));
  for (int i = 0; i < 20; ++i)
    add_box(*s, {-1, 0.05 + 0.1 * i, 0}, {0.1, 0.1, 0.1}, 1, {}, "box" + std::to_string(i));
  for (int i = 0; i < 1000; ++i)
    add_box(*s, {10 + 1.01 * (i % 50), 0.5 + 1.01 * (i / 50), 0}, {1, 1, 1}, 1, {},
            "crate" + std::to_string(i));
  for (int i = 0; i < 50; ++i)
    add_sphere(*s, {-5.5 + 0.01 * i, 0.005, 0}, 0.005, 0.001, "bead" + std::to_string(i));
  add_box(*s, {-5.255, 0.015, 0}, {0.5, 0.01, 0.05}, 0.1, {}, "plank");
  int reported = 0;
  s->add_observer([&](const Event& ev) { reported += ev.type == "crowded"; });
  s->run(3);
  const rigid::CollisionSet& set = collisions(s);
  std::printf("ode normal scene: %zu waiting, %llu shape tests in 3 steps\n", set.waiting().size(),
              (unsigned long long)set.crowd_tests());
  EXPECT_GT(set.crowd_tests(), 0u);  // the plank and the beads were checked
  EXPECT_TRUE(set.waiting().empty());
  EXPECT_EQ(reported, 0);
}

TEST(ContactLimitOde, AShallowCrowdLeavesPairsOutAndNothingWaits) {
  // 216 balls of 5 cm on a lattice 2.75 cm apart: each touches up to 194
  // others but is sunk deep (centres closer than one radius) into at most
  // 26, so none waits; the pair limit leaves pairs out instead, and says so
  // once, naming a ball.
  Sim s(at_240());
  add_floor(*s, -1);
  std::vector<ObjectId> parts;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k)
        parts.push_back(add_sphere(*s, {0.0275 * i, 0.3 + 0.0275 * j, 0.0275 * k}, 0.05, 0.1,
                                   "l" + std::to_string(36 * i + 6 * j + k)));
  std::vector<Event> limits;
  int crowded = 0;
  s->add_observer([&](const Event& ev) {
    if (ev.type == "contact_limit") limits.push_back(ev);
    crowded += ev.type == "crowded";
  });
  s->start();
  const rigid::CollisionSet& set = collisions(s);
  std::printf("ode lattice of 216: %zu touching pairs, %zu waiting, %llu shape tests\n",
              set.touching().size(), set.waiting().size(), (unsigned long long)set.crowd_tests());
  EXPECT_TRUE(set.waiting().empty());
  EXPECT_EQ(crowded, 0);
  EXPECT_GT(set.crowd_tests(), 0u);  // the parts with pairs left out were checked
  EXPECT_LE(set.touching().size(), rigid::limits::contact_pairs_per_part * parts.size());
  ASSERT_EQ(limits.size(), 1u);
  EXPECT_NE(std::find(parts.begin(), parts.end(), limits[0].a), parts.end());
  EXPECT_EQ(limits[0].value("per_part"), 32.0);
}

TEST(ContactLimitOde, ARestoreFindsTheBuriedPartsAgainAndReportsNothingNew) {
  // As on Box2D, which waits is not saved: the restored set's first update
  // finds the parts still buried and they wait again, without a second
  // `crowded` event; the run then goes on with every part back in the end.
  Sim s(at_240());
  add_floor(*s);
  heap(*s, 120);
  int events = 0;
  s->add_observer([&](const Event& ev) { events += ev.type == "crowded"; });
  s->run(2);
  const rigid::CollisionSet& set = collisions(s);
  const std::size_t waiting = set.waiting().size();
  ASSERT_GT(waiting, 0u);
  const Snapshot snap = s->snapshot();
  s->run(2);
  s->restore(snap);
  const rigid::CollisionSet& restored = collisions(s);
  std::printf("ode heap of 120: %zu waiting at the snapshot, %zu after the restore\n", waiting,
              restored.waiting().size());
  EXPECT_GT(restored.waiting().size(), 0u);
  EXPECT_LE(restored.waiting().size(), waiting);
  EXPECT_EQ(events, 1);
  std::size_t steps = 0;
  while (!restored.waiting().empty() && steps < 480) s->step(), ++steps;
  EXPECT_TRUE(restored.waiting().empty());
  EXPECT_EQ(events, 1);
}

}  // namespace
}  // namespace alloy::scenes
