// The rigid body resolver: bodies from properties, edits between steps,
// assemblies, hinges, the planar kit, interaction functions, settings,
// activation, write permission and determinism.
#include "resolvers/rigid_body/rigid_body.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "resolvers/plugins.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::RigidBodyResolver;

WorldDef without_gravity() {
  WorldDef def;
  def.plugins = {"rigid_body", "collisions", "rigid_body_from_collisions"};
  return def;
}

RigidBodyResolver& rigid_of(World& w) {
  return dynamic_cast<RigidBodyResolver&>(*w.stage("rigid_body"));
}

TEST(RigidBody, MovesWithItsVelocity) {
  Sim s(without_gravity());
  const ObjectId b = add_box(*s, {0, 5, 0}, {0.2, 0.2, 0.2}, 1.0);
  s->set(b, "velocity", Vec3{1, 0, 0});
  s->set(b, "angular_velocity", Vec3{0, 2, 0});
  s.run_for(1.0);
  EXPECT_NEAR(s.position(b).x, 1.0, 1e-12);
  EXPECT_NEAR(s.position(b).y, 5.0, 1e-12);
  EXPECT_NEAR(std::get<Vec3>(s->get(b, "angular_velocity")).y, 2.0, 1e-9);
  const Quat q = s.orientation(b);
  EXPECT_NEAR(2 * std::atan2(q.y, q.w), 2.0, 1e-9);  // 2 rad about y in 1 s (finite rotation)
}

TEST(RigidBody, DensityGivesMassAndFollowsTheShape) {
  Sim s(without_gravity());
  const ObjectId b = s->create("cube");
  s->set(b, "shape", std::string("box"));
  s->set(b, "size", Vec3{0.1, 0.1, 0.1});
  s->set(b, "density", 1000.0);
  s->set(b, "position", Vec3{});
  s->step();
  EXPECT_NEAR(std::get<double>(s->get(b, "mass")), 1.0, 1e-12);
  s->set(b, "size", Vec3{0.2, 0.1, 0.1});  // a defining edit: rebuilt, mass follows
  s->step();
  EXPECT_NEAR(std::get<double>(s->get(b, "mass")), 2.0, 1e-12);
}

TEST(RigidBody, BadBodiesAreRefusedWithTheObjectsName) {
  {
    Sim s;
    const ObjectId b = add_box(*s, {}, {0.1, 0.1, 0.1}, 1.0, {}, "weightless");
    try {
      s->set(b, "mass", 0.0);  // refused at the edit: the property's bound
      FAIL() << "mass 0 accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().object, "weightless");
      EXPECT_NE(std::string(e.what()).find("'mass' must be greater than 0, got 0"),
                std::string::npos)
          << e.what();
    }
    EXPECT_NO_THROW(s->check(b));  // the refused edit left the mass as it was
    s->remove(b, "size");
    try {
      s->check(b);  // the rigid body's whole-object check, run by World::check
      FAIL() << "a box without a size passed";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("object 'weightless': a box needs a 'size'"),
                std::string::npos)
          << e.what();
    }
  }
  {
    Sim s;
    const ObjectId b = add_sphere(*s, {}, 0.1, 1.0, "ghost");
    EXPECT_THROW(s->set(b, "mass", -1.0), InputError);  // refused at the edit
    s->remove(b, "shape");
    EXPECT_THROW(s->start(), InputError);
  }
}

TEST(RigidBody, EditingPositionTeleportsAndKeepsVelocity) {
  Sim s;
  const FreeFall ff = build_free_fall(*s, 10);
  s->run(24);
  const Vec3 v = s.velocity(ff.ball);
  s->set(ff.ball, "position", Vec3{3, 20, 0});
  s->step();
  const double dt = s->dt();
  EXPECT_NEAR(s.position(ff.ball).x, 3.0, 1e-12);
  EXPECT_NEAR(s.position(ff.ball).y, 20 + (v.y - 9.81 * dt) * dt, 1e-9);
  s->set(ff.ball, "velocity", Vec3{0, 5, 0});
  s->step();
  EXPECT_NEAR(s.velocity(ff.ball).y, 5 - 9.81 * dt, 1e-9);
  EXPECT_EQ(rigid_of(*s).rebuild_count(), 1u);  // edits of state do not rebuild
}

TEST(RigidBody, PinnedPartStaysAndFallsOnceUnpinned) {
  Sim s;
  const ObjectId b = add_box(*s, {0, 2, 0}, {0.2, 0.2, 0.2}, 1.0, {}, "pinned");
  s->set(b, "pinned", true);
  s.run_for(0.5);
  EXPECT_EQ(s.position(b).y, 2.0);
  s->set(b, "pinned", false);  // a value edit, not a structural one
  s.run_for(0.5);
  EXPECT_LT(s.position(b).y, 2.0 - 0.5 * 9.81 * 0.25 * 0.95);
  EXPECT_EQ(rigid_of(*s).rebuild_count(), 2u);
}

