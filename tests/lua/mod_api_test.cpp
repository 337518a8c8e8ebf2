// The mod API (lua/mod_runtime.hpp, lua/lua_stages.hpp): a mod defines, from
// Lua, a property type, a component, a resolver with an interaction function,
// a derived set and interactions (one onto its own Lua resolver, one onto the
// native rigid body), and they act in a running world next to the native
// stages, under the same scheduling, skipping and area rules.
#include <gtest/gtest.h>

#include "lua/lua_stages.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

// "warmth": temperature as a physics of its own. Touching objects conduct
// heat (an interaction reading the native collisions set, queueing heat() on
// the Lua resolver); a glowing object (a derived set) rises like hot air (an
// interaction queueing add_force on the native rigid body).
const char* kWarmthRuntime = R"LUA(
mod.property { name = "temperature", unit = "K", min = 0, doc = "absolute temperature" }
mod.property { name = "heat_capacity", unit = "J/K", min = 0, min_exclusive = true }

mod.resolver {
  name = "warmth.heat",
  reads = { "heat_capacity" },
  writes = { "temperature" },
  needs = { "temperature" },
  functions = { heat = { "number" } },
  settings = { ambient = 300, cooling = 0.5 },
  advance = function(w, dt)
    local T, c = w:write("temperature"), w:read("heat_capacity")
    for i, q in w:commands("heat") do
      if c:has(i) then T[i] = T[i] + q / c[i] end
    end
    local s = w.settings
    for i in T:each() do
      if c:has(i) then
        local before = T[i]
        T[i] = before - s.cooling * (before - s.ambient) * dt
        if before >= 500 and T[i] < 500 then w:emit("warmth.cooled", { a = i, temperature = T[i] }) end
      end
    end
  end,
}

mod.derived {
  name = "warmth.glow",
  reads = { "temperature" },
  provides = { glow = "number" },
  update = function(w)
    local T, glow = w:read("temperature"), w:output("glow")
    for i in T:each() do
      if T[i] > 500 then glow[i] = (T[i] - 500) / 100 end
    end
  end,
}

mod.interaction {
  name = "warmth_from_collisions",
  reads = { "temperature" },
  derived = { "collisions" },
  target = "warmth.heat",
  settings = { conductance = 50 },
  apply = function(w)
    local T = w:read("temperature")
    local k = w.settings.conductance * w.dt
    for a, b in w:contacts("touching") do
      if T:has(a) and T:has(b) then
        local q = k * (T[a] - T[b])
        w.target.heat(a, -q)
        w.target.heat(b, q)
      end
    end
  end,
}

mod.interaction {
  name = "rigid_body_from_glow",
  reads = { "mass", "gravity" },
  derived = { "warmth.glow" },
  target = "rigid_body",
  apply = function(w)
    local glow, mass, g = w:derived("warmth.glow", "glow"), w:read("mass"), w:read("gravity")
    for i in glow:each() do
      if mass:has(i) then w.target.add_force(i, g[i] * (-2 * glow[i] * mass[i])) end
    end
  end,
}
)LUA";

// The component: a block of a given temperature, for scenes.
const char* kWarmthInit = R"LUA(
local kit = require "kit"
local block = kit.define("warm_block", {
  doc = "a 10 cm block at a temperature",
  args = { { "at", "vec", required = true }, { "temperature", "positive", default = 300 },
           { "capacity", "positive", default = 1000 }, { "fixed", "boolean", default = false } },
  build = function(a)
    local p = { shape = "box", size = { 0.1, 0.1, 0.1 }, position = a.at, temperature = a.temperature,
                friction = 0.5, restitution = 0 }
    if a.fixed then p.static = true else p.mass = 1; p.planar = true; p.heat_capacity = a.capacity end
    return p
  end,
})
return { block = block }
)LUA";

const char* kWarmthScene = R"LUA(
local kit = require "kit"
local warmth = require "warmth"
world { dt = 1 / 240, settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } } }
kit.floor { name = "floor", at = { 0, -0.05 }, size = { 4, 0.1 } }
warmth.block { name = "balloon", at = { -1, 1 }, temperature = 700 }
warmth.block { name = "stone", at = { 0, 1 } }
warmth.block { name = "plate", at = { 1, 0.05 }, temperature = 900, fixed = true }
warmth.block { name = "pot", at = { 1, 0.15 } }
)LUA";

