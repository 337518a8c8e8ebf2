// Frozen objects on the real rigid body (resolvers/rigid_body): a box flung
// out of the world. A finite velocity of 1.7e308 m/s used to overflow its
// position to infinity, and the rigid body's write of it was refused by
// ColumnWriter::set (non_finite). Such an edit is now refused by the property
// registry (limits:: in resolvers/rigid_body/properties.hpp), and a box that
// leaves the world's extent at the speed limit is refused by the rigid body
// before any number overflows: it names the rigid body, the box and where it
// went, and freezes the box; the rigid body rebuilds without it, and the
// other bodies keep falling and landing with finite values.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy {
namespace {

TEST(FrozenRigidBody, AnOverflowingBodyIsFrozenAndTheOthersGoOn) {
  scenes::Sim sim(
      WorldDef{.plugins = {"rigid_body", "gravity.uniform", "rigid_body_from_gravity"}});
  World& w = *sim;
  const ObjectId wild = scenes::add_box(w, {0, 1, 0}, {0.2, 0.2, 0.2}, 1, {}, "wild");
  std::vector<ObjectId> calm;
  for (int i = 0; i < 3; ++i)
    calm.push_back(
        scenes::add_box(w, {1.0 + i, 0.5, 0}, {0.2, 0.2, 0.2}, 1, {}, "calm" + std::to_string(i)));
  w.run(10);
  // Finite, but position += velocity * dt would overflow after about 240 steps.
  EXPECT_THROW(w.set(wild, "velocity", Vec3{1.7e308, 0, 0}), InputError);
  // At the speed limit, 1 km from the world's edge: out in three steps.
  w.set(wild, "position", Vec3{999e3, 1, 0});
  w.set(wild, "velocity", Vec3{1e5, 0, 0});

  std::vector<Event> bad;
  w.add_observer([&](const Event& e) {
    ASSERT_NE(e.type, "non_finite") << frozen_message(w, e);  // nothing overflowed
    if (e.type == "out_of_bounds") bad.push_back(e);
  });
  for (int i = 0; i < 480; ++i) w.step();

  ASSERT_FALSE(bad.empty());
  EXPECT_EQ(bad.front().source, "rigid_body");
  EXPECT_EQ(bad.front().a, wild);
  EXPECT_NE(bad.front().text.find("beyond the world's extent"), std::string::npos)
      << bad.front().text;
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
