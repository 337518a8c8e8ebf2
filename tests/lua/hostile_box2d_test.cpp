// A hostile mod's loads on the Box2D engine (the adversary's F15): the same
// screen as ODE's (resolvers/rigid_body/load_screen.hpp) refuses a load that
// would fling a body, naming the mod and its stage, before Box2D integrates
// it; loads the plane cannot give (a torque about x, a force along z) are
// dropped with one event per stage and kind, naming the mod.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

std::string hostile(const std::string& code) {
  return "mod.property { name = \"evil_mark\" }\n"
         "mod.interaction { name = \"evil.push\", reads = { \"evil_mark\", \"mass\" }, "
         "needs = { \"evil_mark\" }, target = \"rigid_body\",\n"
         "  apply = function(w)\n"
         "    local ball, t = w:find(\"ball\"), w.target\n" +
         code +
         "\n"
         "  end }\n";
}

struct Outcome {
  std::vector<std::string> frozen, dropped;
  bool ball_frozen = false;
  double witness_vy = 0;
  std::uint64_t steps = 0;
};

Outcome run_on_box2d(const std::string& code) {
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("evil", hostile(code));
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  runtime.load("evil");
  WorldDef def;
  def.dt = 1.0 / 240;
  def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  World world(registry, def);
  runtime.attach(world);
  const ObjectId thing = world.create("thing");
  world.set(thing, "evil_mark", 0.0);
  auto ball = [&](const char* name, double x) {
    const ObjectId b = world.create(name);
    world.set(b, "shape", std::string("sphere"));
    world.set(b, "radius", 0.1);
    world.set(b, "mass", 4.0);
    world.set(b, "position", Vec3{x, 10, 0});
    return b;
  };
  const ObjectId victim = ball("ball", 0), witness = ball("witness", 5);
  Outcome r;
  world.add_observer([&](const Event& e) {
    if (e.type == "out_of_bounds") r.frozen.push_back(frozen_message(world, e));
    if (e.type == "load_dropped") r.dropped.push_back(e.text);
  });
  world.run(30);
  r.steps = world.step_count();
  r.ball_frozen = world.frozen(victim);
  r.witness_vy = std::get<Vec3>(world.get(witness, "velocity")).y;
  EXPECT_FALSE(world.frozen(witness));
  return r;
}

TEST(HostileBox2D, AHugeForceIsRefusedNamingTheModAndStage) {
  const Outcome r = run_on_box2d("t.add_force(ball, vec3(1e9, 0, 0))");
  EXPECT_EQ(r.steps, 30u);
  ASSERT_EQ(r.frozen.size(), 1u);
  EXPECT_TRUE(contains(r.frozen[0],
                       "frozen: ball: mod 'evil' (stage 'evil.push') queued add_force {1e+09, 0, "
                       "0} N on it: its loads would change its speed by 1.04167e+06 m/s (the "
                       "limit is 100000 m/s) in one step of 0.00416667 s; they were refused"))
      << r.frozen[0];
  EXPECT_TRUE(r.ball_frozen);
  EXPECT_NEAR(r.witness_vy, -9.81 * 30 / 240, 1e-4);  // the world went on
}

TEST(HostileBox2D, ABulkWriteOfAHugeTorqueIsRefusedToo) {
  const Outcome r = run_on_box2d(
      "local m = w:read('mass') local q = t.add_torque_each(m) "
      "for i in m:each() do if i == ball then q[i] = vec3(0, 0, 1e200) end end");
  ASSERT_EQ(r.frozen.size(), 1u);
  EXPECT_TRUE(contains(r.frozen[0],
                       "mod 'evil' (stage 'evil.push') queued add_torque {0, 0, "
                       "1e+200} N m on it: its loads would change its angular speed"))
      << r.frozen[0];
}

TEST(HostileBox2D, LoadsOffThePlaneAreDroppedWithOneEventPerKindNamingTheMod) {
  const Outcome r = run_on_box2d(
      "t.add_torque(ball, vec3(100, 0, 0)) t.add_force(ball, vec3(0, 0, 1000)) "
      "t.add_force_at(ball, vec3(0, 1, 0), vec3(0, 10, 5))");
  EXPECT_TRUE(r.frozen.empty());
  ASSERT_EQ(r.dropped.size(), 3u);  // 30 steps, three kinds: once each
  EXPECT_TRUE(contains(r.dropped[0],
                       "mod 'evil' (stage 'evil.push') queued add_torque {100, 0, "
                       "0} N m on 'ball': its torque about x and y was dropped"))
      << r.dropped[0];
  EXPECT_TRUE(contains(r.dropped[1],
                       "mod 'evil' (stage 'evil.push') queued add_force {0, 0, "
                       "1000} N on 'ball': its force along z was dropped"))
      << r.dropped[1];
  EXPECT_TRUE(contains(r.dropped[2], "add_force_at {0, 1, 0} N at {0, 10, 5} m on 'ball'"))
      << r.dropped[2];
}

}  // namespace
}  // namespace alloy::test
