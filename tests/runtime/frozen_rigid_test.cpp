// Frozen objects on the real rigid body (resolvers/rigid_body): a box given a
// huge velocity makes ODE produce non-finite numbers; the rigid body's write
// of them goes through ColumnWriter::set, so the world refuses it, names the
// rigid body, the box and the property, and freezes the box; the rigid body
// rebuilds without it, so its NaN cannot reach the other bodies, which keep
// falling and landing with finite values.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy {
namespace {

TEST(FrozenRigidBody, AnOverflowingBodyIsFrozenAndTheOthersGoOn) {
  // No collisions stage: ODE's collision space asserts (and aborts) on a box
  // beyond 2^53 m, and a huge angular velocity makes it abort when it
  // normalises a NaN quaternion. Both happen inside ODE, before any write; the
  // overflow of a position is what reaches the harness.
  scenes::Sim sim(
      WorldDef{.plugins = {"rigid_body", "gravity.uniform", "rigid_body_from_gravity"}});
  World& w = *sim;
  const ObjectId wild = scenes::add_box(w, {0, 1, 0}, {0.2, 0.2, 0.2}, 1, {}, "wild");
  std::vector<ObjectId> calm;
  for (int i = 0; i < 3; ++i)
    calm.push_back(
        scenes::add_box(w, {1.0 + i, 0.5, 0}, {0.2, 0.2, 0.2}, 1, {}, "calm" + std::to_string(i)));
  w.run(10);
  // Finite, but position += velocity * dt overflows to infinity after about 240 steps.
  w.set(wild, "velocity", Vec3{1.7e308, 0, 0});

  std::vector<Event> bad;
  w.add_observer([&](const Event& e) {
    if (e.type == "non_finite") bad.push_back(e);
  });
  for (int i = 0; i < 480; ++i) w.step();

  ASSERT_FALSE(bad.empty());
  EXPECT_EQ(bad.front().source, "rigid_body");
  EXPECT_EQ(bad.front().a, wild);
  EXPECT_FALSE(bad.front().text.empty());
  for (const Event& e : bad) EXPECT_EQ(e.a, wild) << frozen_message(w, e);  // nobody else caught it
  EXPECT_TRUE(w.frozen(wild));
  EXPECT_EQ(w.frozen_objects(), (std::vector<ObjectId>{wild}));
  for (const char* p : {"position", "orientation", "velocity", "angular_velocity"}) {
    const PropertyValue v = w.get(wild, p);
    if (const Vec3* x = std::get_if<Vec3>(&v)) {
      EXPECT_TRUE(is_finite(*x)) << p;
    } else {
      EXPECT_TRUE(is_finite(std::get<Quat>(v))) << p;
    }
  }
  // The others fall freely all along, finite: y = 0.5 - g t^2 / 2 (semi-implicit
  // Euler adds g dt t / 2).
  const double t = w.time(), g = 9.81;
  for (ObjectId c : calm) {
    EXPECT_TRUE(is_finite(sim.position(c)));
    EXPECT_NEAR(sim.position(c).y, 0.5 - 0.5 * g * t * t, g * w.dt() * t) << w.describe(c);
  }
  EXPECT_EQ(dynamic_cast<const rigid::RigidBodyResolver&>(*w.stage("rigid_body")).body_count(),
            calm.size());
}

}  // namespace
}  // namespace alloy