TEST(RigidBody, GluedPartsAreOneBody) {
  Sim s;
  const ObjectId a = add_box(*s, {0, 3, 0}, {0.4, 0.1, 0.1}, 1.0, {}, "a");
  const ObjectId b =
      add_box(*s, {0.25, 3.1, 0}, {0.1, 0.3, 0.1}, 3.0, Quat::from_angle_z(0.3), "b");
  add_glue(*s, a, b);
  s->set(a, "angular_velocity", Vec3{0, 0, 1.5});
  const Vec3 rel0 = rotate(
      Quat{s.orientation(a).w, -s.orientation(a).x, -s.orientation(a).y, -s.orientation(a).z},
      s.position(b) - s.position(a));
  s.run_for(1.0);
  EXPECT_EQ(rigid_of(*s).body_count(), 1u);
  const Quat qa = s.orientation(a);
  const Vec3 rel = rotate(Quat{qa.w, -qa.x, -qa.y, -qa.z}, s.position(b) - s.position(a));
  EXPECT_NEAR(length(rel - rel0), 0, 1e-9);  // rigidly together while spinning and falling
  // Only a spins (about its own centre), b is at rest: the assembly keeps
  // their momentum, zero, so its centre of mass only falls (session 18; until
  // then it moved as its first part, starting with w x (com - a)).
  const Vec3 com0{(0 * 1 + 0.25 * 3) / 4.0, (3 * 1 + 3.1 * 3) / 4.0, 0};
  const Vec3 v0{};
  const Vec3 com = (1.0 * s.position(a) + 3.0 * s.position(b)) / 4.0;
  EXPECT_NEAR(com.x, com0.x + v0.x, 1e-9);
  EXPECT_NEAR(com.y, com0.y + v0.y - 0.5 * 9.81 * 1.0 - 0.5 * 9.81 * s->dt(), 1e-9);
}

TEST(RigidBody, GlueToThePlayAreaHolds) {
  Sim s;
  const ObjectId a = add_box(*s, {0, 1, 0}, {0.2, 0.2, 0.2}, 1.0);
  add_glue(*s, a, {});
  s.run_for(0.5);
  EXPECT_EQ(s.position(a).y, 1.0);
}

TEST(RigidBody, HingeFrictionStopsASmallSwing) {
  Sim s;
  const BarPendulum p = build_bar_pendulum(*s, 1.0, 0.3);
  // Gravity's torque at 0.3 rad: m g (L/2) sin(0.3) = 1.45 N m.
  s->set(p.hinge, "joint_friction", 2.0);
  s.run_for(1.0);
  EXPECT_NEAR(angle_z(s.orientation(p.bar)) + std::numbers::pi / 2, 0.3, 1e-3);
  s->set(p.hinge, "joint_friction", 1.0);
  s.run_for(1.0);
  EXPECT_LT(angle_z(s.orientation(p.bar)) + std::numbers::pi / 2, 0.25);
}

TEST(RigidBody, HingeLimitsAreAnglesOfBodyARelativeToBodyB) {
  Sim s;
  // A horizontal bar hinged at its left end; it may fall to -0.5 rad only.
  const ObjectId bar = add_box(*s, {0.5, 0, 0}, {1, 0.04, 0.04}, 1.0, {}, "bar");
  s->set(bar, "planar", true);
  const ObjectId h = add_hinge(*s, bar, {}, {0, 0, 0});
  s->set(h, "limit_low", -0.5);
  s->set(h, "limit_high", 0.5);
  s.run_for(2.0);
  EXPECT_NEAR(angle_z(s.orientation(bar)), -0.5, 0.01);
  // The limit survives a rebuild (an edit of a defining column).
  s->set(h, "joint_friction", 0.01);
  s.run_for(1.0);
  EXPECT_NEAR(angle_z(s.orientation(bar)), -0.5, 0.01);
}

TEST(RigidBody, HingeAnchorIsKeptCurrent) {
  Sim s(without_gravity());
  const ObjectId a = add_box(*s, {0, 0, 0}, {0.2, 0.2, 0.2}, 1.0);
  const ObjectId b = add_box(*s, {0.5, 0, 0}, {0.2, 0.2, 0.2}, 1.0);
  const ObjectId h = add_hinge(*s, a, b, {0.25, 0, 0});
  s->set(a, "velocity", Vec3{0, 1, 0});
  s->set(b, "velocity", Vec3{0, 1, 0});
  s.run_for(1.0);
  EXPECT_NEAR(std::get<Vec3>(s->get(h, "anchor")).y, 1.0, 1e-6);
}

