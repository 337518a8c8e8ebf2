// The collisions derived set and rigid_body_from_collisions.
#include "resolvers/rigid_body/collisions.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "resolvers/rigid_body/rigid_body.hpp"
#include "resolvers/rigid_body/rigid_body_from_collisions.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::CollisionSet;
using rigid::ContactPair;

const CollisionSet& contacts_of(World& w) { return dynamic_cast<CollisionSet&>(*w.stage("collisions")); }

/// A scene that asks for impulses whether or not a stage reads them.
WorldDef with_impulses() {
  WorldDef def;
  def.settings["collisions"].set("impulses", true);
  return def;
}

TEST(Collisions, BeganOngoingEndedAcrossABounce) {
  Sim s(with_impulses());
  const Bounce b = build_bounce(*s, 0.5, 0.5);
  std::vector<Event> events;
  s->add_observer([&](const Event& e) { events.push_back(e); });
  int began_at = -1, ended_at = -1, ongoing_steps = 0;
  ContactPair began{}, ended{};
  for (int i = 0; i < 240 && ended_at < 0; ++i) {
    s->step();
    const CollisionSet& c = contacts_of(*s);
    EXPECT_EQ(c.step(), s->step_count() - 1);
    if (!c.began().empty()) {
      ASSERT_EQ(began_at, -1) << "a second began before the end";
      began_at = i, began = c.began()[0];
      ASSERT_EQ(c.points(began).size(), 1u);  // sphere on box: one point
      EXPECT_LT(c.points(began)[0].normal.y, -0.99);  // from b (ball) to a (floor): down
    }
    if (began_at >= 0 && !c.ongoing().empty()) ++ongoing_steps;
    if (!c.ended().empty()) ended_at = i, ended = c.ended()[0];
  }
  ASSERT_GE(began_at, 0);
  ASSERT_GT(ended_at, began_at);
  // Pairs are ordered by object id: the floor was made first.
  EXPECT_EQ(began.a, b.floor);
  EXPECT_EQ(began.b, b.ball);
  EXPECT_EQ(ended.a, b.floor);
  // The impact speed is the fall's, sqrt(2 g h).
  EXPECT_NEAR(began.normal_speed, std::sqrt(2 * 9.81 * 0.5), 0.03 * std::sqrt(2 * 9.81 * 0.5));
  EXPECT_LE(ongoing_steps, 3);
  // The impulse over the contact: m (1 + e) v.
  const double expected = 0.5 * 1.5 * std::sqrt(2 * 9.81 * 0.5);
  EXPECT_NEAR(ended.total_impulse, expected, 0.05 * expected);
  // Events, published after the step that found them.
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].type, "contact_began");
  EXPECT_EQ(events[0].source, "collisions");
  EXPECT_EQ(events[0].a, b.floor);
  EXPECT_NEAR(events[0].value("speed"), began.normal_speed, 1e-12);
  EXPECT_EQ(events[1].type, "contact_ended");
  EXPECT_NEAR(events[1].value("impulse"), ended.total_impulse, 1e-12);
  EXPECT_NEAR(events[1].value("duration"), (ended_at - began_at) * s->dt(), 1e-9);
}

TEST(Collisions, RestingContactStaysOngoing) {
  Sim s(with_impulses());
  const Stack st = build_stack(*s, 3, 0.2);
  s.run_for(0.1);
  std::size_t events = 0;
  s->add_observer([&](const Event&) { ++events; });
  s.run_for(2.0);
  EXPECT_EQ(events, 0u);  // no flicker: nothing begins or ends
  const CollisionSet& c = contacts_of(*s);
  EXPECT_EQ(c.ongoing().size(), 3u);  // floor-box0, box0-box1, box1-box2
  EXPECT_TRUE(c.find(st.boxes[1], st.boxes[0]) != nullptr);
  EXPECT_TRUE(c.find(st.boxes[0], st.boxes[2]) == nullptr);
  // Each pair carries the weight above it.
  const ContactPair* top = c.find(st.boxes[1], st.boxes[2]);
  ASSERT_NE(top, nullptr);
  EXPECT_NEAR(top->normal_impulse, 9.81 * s->dt(), 0.02 * 9.81 * s->dt());
  for (std::size_t i = 1; i < c.ongoing().size(); ++i)
    EXPECT_TRUE(rigid::pair_less(c.ongoing()[i - 1].a, c.ongoing()[i - 1].b, c.ongoing()[i].a, c.ongoing()[i].b));
}