class ModApi : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    mods.mod("warmth", kWarmthRuntime,
             "depends = { \"kit\" }, main = \"init.lua\", scene = \"scene.lua\"");
    mods.write("warmth/init.lua", kWarmthInit);
    mods.write("warmth/scene.lua", kWarmthScene);
  }
  lua::LoadedScene load(const std::string& path) {
    lua::LoadOptions o;
    o.mod_paths = {mods.path()};
    o.mod_log = [this](const std::string& m, const std::string& l) {
      log.push_back("[" + m + "] " + l);
    };
    return lua::load_scene(path, registry, o);
  }
  double y(const World& w, const std::string& name) { return get<Vec3>(w, name, "position").y; }

  PluginRegistry registry;
  TempMods mods;
  std::vector<std::string> log;
};

TEST_F(ModApi, EveryKindOfDefinitionFromLuaActsInAWorldNextToNativeStages) {
  lua::LoadedScene scene = load((mods / "warmth").string());
  ASSERT_TRUE(scene.mods);
  World& world = *scene.world;

  // The property types, registered by the mod.
  const auto t = registry.properties().find("temperature");
  ASSERT_TRUE(t);
  EXPECT_EQ(registry.properties().def(*t).unit, "K");
  EXPECT_EQ(registry.properties().def(*t).owner, "warmth");
  // The component made the objects with them.
  EXPECT_DOUBLE_EQ(get<double>(world, "balloon", "temperature"), 700);
  EXPECT_DOUBLE_EQ(get<double>(world, "pot", "heat_capacity"), 1000);

  world.start();
  const auto stages = world.active_stages();
  for (const char* s : {"rigid_body", "collisions", "gravity.uniform", "warmth.heat", "warmth.glow",
                        "warmth_from_collisions", "rigid_body_from_glow"})
    EXPECT_NE(std::find(stages.begin(), stages.end(), s), stages.end()) << s;

  const double balloon0 = y(world, "balloon"), stone0 = y(world, "stone");
  world.run(60);  // 0.25 s
  // Lua -> native: the hot block rises (the Lua derived set's glow, the Lua
  // interaction's force on the ODE body); the cold one falls as usual.
  EXPECT_GT(y(world, "balloon"), balloon0 + 0.1);
  EXPECT_LT(y(world, "stone"), stone0 - 0.2);

  bool cooled = false;
  for (int i = 0; i < 360 && !cooled; ++i) {
    world.step();
    if (const Event* e = find_event(world, "warmth.cooled")) {
      cooled = true;
      EXPECT_EQ(e->source, "warmth.heat");
      EXPECT_EQ(world.describe(e->a), "balloon");
      EXPECT_LT(e->value("temperature"), 500);
    }
  }
  EXPECT_TRUE(cooled) << "the Lua resolver's event";

  // Native -> Lua: the pot on the hot plate warms by conduction through the
  // contact the collisions set found; the stone on the cold floor does not.
  world.run(240);
  EXPECT_GT(get<double>(world, "pot", "temperature"), 320);
  EXPECT_LT(get<double>(world, "stone", "temperature"), 300.5);
  EXPECT_DOUBLE_EQ(get<double>(world, "plate", "temperature"),
                   900);  // no heat capacity: a reservoir
  EXPECT_TRUE(log.empty()) << log.front();
}

TEST_F(ModApi, LuaStagesAreSkippedAndLeftOutLikeNativeOnes) {
  mods.write("cold.lua", R"LUA(
local warmth = require "warmth"
world { dt = 1 / 240 }
warmth.block { name = "plate", at = { 0, 0 }, temperature = 900, fixed = true }
)LUA");
  lua::LoadedScene scene = load((mods / "cold.lua").string());
  World& world = *scene.world;
  world.run(100);
  const auto& stages = world.profile().stages;
  auto timing = [&](const std::string& n) {
    for (const auto& s : stages)
      if (s.name == n) return s;
    ADD_FAILURE() << "no stage " << n;
    return StageTiming{};
  };
  // The plate's temperature never changes (no heat capacity), so the Lua
  // derived set is computed once, at priming, and skipped every step after.
  EXPECT_EQ(timing("warmth.glow").runs, 1u);
  EXPECT_EQ(timing("warmth.glow").skipped, 100u);
  EXPECT_EQ(timing("warmth.heat").runs, 100u);
  // Nothing has mass: the rigid body and everything that needs it is absent.
  const auto& absent = world.profile().not_instantiated;
  for (const char* s : {"rigid_body", "rigid_body_from_glow"})
    EXPECT_NE(std::find(absent.begin(), absent.end(), s), absent.end()) << s;
}

