// The magic mod (mods/magic): a resolver written entirely in Lua that works
// both ways with native physics. Contacts found by the native collisions set
// decide where mana flows; mana decides the forces queued on the native rigid
// body. The bundled scene shows it among ordinary kit parts.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

struct Flight {
  double max_y = -1e9, min_y = 1e9;
  int lit = 0, dark = 0;
};

class Magic : public ::testing::Test {
 protected:
  void SetUp() override { register_native_plugins(registry); }
  lua::LoadedScene load(const std::string& path, std::vector<std::string>* log = nullptr) {
    lua::LoadOptions o;
    o.mod_log = [log](const std::string& m, const std::string& l) {
      if (log) log->push_back("[" + m + "] " + l);
    };
    return lua::load_scene(path, registry, o);
  }
  PluginRegistry registry;
};

TEST_F(Magic, LiftRunesChargeFloatAndFallBackAmongNativeParts) {
  std::vector<std::string> log;
  lua::LoadedScene scene = load(source_path("mods/magic").string(), &log);
  ASSERT_TRUE(scene.mods);
  World& world = *scene.world;
  world.start();
  const auto stages = world.active_stages();
  for (const char* s :
       {"rigid_body", "collisions", "rigid_body_from_collisions", "gravity.uniform", "magic.mana",
        "magic.charge", "magic_from_collisions", "rigid_body_from_magic"})
    EXPECT_NE(std::find(stages.begin(), stages.end(), s), stages.end()) << s;

  std::map<std::string, Flight> f;
  const double pendulum0 = angle_z(get<Quat>(world, "pendulum", "orientation"));
  double channel_mana = 0;
  for (int step = 0; step < 8 * 240; ++step) {
    world.step();
    for (const char* n : {"feather", "kite", "bearer", "plank", "ball"}) {
      const double y = get<Vec3>(world, n, "position").y;
      f[n].max_y = std::max(f[n].max_y, y);
      f[n].min_y = std::min(f[n].min_y, y);
    }
    channel_mana = std::max(channel_mana, get<double>(world, "channel", "mana"));
    for (const Event& e : world.events()) {
      if (e.type == "rune_lit") ++f[world.describe(e.a)].lit;
      if (e.type == "rune_dark") ++f[world.describe(e.a)].dark;
    }
  }
  // The feather rests on its source at y = 0.12: it fills, lights, floats
  // well clear, spends its mana, falls back, and does it again.
  EXPECT_GE(f["feather"].lit, 2);
  EXPECT_GE(f["feather"].dark, 2);
  EXPECT_GT(f["feather"].max_y, 0.3);
  EXPECT_NEAR(f["feather"].min_y, 0.12, 0.01);
  EXPECT_NEAR(get<Vec3>(world, "feather", "position").x, -1.5, 0.05);  // straight up and down
  // The kite gets its mana through the loose conduit stone: source -> conduit -> lift.
  EXPECT_GT(channel_mana, 0.5);
  EXPECT_GE(f["kite"].lit, 1);
  EXPECT_GT(f["kite"].max_y, 0.35);
  // The bearer carries the wooden plank up with it.
  EXPECT_GE(f["bearer"].lit, 1);
  EXPECT_GT(f["plank"].max_y, f["plank"].min_y + 0.15);
  // Plain physics in the same world is plain physics.
  EXPECT_GT(std::abs(angle_z(get<Quat>(world, "pendulum", "orientation")) - pendulum0), 0.1);
  EXPECT_LT(f["ball"].min_y, 0.1);
  EXPECT_TRUE(log.empty()) << log.front();
}

TEST_F(Magic, TheSameSceneTwiceIsBitIdentical) {
  auto run = [&] {
    PluginRegistry r;
    register_native_plugins(r);
    lua::LoadedScene scene = lua::load_scene(source_path("mods/magic"), r, {});
    scene.world->run(3 * 240);
    std::vector<double> out;
    for (const char* n : {"feather", "kite", "channel", "bearer", "plank", "ball", "pendulum"}) {
      const Vec3 p = get<Vec3>(*scene.world, n, "position");
      out.insert(out.end(), {p.x, p.y, p.z});
    }
    for (const char* n : {"feather", "kite", "channel", "bearer"})
      out.push_back(get<double>(*scene.world, n, "mana"));
    return out;
  };
  const auto a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
}

TEST_F(Magic, AnotherScenesRuneStonesUseTheModAsALibrary) {
  TempMods dir;
  dir.write("tower.lua", R"LUA(
local kit = require "kit"
local magic = require "magic"
world { dt = 1 / 240, settings = { ["magic.mana"] = { regen = 20, conductance = 40 },
                                   ["rigid_body_from_magic"] = { lift = 3 } } }
kit.floor { name = "floor", at = { 0, -0.05 }, size = { 2, 0.1 } }
magic.stone { name = "base", rune = "source", at = { 0, 0.04 }, fixed = true, mana = 1 }
magic.stone { name = "top", rune = "lift", at = { 0, 0.12 } }
)LUA");
  lua::LoadedScene scene = load((dir / "tower.lua").string());
  ASSERT_TRUE(scene.mods);
  EXPECT_EQ(scene.mods->loaded(), std::vector<std::string>{"magic"});
  World& world = *scene.world;
  // The scene's settings reach the Lua stages: with ten times the flow, the
  // stone lights within a fraction of a second, and with lift 3 it shoots up.
  double max_y = 0;
  int lit_step = -1;
  for (int i = 0; i < 240; ++i) {
    world.step();
    max_y = std::max(max_y, get<Vec3>(world, "top", "position").y);
    if (lit_step < 0 && find_event(world, "rune_lit")) lit_step = i;
  }
  EXPECT_GE(lit_step, 0);
  EXPECT_LT(lit_step, 60);
  EXPECT_GT(max_y, 0.5);
}

TEST_F(Magic, UnknownSettingsOfALuaStageAreRefusedWithTheScenesLine) {
  TempMods dir;
  dir.write("typo.lua", R"LUA(
local magic = require "magic"
world { dt = 1 / 240,
        settings = { ["magic.mana"] = { regne = 20 } } }
magic.stone { name = "base", rune = "source", at = { 0, 0.04 }, fixed = true }
)LUA");
  try {
    PluginRegistry r;
    register_native_plugins(r);
    lua::check(dir / "typo.lua", r, {});
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "typo.lua:3")) << e.what();
    EXPECT_TRUE(contains(e.what(), "no setting 'regne' (did you mean 'regen'?)")) << e.what();
  }
}

}  // namespace
}  // namespace alloy::test