// touching() is began and ongoing together, in (a, b) order: the rigid body's
// feed reads it, and ongoing() is made from it when asked. Checked step by
// step on a falling pile, where pairs begin and end in every step (and the
// pairs are sorted by a counting sort over the slots).
TEST(Collisions, TouchingIsBeganAndOngoingMergedInPairOrder) {
  Sim s;
  build_pile(*s, pile_layout(64));
  std::size_t began_total = 0, ongoing_total = 0;
  for (int i = 0; i < 240; ++i) {
    s->step();
    const CollisionSet& c = contacts_of(*s);
    const auto touching = c.touching(), began = c.began(), ongoing = c.ongoing();
    ASSERT_EQ(touching.size(), began.size() + ongoing.size()) << "step " << i;
    std::size_t b = 0, o = 0;
    for (std::size_t k = 0; k < touching.size(); ++k) {
      const ContactPair& p = touching[k];
      if (k > 0) {
        ASSERT_TRUE(rigid::pair_less(touching[k - 1].a, touching[k - 1].b, p.a, p.b)) << "step " << i;
      }
      ASSERT_LT(p.a, p.b);
      ASSERT_GT(p.count, 0u);
      ASSERT_LE(p.first + p.count, c.points().size());
      // Each pair is in exactly one of the two lists, at its place in order.
      const bool in_began = b < began.size() && began[b].a == p.a && began[b].b == p.b;
      const bool in_ongoing = o < ongoing.size() && ongoing[o].a == p.a && ongoing[o].b == p.b;
      ASSERT_NE(in_began, in_ongoing) << "step " << i;
      const ContactPair& q = in_began ? began[b++] : ongoing[o++];
      EXPECT_EQ(q.first, p.first);
      EXPECT_EQ(q.began_step, p.began_step);
      EXPECT_EQ(in_began, p.began_step == c.step());
      EXPECT_EQ(c.find(p.b, p.a), &p);
    }
    EXPECT_EQ(c.ongoing().data(), ongoing.data());  // made once per update
    began_total += began.size(), ongoing_total += ongoing.size();
  }
  EXPECT_GT(began_total, 30u);  // 64 boxes landing: 64 when written
  EXPECT_GT(ongoing_total, 1000u);
}

/// A ball dropped on a floor until the contact ends; records the
/// contact_ended event and the set's state then. With `demand_at` >= 0, an
/// impulse demand is taken after that many steps past the touch (0: before
/// the first step).
struct DropRun {
  Event ended;
  bool known_at_end = false;
  std::vector<double> poses;  // every step's ball height, bit for bit
};
DropRun drop(bool demand, int demand_after_touch = -1, bool slide_off = false) {
  Sim s;
  if (slide_off) {
    // A ball resting at the floor's edge, rolling off it at 1 m/s: a contact
    // of many steps (a bounce's lasts one: the collision is resolved in the
    // step that finds it, and the ball moved to where it would be).
    const Bounce b = build_bounce(*s, 0, 0);
    s->set(b.ball, "position", Vec3{9.9, b.radius + 1e-3, 0});
    s->set(b.ball, "velocity", Vec3{1, 0, 0});
  } else {
    build_bounce(*s, 0.5, 0.5);
  }
  DropRun r;
  s->add_observer([&](const Event& e) {
    if (e.type == "contact_ended") r.ended = e;
  });
  s->step();
  rigid::ImpulseDemand d;
  if (demand && demand_after_touch < 0) d = contacts_of(*s).demand_impulses();
  int touched = -1;
  for (int i = 0; i < 480 && r.ended.type.empty(); ++i) {
    s->step();
    r.poses.push_back(std::get<Vec3>(s->get(s->find("ball"), "position")).y);
    if (touched < 0 && !contacts_of(*s).began().empty()) touched = i;
    if (demand && touched >= 0 && i == touched + demand_after_touch) d = contacts_of(*s).demand_impulses();
  }
  r.known_at_end = contacts_of(*s).impulses_known();
  return r;
}

bool has_value(const Event& e, std::string_view key) {
  return std::any_of(e.values.begin(), e.values.end(), [&](const auto& kv) { return kv.first == key; });
}

