#include "resolvers/gravity/uniform_gravity.hpp"

#include <gtest/gtest.h>

#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

Vec3 gravity(Sim& s, ObjectId o) { return std::get<Vec3>(s->get(o, "gravity")); }

TEST(UniformGravity, WritesGForEveryBodyWithMassAndNothingElse) {
  WorldDef def;
  def.settings["gravity.uniform"].set("g", Vec3{0, -1.62, 0});  // the Moon
  Sim s(def);
  const ObjectId floor = add_floor(*s);
  s->set(floor, "mass", 1000.0);  // static: immovable, feels nothing here
  const ObjectId ball = add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
  const ObjectId cube = s->create();
  s->set(cube, "shape", std::string("box"));
  s->set(cube, "size", Vec3{0.1, 0.1, 0.1});
  s->set(cube, "density", 100.0);
  s->set(cube, "position", Vec3{1, 1, 0});
  const ObjectId label = s->create("label");
  s->set(label, "position", Vec3{});
  s->step();
  EXPECT_EQ(gravity(s, ball), (Vec3{0, -1.62, 0}));
  EXPECT_EQ(gravity(s, cube), (Vec3{0, -1.62, 0}));
  EXPECT_THROW(s->get(floor, "gravity"), AccessError);
  EXPECT_THROW(s->get(label, "gravity"), AccessError);
  EXPECT_NEAR(s.velocity(ball).y, -1.62 * s->dt(), 1e-12);
}

TEST(UniformGravity, CostsNothingWhileNothingChanges) {
  Sim s;
  const ObjectId ball = add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
  s->step();
  const auto& column = s->store().column(s->properties().id("gravity"));
  const std::uint64_t v = column.version();
  s->run(50);
  EXPECT_EQ(column.version(), v);
  // Made static: it feels no more gravity (and the rigid body lets it go).
  s->set(ball, "static", true);
  s->step();
  EXPECT_EQ(gravity(s, ball), Vec3{});
}

TEST(UniformGravity, ABodyThatLeavesItsAreaKeepsNoStaleGravity) {
  // Gravity only inside a 2 m box; no provider of gravity anywhere else.
  WorldDef def;
  def.plugins = {"rigid_body", "rigid_body_from_gravity"};
  AreaDef field{.name = "field", .center = {0, 0, 0}, .half_extents = {1, 1, 1}, .plugins = {"gravity.uniform"}};
  field.settings["gravity.uniform"].set("g", Vec3{0, -5, 0});
  def.areas.push_back(field);
  Sim s(def);
  const ObjectId ball = add_sphere(*s, {0.5, 0, 0}, 0.05, 1.0, "ball");
  s->set(ball, "velocity", Vec3{4, 0, 0});
  s->step();
  EXPECT_EQ(s->area_of(ball), "field");
  EXPECT_EQ(gravity(s, ball), (Vec3{0, -5, 0}));
  while (s->area_of(ball) == "field") s->step();
  EXPECT_GT(s.position(ball).x, 1);
  EXPECT_THROW(s->get(ball, "gravity"), AccessError);  // erased on the way out
  s->step();  // the last force queued inside acts in this step
  const double vy = s.velocity(ball).y;
  EXPECT_LT(vy, 0);
  s->run(20);
  EXPECT_EQ(s.velocity(ball).y, vy);  // nothing pulls it any more
}

TEST(UniformGravity, AbsentWithoutMassAndSettingsChecked) {
  {
    Sim s;
    add_floor(*s);
    s->step();
    EXPECT_FALSE(s->has_stage("gravity.uniform"));
  }
  WorldDef def;
  def.settings["gravity.uniform"].set("gee", Vec3{0, -9.81, 0});
  Sim s(def);
  add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
  EXPECT_THROW(s->start(), InputError);
}

}  // namespace
}  // namespace alloy::scenes