TEST_F(ModApi, ALuaResolverInAnAreaActsOnlyOnTheObjectsInIt) {
  mods.write("areas.lua", R"LUA(
local warmth = require "warmth"
world { dt = 1 / 240, plugins = { "warmth.glow" },
        areas = { { name = "oven", center = { 1, 0 }, radius = 0.5, plugins = { "warmth.heat" },
                    settings = { ["warmth.heat"] = { ambient = 1000, cooling = 2 } } } } }
warmth.block { name = "inside", at = { 1, 0 }, fixed = true }
warmth.block { name = "outside", at = { -1, 0 }, fixed = true }
object { name = "loaf", position = { 1.2, 0 }, temperature = 300, heat_capacity = 1 }
object { name = "crumb", position = { -1.2, 0 }, temperature = 300, heat_capacity = 1 }
)LUA");
  lua::LoadedScene scene = load((mods / "areas.lua").string());
  World& world = *scene.world;
  world.run(240);
  EXPECT_TRUE(world.has_stage("warmth.heat@oven"));
  EXPECT_FALSE(world.has_stage("warmth.heat"));
  EXPECT_GT(get<double>(world, "loaf", "temperature"), 800);  // heated towards the oven's 1000 K
  EXPECT_DOUBLE_EQ(get<double>(world, "crumb", "temperature"), 300);  // out of the area: untouched
}

TEST_F(ModApi, DefinitionErrorsNameTheFileAndLine) {
  struct Case {
    const char* runtime;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {"\nmod.resolver { name = 'bad.one', reads = { 'mas' }, advance = function() end }", 2,
       "unknown property 'mas' (did you mean 'mass'?)"},
      {"mod.resolver { name = 'bad.two', advnce = function() end }", 1,
       "no field 'advnce' (did you mean 'advance'?)"},
      {"\n\nmod.derived { name = 'bad.three', update = function() end }", 3, "provides nothing"},
      {"mod.interaction { name = 'bad.four', target = 'electricity', apply = function() end }", 1,
       "not a resolver Lua can queue on"},
      {"mod.interaction { name = 'bad.five', apply = function() end }", 1,
       "needs the one resolver it queues on"},
      {"mod.resolver { name = 'bad.six', functions = { f = { 'string' } }, advance = function() "
       "end }",
       1, "must be \"number\", \"object\" or \"vec3\""},
      {"mod.resolver { name = 'rigid_body', advance = function() end }", 1,
       "taken by a native plugin"},
      {"local x = 1\nmod.property { name = 'mass', kind = 'vec3' }", 0,
       "cannot define it differently"},
      {"mod.property { name = 'x', kind = 'colour' }", 1, "unknown kind 'colour'"},
      {"local a = 1\nlocal b = = 2", 2, "unexpected symbol"},
      {"\nerror('refused at load')", 2, "refused at load"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.runtime);
    TempMods bad;
    bad.mod("bad", c.runtime);
    lua::ModRuntime runtime(registry, runtime_options(bad, &log));
    try {
      runtime.load("bad");
      ADD_FAILURE() << "loaded";
    } catch (const InputError& e) {
      EXPECT_TRUE(contains(e.where().file, "bad/runtime.lua")) << e.what();
      EXPECT_EQ(e.where().line, c.line) << e.what();
      EXPECT_TRUE(contains(e.what(), c.message)) << e.what();
    }
    // Nothing of a failed load stays registered.
    EXPECT_FALSE(runtime.has("bad"));
    for (const char* p : {"bad.one", "bad.two", "bad.three", "bad.four"})
      EXPECT_FALSE(registry.find(p));
  }
}