TEST(Collisions, ImpulsesAreComputedOnlyWhileAStageReadsThem) {
  // Nobody reads them: the rigid body computes none, and contact_ended says
  // so by carrying no impulse (rather than a wrong 0).
  const DropRun without = drop(false);
  ASSERT_EQ(without.ended.type, "contact_ended");
  EXPECT_FALSE(without.known_at_end);
  EXPECT_FALSE(has_value(without.ended, "impulse"));
  EXPECT_TRUE(has_value(without.ended, "duration"));

  // A reader from the start: the impulse over the contact, m (1 + e) v.
  const DropRun with = drop(true);
  ASSERT_EQ(with.ended.type, "contact_ended");
  EXPECT_TRUE(with.known_at_end);
  ASSERT_TRUE(has_value(with.ended, "impulse"));
  const double expected = 0.5 * 1.5 * std::sqrt(2 * 9.81 * 0.5);
  EXPECT_NEAR(with.ended.value("impulse"), expected, 0.05 * expected);
  EXPECT_EQ(with.ended.value("duration"), without.ended.value("duration"));

  // Impulses are read out of the solve, never fed back: the same motion, bit for bit.
  EXPECT_EQ(with.poses, without.poses);
}

TEST(Collisions, APairThatBeganBeforeTheDemandEndsWithoutAnImpulse) {
  // The demand comes one step into the contact: the pair's total misses the
  // first advance, so its end reports no impulse; the set's impulses are known.
  const DropRun late = drop(true, 1, true);
  ASSERT_EQ(late.ended.type, "contact_ended");
  EXPECT_TRUE(late.known_at_end);
  EXPECT_FALSE(has_value(late.ended, "impulse"));
  // Taken in the step that found the touch, before the rigid body resolved
  // it: every advance of the pair computed its impulse.
  const DropRun in_time = drop(true, 0, true);
  ASSERT_EQ(in_time.ended.type, "contact_ended");
  EXPECT_TRUE(has_value(in_time.ended, "impulse"));
}

TEST(Collisions, ImpulsesStopWhenTheLastDemandIsDropped) {
  Sim s;
  build_bounce(*s, 0.0, 0.0);  // a ball resting on the floor
  s->step();
  const auto& rigid = dynamic_cast<const rigid::RigidBodyResolver&>(*s->stage("rigid_body"));
  {
    rigid::ImpulseDemand a = contacts_of(*s).demand_impulses();
    rigid::ImpulseDemand b = rigid.demand_impulses();
    s.run_for(0.1);
    EXPECT_TRUE(contacts_of(*s).impulses_known());
    ASSERT_EQ(rigid.impulses().size(), 1u);
    EXPECT_NEAR(rigid.impulses()[0].normal_impulse, 0.5 * 9.81 * s->dt(), 1e-3 * 0.5 * 9.81 * s->dt());
    a = {};  // one of two dropped: still demanded
    s->step();
    EXPECT_TRUE(contacts_of(*s).impulses_known());
  }
  s->step();
  EXPECT_FALSE(rigid.impulses_computed());
  EXPECT_TRUE(rigid.impulses().empty());
  EXPECT_FALSE(contacts_of(*s).impulses_known());
  const ContactPair* p = contacts_of(*s).find(s->find("floor"), s->find("ball"));
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->normal_impulse, 0.0);
}

TEST(Collisions, ABarLyingOnATurningCamStaysInContact) {
  // A bar hinged at one end lies by its weight on a square cam that turns
  // under it (a sliding contact, as on the motor's spokes). Where a corner of
  // the cam carries the bar, the corner moves on a circle that curves away
  // from the bar: a velocity-level contact lets them drift apart by
  // 1/2 R w^2 dt^2 a step, and unless a pressed contact may close to the
  // surface layer again the pair ended and began every few steps (a circuit
  // through it flickered with it).
  Sim s;
  const double w = 2;
  const ObjectId cam = add_box(*s, {0, 0, 0}, {0.2, 0.2, 0.2}, 200.0, {}, "cam");
  s->set(cam, "angular_velocity", Vec3{0, 0, w});
  s->set(cam, "planar", true);
  add_hinge(*s, cam, {}, {0, 0, 0});
  const ObjectId bar = add_box(*s, {0, 0.16, 0}, {0.5, 0.02, 0.02}, 0.2, {}, "bar");
  s->set(bar, "friction", 0.1);
  s->set(bar, "planar", true);
  add_hinge(*s, bar, {}, {-0.24, 0.16, 0});
  s.run_for(0.25);
  ASSERT_NE(contacts_of(*s).find(cam, bar), nullptr) << "the bar lies on the cam";
  int ended = 0;
  s->add_observer([&](const Event& e) { ended += e.type == "contact_ended"; });
  s.run_for(3.0);  // about a turn: the bar rides over every corner
  EXPECT_EQ(ended, 0) << "the bar left the cam";
  EXPECT_NE(contacts_of(*s).find(cam, bar), nullptr);
  const double turned = std::get<Vec3>(s->get(cam, "angular_velocity")).z;
  EXPECT_GT(turned, 0.5 * w) << "the cam still turns under the bar";
}