TEST(RigidBody, PlanarBodyStaysInThePlayArea) {
  Sim s(without_gravity());
  const ObjectId b = add_box(*s, {0, 0, 0}, {0.3, 0.1, 0.1}, 1.0);
  s->set(b, "planar", true);
  s->set(b, "velocity", Vec3{1, 0, 2});
  s->set(b, "angular_velocity", Vec3{0, 0, 2});
  s->start();
  rigid_of(*s).add_torque(b, {5, 5, 0});
  s.run_for(1.0);
  const Quat q = s.orientation(b);
  EXPECT_NEAR(s.position(b).z, 0, 1e-6);
  EXPECT_NEAR(q.x, 0, 1e-9);
  EXPECT_NEAR(q.y, 0, 1e-9);
  EXPECT_NEAR(s.position(b).x, 1.0, 1e-3);
  EXPECT_NEAR(std::get<Vec3>(s->get(b, "angular_velocity")).z, 2.0, 1e-9);
}

TEST(RigidBody, InteractionFunctionsAreQueuedForTheNextAdvance) {
  Sim s(without_gravity());
  const ObjectId b = add_sphere(*s, {0, 0, 0}, 0.5, 2.0, "ball");
  s->start();
  RigidBodyResolver& rb = rigid_of(*s);
  const double dt = s->dt();
  rb.add_force(b, {4, 0, 0});
  EXPECT_EQ(s.velocity(b).x, 0.0);  // nothing happens until the advance
  s->step();
  EXPECT_NEAR(s.velocity(b).x, 4 / 2.0 * dt, 1e-12);
  s->step();  // the queue was cleared
  EXPECT_NEAR(s.velocity(b).x, 4 / 2.0 * dt, 1e-12);
  // A force off the centre turns it: torque r x F about z.
  rb.add_force(b, {0, 1, 0}, s.position(b) + Vec3{0.5, 0, 0});
  s->step();
  const double inertia = 0.4 * 2.0 * 0.25;
  EXPECT_NEAR(std::get<Vec3>(s->get(b, "angular_velocity")).z, 0.5 / inertia * dt, 1e-9);
  rb.add_torque(b, {0, 0, -0.5});
  s->step();
  EXPECT_NEAR(std::get<Vec3>(s->get(b, "angular_velocity")).z, 0, 1e-9);
  // A stale id fails loudly.
  s->destroy(b);
  EXPECT_THROW(rb.add_force(b, {1, 0, 0}), AccessError);
}

TEST(RigidBody, SettingsAreValidated) {
  for (auto [key, value] : std::vector<std::pair<std::string, PropertyValue>>{
           {"iteratons", std::int64_t(10)}, {"solver", std::string("fast")}, {"erp", 2.0}}) {
    WorldDef def;
    def.settings["rigid_body"].set(key, value);
    Sim s(def);
    add_sphere(*s, {}, 0.1, 1.0);
    EXPECT_THROW(s->start(), InputError) << key;
  }
  WorldDef def;
  def.settings["rigid_body"].set("iteratons", std::int64_t(10));
  Sim s(def);
  add_sphere(*s, {}, 0.1, 1.0);
  try {
    s->start();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'iterations'"), std::string::npos)
        << e.what();
  }
}

TEST(RigidBody, DirectSolverGivesTheSameFreeFall) {
  WorldDef def;
  def.settings["rigid_body"].set("solver", std::string("step"));
  Sim s(def);
  const FreeFall ff = build_free_fall(*s, 10);
  s.run_for(2.0);
  EXPECT_NEAR(s.position(ff.ball).y, 10 - 9.81 * s->dt() * s->dt() * 480 * 481 / 2, 1e-9);
}

TEST(RigidBody, ImpulsesOfRestingContactCarryTheWeight) {
  WorldDef def;
  def.settings["collisions"].set("impulses", true);  // read below: computed for readers only
  Sim s(def);
  const Bounce b = build_bounce(*s, 0.0, 0.0);
  s.run_for(1.0);
  const auto imp = rigid_of(*s).impulses();
  ASSERT_EQ(imp.size(), 1u);
  EXPECT_EQ(imp[0].a, b.floor);
  EXPECT_EQ(imp[0].b, b.ball);
  EXPECT_NEAR(imp[0].normal_impulse, 0.5 * 9.81 * s->dt(), 1e-3 * 0.5 * 9.81 * s->dt());
  EXPECT_NEAR(imp[0].impulse.y, -0.5 * 9.81 * s->dt(), 1e-3);  // on the floor: downwards
  const std::uint64_t v = rigid_of(*s).state_version();
  s->step();
  EXPECT_NE(rigid_of(*s).state_version(), v);
}