TEST_F(ModApi, StagesMayWriteOnlyWhatTheyDeclared) {
  TempMods rogue;
  rogue.mod("rogue", R"LUA(
mod.property { name = "heat" }
mod.resolver {
  name = "rogue.resolver", reads = { "mass" }, writes = { "heat" }, needs = { "heat" },
  advance = function(w)
    w:write("heat")
    local m = w:write("mass")
  end,
}
mod.derived {
  name = "rogue.derived", reads = { "heat" }, provides = { x = "number" },
  update = function(w) w:write("heat") end,
}
mod.interaction {
  name = "rogue.reader", target = "rigid_body",
  apply = function(w) w:read("velocity") end,
}
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(rogue, &log));
  runtime.load("rogue");
  World world(registry);
  runtime.attach(world);
  const ObjectId o = world.create("thing");
  world.set(o, "heat", 1.0);
  world.set(o, "mass", 1.0);
  world.set(o, "shape", std::string("sphere"));
  world.set(o, "radius", 0.1);
  world.step();
  world.step();
  std::vector<std::string> disabled;
  for (const auto& r : runtime.poll())
    if (r.kind == lua::ModReport::Kind::StageDisabled) disabled.push_back(r.message);
  ASSERT_EQ(disabled.size(), 3u);
  auto has = [&](const char* part) {
    return std::any_of(disabled.begin(), disabled.end(),
                       [&](const std::string& m) { return contains(m, part); });
  };
  EXPECT_TRUE(has("writes 'mass' without declaring it"));
  EXPECT_TRUE(has("only a resolver may write properties"));
  EXPECT_TRUE(has("reads 'velocity' without declaring it"));
  EXPECT_TRUE(has("rogue/runtime.lua:7:"));  // the line of the bad write
  // The world went on: the rigid body still integrates.
  EXPECT_TRUE(world.has_stage("rigid_body"));
  EXPECT_EQ(world.step_count(), 2u);
}

TEST_F(ModApi, ValuesWrittenFromLuaAreCheckedBeforeTheySpread) {
  TempMods m;
  m.mod("checks", R"LUA(
mod.property { name = "level", min = 0 }
local mode = 0
mod.resolver {
  name = "checks.writer", writes = { "level" }, needs = { "level" },
  advance = function(w)
    local l = w:write("level")
    for i in l:each() do
      local ok, err = pcall(function() l[i] = 0/0 end)
      w.state.nan = err
      ok, err = pcall(function() l[i] = -1 end)
      w.state.negative = err
      ok, err = pcall(function() l[i + 1000] = 1 end)
      w.state.slot = err
      ok, err = pcall(function() return l[-1] end)
      w.state.read = err
      if l[i] >= 2 then
        error(w.state.nan .. "|" .. w.state.negative .. "|" .. w.state.slot .. "|" .. w.state.read)
      end
      l[i] = l[i] + 1
    end
  end,
}
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(m, &log));
  runtime.load("checks");
  World world(registry);
  runtime.attach(world);
  const ObjectId o = world.create("gauge");
  world.set(o, "level", 1.0);
  world.step();
  world.step();
  EXPECT_DOUBLE_EQ(std::get<double>(world.get(o, "level")), 2.0);  // the good write went through
  std::string text;
  for (const auto& r : runtime.poll()) text += r.message;
  EXPECT_TRUE(contains(text, "'level' of gauge must be finite")) << text;
  EXPECT_TRUE(contains(text, "'level' of gauge must be at least 0")) << text;
  EXPECT_TRUE(contains(text, "no object in slot 1000")) << text;
  EXPECT_TRUE(contains(text, "column 'level': no object in slot -1")) << text;
}

/// A 1 kg ball of 0.1 m radius 0.5 m above a static floor, to land on it.
void drop_ball(World& world, double restitution = 0) {
  const ObjectId floor = world.create("floor");
  world.set(floor, "shape", std::string("box"));
  world.set(floor, "size", Vec3{4, 0.1, 1});
  world.set(floor, "static", true);
  world.set(floor, "position", Vec3{0, 0, 0});
  const ObjectId ball = world.create("ball");
  world.set(ball, "shape", std::string("sphere"));
  world.set(ball, "radius", 0.1);
  world.set(ball, "mass", 1.0);
  world.set(ball, "restitution", restitution);
  world.set(ball, "position", Vec3{0, 0.5, 0});
}

TEST_F(ModApi, LuaEventHandlersSeeThePublishedEventsWithTheModsState) {
  TempMods m;
  m.mod("listener", R"LUA(
mod.property { name = "count" }
mod.resolver {
  name = "listener.show", reads = {}, writes = { "count" }, needs = { "count" },
  advance = function(w)
    local c = w:write("count")
    for i in c:each() do c[i] = w.state.touches end
  end,
}
mod.on("contact_began", function(e, state)
  state.touches = state.touches + 1
  state.last = e.a_name .. "+" .. e.b_name
end)
function mod.on_load(state) state.touches = 0 end
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(m, &log));
  runtime.load("listener");
  EXPECT_EQ(runtime.handlers_of("listener"), 1u);
  World world(registry);
  runtime.attach(world);
  const ObjectId counter = world.create("counter");
  world.set(counter, "count", 0.0);
  drop_ball(world);
  world.run(240);
  EXPECT_GE(std::get<double>(world.get(counter, "count")), 1.0);  // the handler counted the landing
}