TEST(Collisions, StaticPairsAndJoinedPairsAreNotReported) {
  Sim s;
  add_floor(*s);
  const ObjectId wall = s->create("wall");  // overlaps the floor
  s->set(wall, "shape", std::string("box"));
  s->set(wall, "size", Vec3{0.2, 2, 2});
  s->set(wall, "position", Vec3{1, 0.5, 0});
  s->set(wall, "static", true);
  // Two overlapping parts joined by a hinge, held in the air.
  const ObjectId a = add_box(*s, {0, 2, 0}, {0.4, 0.1, 0.1}, 1.0, {}, "a");
  const ObjectId b = add_box(*s, {0.3, 2, 0}, {0.4, 0.1, 0.1}, 1.0, {}, "b");
  s->set(a, "pinned", true);
  add_hinge(*s, a, b, {0.15, 2, 0});
  s->step();
  const CollisionSet& c = contacts_of(*s);
  EXPECT_TRUE(c.began().empty());
  EXPECT_EQ(c.find(a, b), nullptr);
}

TEST(Collisions, PinnedPartsTouchingAreReported) {
  // Two pinned contacts of a switch touch: no forces, but the pair exists (electricity needs it).
  Sim s;
  const ObjectId a = add_box(*s, {0, 1, 0}, {0.2, 0.2, 0.2}, 1.0);
  const ObjectId b = add_box(*s, {0.19, 1, 0}, {0.2, 0.2, 0.2}, 1.0);
  s->set(a, "pinned", true);
  s->set(b, "pinned", true);
  s->step();
  EXPECT_NE(contacts_of(*s).find(a, b), nullptr);
  EXPECT_EQ(s.position(b).x, 0.19);
}

TEST(Collisions, FrictionIsMixedAsTheGeometricMean) {
  EXPECT_DOUBLE_EQ(rigid::RigidBodyFromCollisions::mix_friction(0.4, 0.9), 0.6);
  EXPECT_DOUBLE_EQ(rigid::RigidBodyFromCollisions::mix_friction(0.0, 0.9), 0.0);
  EXPECT_DOUBLE_EQ(rigid::RigidBodyFromCollisions::mix_restitution(0.2, 0.7), 0.7);
  // A box sliding on the floor stops after v^2 / (2 mu g).
  Sim s;
  const ObjectId floor = add_floor(*s);
  s->set(floor, "friction", 0.9);
  const ObjectId box = add_box(*s, {0, 0.1, 0}, {0.2, 0.2, 0.2}, 1.0);
  s->set(box, "friction", 0.4);
  s->set(box, "velocity", Vec3{2, 0, 0});
  s.run_for(1.5);
  const double mu = 0.6, stop = 4 / (2 * mu * 9.81);
  EXPECT_NEAR(s.position(box).x, stop, 0.03 * stop);
  EXPECT_NEAR(s.velocity(box).x, 0, 1e-4);
}

TEST(Collisions, CapsuleLiesAlongItsX) {
  Sim s;
  add_floor(*s);
  auto post = [&](Vec3 at) {  // thin static posts beside the capsule's ends
    const ObjectId p = s->create();
    s->set(p, "shape", std::string("box"));
    s->set(p, "size", Vec3{0.02, 0.1, 0.02});
    s->set(p, "position", at);
    s->set(p, "static", true);
    return p;
  };
  const ObjectId along_x = post({0.33, 0.05, 0}), along_z = post({0, 0.05, 0.33});
  const ObjectId cap = s->create("bar");
  s->set(cap, "shape", std::string("capsule"));
  s->set(cap, "radius", 0.05);
  s->set(cap, "length", 0.6);  // tips at x = +-0.35
  s->set(cap, "mass", 1.0);
  s->set(cap, "position", Vec3{0, 0.049, 0});
  s->start();
  const CollisionSet& c = contacts_of(*s);
  EXPECT_NE(c.find(cap, along_x), nullptr);
  EXPECT_EQ(c.find(cap, along_z), nullptr);
  s.run_for(0.5);
  EXPECT_NEAR(s.position(cap).y, 0.05, 1e-3);  // lies on the floor
}

}  // namespace
}  // namespace alloy::scenes