TEST(RigidBody, PluginsAreNotInstantiatedWhenNothingNeedsThem) {
  Sim s;
  add_floor(*s);
  const ObjectId wall = s->create("wall");
  s->set(wall, "shape", std::string("box"));
  s->set(wall, "size", Vec3{0.2, 2, 2});
  s->set(wall, "position", Vec3{1, 1, 0});
  s->set(wall, "static", true);
  s->step();
  for (const char* name : {"rigid_body", "collisions", "rigid_body_from_collisions",
                           "gravity.uniform", "rigid_body_from_gravity"}) {
    EXPECT_FALSE(s->has_stage(name)) << name;
    const auto& ni = s->profile().not_instantiated;
    EXPECT_NE(std::find(ni.begin(), ni.end(), name), ni.end()) << name;
  }
  // A part with mass appears: everything it needs comes to life.
  const ObjectId ball = add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
  s->run(2);  // stages made mid-run are not primed: their first commands act one step later
  for (const char* name : {"rigid_body", "collisions", "rigid_body_from_collisions",
                           "gravity.uniform", "rigid_body_from_gravity"})
    EXPECT_TRUE(s->has_stage(name)) << name;
  EXPECT_LT(s.position(ball).y, 1.0);
}

// A resolver that declares velocity but writes position.
class Rogue final : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& access, double) override {
    access.writer<Vec3>("position").set(0, Vec3{1, 1, 1});
  }
};

TEST(RigidBody, WritingAnUndeclaredColumnThrows) {
  PluginRegistry registry;
  register_native_plugins(registry);
  registry.add({.info = {.name = "rogue",
                         .kind = StageKind::Resolver,
                         .writes = {"velocity"},
                         .needs = {"mass"}},
                .create = [](PluginContext&) -> std::unique_ptr<Stage> {
                  return std::make_unique<Rogue>();
                }});
  World w(registry);
  add_sphere(w, {}, 0.1, 1.0);
  EXPECT_THROW(w.step(), AccessError);
  // The rigid body may write only what it declared, too.
  const PluginDef* def = registry.find("rigid_body");
  ASSERT_NE(def, nullptr);
  EXPECT_EQ(def->info.writes,
            (std::vector<std::string>{"position", "orientation", "velocity", "angular_velocity",
                                      "mass", "anchor", "anchor_a", "anchor_b", "axis"}));
}

std::vector<Vec3> positions_after(int steps, int rebuild_every, bool tumble = true) {
  Sim s;
  if (tumble) {
    build_tumble(*s);
  } else {  // no chaos: a stack, a swinging bar, a sliding box
    build_stack(*s, 3, 0.2);
    add_hinge(*s, add_box(*s, {1.5, 1, 0}, {0.6, 0.05, 0.05}, 1.0), {}, {1.2, 1, 0});
    const ObjectId slider = add_box(*s, {-1.5, 0.1, 0}, {0.2, 0.2, 0.2}, 1.0);
    s->set(slider, "velocity", Vec3{1, 0, 0.5});
  }
  std::vector<ObjectId> ids;
  for (std::uint32_t i = 0; i < s->store().slot_count(); ++i)
    if (s->store().has(s->store().id_at(i), s->properties().id("position")))
      ids.push_back(s->store().id_at(i));
  for (int i = 0; i < steps; ++i) {
    if (rebuild_every && i % rebuild_every == rebuild_every - 1) {
      // An edit of a defining column of one part: the resolver rebuilds everything.
      s->set(ids.back(), "linear_damping", i % 2 ? 0.0 : 1e-300);
    }
    s->step();
  }
  std::vector<Vec3> out;
  for (ObjectId id : ids) out.push_back(s.position(id));
  return out;
}

TEST(RigidBody, SameSceneTwiceIsBitIdentical) {
  const auto a = positions_after(720, 0), b = positions_after(720, 0);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)), 0);
}

TEST(RigidBody, RebuildsLoseNothing) {
  // A full rebuild from properties continues the motion: the state that
  // matters is in the properties. Bodies without joints continue bit for bit.
  // A hinge is re-anchored where it is, which keeps its constraint error of
  // micrometres; the swinging bar's period then shifts by parts per million.
  const auto a = positions_after(720, 0, false), b = positions_after(720, 50, false);
  ASSERT_EQ(a.size(), 6u);  // floor, three stacked boxes, the hinged bar, the slider
  ASSERT_EQ(b.size(), 6u);
  for (std::size_t i : {0, 1, 2, 3, 5}) EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(Vec3)), 0) << i;
  const double bar = length(a[4] - b[4]);
  std::printf("rebuild every 50 steps: hinged bar differs by %.3g m after 3 s\n", bar);
  EXPECT_LT(bar, 1e-3);
}

}  // namespace
}  // namespace alloy::scenes