TEST_F(ModApi, AContactEndedHandlerGetsTheImpulseWithoutAskingForIt) {
  // Impulses are computed only for their readers; a mod that handles
  // contact_ended is one, without declaring anything.
  TempMods m;
  m.mod("bounces", R"LUA(
mod.property { name = "last_impulse" }
mod.resolver {
  name = "bounces.show", reads = {}, writes = { "last_impulse" }, needs = { "last_impulse" },
  advance = function(w)
    local c = w:write("last_impulse")
    for i in c:each() do c[i] = w.state.impulse end
  end,
}
mod.on("contact_ended", function(e, state) state.impulse = e.values.impulse or -1 end)
function mod.on_load(state) state.impulse = 0 end
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(m, &log));
  runtime.load("bounces");
  World world(registry);
  runtime.attach(world);
  const ObjectId shown = world.create("shown");
  world.set(shown, "last_impulse", 0.0);
  drop_ball(world, 0.8);
  world.run(150);  // falls 0.35 m, lands at 2.6 m/s and bounces off
  // The landing's impulse: m (v_in + v_out) = 1 kg * 2.6 m/s * 1.8, roughly.
  const double impulse = std::get<double>(world.get(shown, "last_impulse"));
  EXPECT_GT(impulse, 3.0) << "-1: the event came without an impulse";
  EXPECT_LT(impulse, 6.0);
}

}  // namespace
}  // namespace alloy::test

namespace alloy::test {
namespace {

TEST(ModCheck, CheckingAModFolderChecksItsRuntimeToo) {
  // `alloy check mods/x` runs the mod's main file and its runtime file, so a
  // bad stage definition is found before anything runs.
  TempMods mods;
  mods.mod("broken",
           "mod.property { name = \"level\" }\n\nmod.resolver { name = \"broken.r\", writes = { "
           "\"levle\" }, "
           "advance = function() end }\n",
           "main = \"init.lua\"");
  mods.write("broken/init.lua", "return {}\n");
  PluginRegistry registry;
  register_native_plugins(registry);
  try {
    lua::check(mods / "broken", registry, {});
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "broken/runtime.lua:3")) << e.what();
    EXPECT_TRUE(contains(e.what(), "unknown property 'levle' (did you mean 'level'?)")) << e.what();
  }
  EXPECT_FALSE(registry.find("broken.r"));
  lua::check(source_path("mods/magic"), registry, {});  // the bundled one is fine
}

}  // namespace
}  // namespace alloy::test

namespace alloy::test {
namespace {

TEST(ModSwap, ALuaResolverIsSwappedForAnotherWhileTheWorldRunsAndKeepsEveryProperty) {
  // Two implementations of the same physics, one per mod: the world swaps one
  // for the other between steps (World::swap), as it does native resolvers.
  TempMods mods;
  mods.mod("slow", R"LUA(
mod.property { name = "level" }
mod.resolver { name = "fill.slow", writes = { "level" }, needs = { "level" },
  advance = function(w) local l = w:write("level") for i in l:each() do l[i] = l[i] + 1 end end }
)LUA");
  mods.mod("fast", R"LUA(
mod.property { name = "level" }
mod.resolver { name = "fill.fast", writes = { "level" }, needs = { "level" },
  advance = function(w) local l = w:write("level") for i in l:each() do l[i] = l[i] + 10 end end }
)LUA");
  PluginRegistry registry;
  lua::ModRuntimeOptions o = runtime_options(mods, nullptr);
  o.grants = {{"fast", {"level"}, {}}};  // slow's property: the scene lets fast write it too
  lua::ModRuntime runtime(registry, o);
  runtime.load("slow");
  runtime.load("fast");
  World world(registry, WorldDef{.plugins = {"fill.slow"}});
  runtime.attach(world);
  const ObjectId tank = world.create("tank");
  world.set(tank, "level", 0.0);
  world.run(3);
  EXPECT_EQ(std::get<double>(world.get(tank, "level")), 3.0);
  world.swap("", "fill.slow", "fill.fast");
  EXPECT_EQ(std::get<double>(world.get(tank, "level")), 3.0);  // nothing lost in the swap
  world.run(2);
  EXPECT_EQ(std::get<double>(world.get(tank, "level")), 23.0);
  EXPECT_TRUE(world.has_stage("fill.fast"));
  EXPECT_FALSE(world.has_stage("fill.slow"));
}

}  // namespace
}  // namespace alloy::test
