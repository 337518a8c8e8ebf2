// The collisions derived set and rigid_body_from_collisions.
#include "resolvers/rigid_body/collisions.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "resolvers/rigid_body/rigid_body_from_collisions.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::CollisionSet;
using rigid::ContactPair;

const CollisionSet& contacts_of(World& w) { return dynamic_cast<CollisionSet&>(*w.stage("collisions")); }

TEST(Collisions, BeganOngoingEndedAcrossABounce) {
  Sim s;
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
  Sim s;
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
