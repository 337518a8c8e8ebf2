// Hot reload (lua/mod_runtime.hpp): mod files are rewritten on disk while a
// world runs. A reload is a transaction: a good change takes effect on the
// next steps with every property and the mod's state kept; a bad one keeps
// the old code running and says where it is wrong. Unloading removes
// everything the mod registered (EnTT's test of a plugin's unloading).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "lua/lua_stages.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

/// The capacitor mod: a resolver charges every object that carries `charge`
/// at `rate` per second and counts its advances in the mod's state table.
/// `extra` is added to the advance's loop body.
std::string capacitor(const std::string& rate, const std::string& extra = "") {
  return R"LUA(mod.property { name = "charge", unit = "C" }
mod.property { name = "ticks" }
local RATE = )LUA" +
         rate + R"LUA(
mod.resolver {
  name = "cap.charger", writes = { "charge", "ticks" }, needs = { "charge" },
  advance = function(w, dt)
    local c, t = w:write("charge"), w:write("ticks")
    w.state.n = w.state.n + 1
    for i in c:each() do
      )LUA" +
         extra + R"LUA(
      c[i] = c[i] + RATE * dt
      t[i] = w.state.n + 1000 * w.state.reloads
    end
  end,
}
function mod.on_load(state) state.n = 0; state.reloads = 0 end
function mod.on_reload(state) state.reloads = state.reloads + 1 end
)LUA";
}

class HotReload : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    mods.mod("cap", capacitor("1"));
  }
  void start(lua::ModRuntimeOptions o) {
    runtime = std::make_unique<lua::ModRuntime>(registry, std::move(o));
    runtime->load("cap");
    world = std::make_unique<World>(registry);
    runtime->attach(*world);
    jar = world->create("jar");
    world->set(jar, "charge", 0.0);
    runtime->poll();  // the "loaded" report
  }
  void start() { start(runtime_options(mods, &log)); }
  double charge() { return std::get<double>(world->get(jar, "charge")); }
  double ticks() { return std::get<double>(world->get(jar, "ticks")); }
  bool event_next_step(const std::string& type) {
    world->step();
    return find_event(*world, type) != nullptr;
  }

  PluginRegistry registry;
  TempMods mods;
  std::vector<std::string> log;
  std::unique_ptr<lua::ModRuntime> runtime;  // declared before the world: it outlives it
  std::unique_ptr<World> world;
  ObjectId jar;
};

TEST_F(HotReload, AChangedConstantTakesEffectOnTheNextSteps) {
  start();
  world->run(240);
  EXPECT_NEAR(charge(), 1.0, 1e-9);
  mods.write("cap/runtime.lua", capacitor("10"));
  const lua::ModReport r = runtime->reload("cap");
  EXPECT_EQ(r.kind, Kind::Reloaded) << r.message;
  EXPECT_TRUE(event_next_step("mod_reloaded"));
  world->run(239);
  EXPECT_NEAR(charge(), 11.0, 1e-9);  // one second at the old rate, one at the new
}

TEST_F(HotReload, ASyntaxErrorKeepsTheOldCodeAndReportsTheLine) {
  start();
  world->run(120);
  mods.write(
      "cap/runtime.lua",
      "mod.property { name = \"charge\", unit = \"C\" }\nlocal RATE = 10\nlocal broken = = 1\n");
  const lua::ModReport r = runtime->reload("cap");
  EXPECT_EQ(r.kind, Kind::ReloadFailed);
  EXPECT_TRUE(contains(r.where.file, "cap/runtime.lua")) << r.message;
  EXPECT_EQ(r.where.line, 3) << r.message;
  EXPECT_TRUE(contains(r.message, "cap/runtime.lua:3:")) << r.message;
  EXPECT_TRUE(contains(r.message, "old code keeps running")) << r.message;
  EXPECT_TRUE(event_next_step("mod_reload_failed"));
  world->run(119);
  EXPECT_NEAR(charge(), 1.0, 1e-9);  // still the old rate, never stopped
  EXPECT_EQ(ticks(), 240);           // and the old state
}

TEST_F(HotReload, ErrorsFoundWhileLoadingOrCheckingAlsoKeepTheOldCode) {
  lua::ModRuntimeOptions o = runtime_options(mods, &log);
  o.budget.ticks_to_load = 1'000'000;
  start(o);
  world->run(10);
  const std::pair<std::string, int> bad[] = {
      {"mod.property { name = \"charge\", unit = \"C\" }\n\nerror(\"not today\")\n", 3},
      {"mod.property { name = \"charge\", unit = \"C\" }\nmod.resolver { name = \"cap.charger\", "
       "writes = { \"chrage\" },"
       " advance = function() end }\n",
       2},
      {"mod.property { name = \"charge\", unit = \"A\" }\n",
       0},                         // a property redefined differently
      {"while true do end\n", 1},  // runs past the load budget
  };
  for (const auto& [text, line] : bad) {
    SCOPED_TRACE(text);
    mods.write("cap/runtime.lua", text);
    const lua::ModReport r = runtime->reload("cap");
    EXPECT_EQ(r.kind, Kind::ReloadFailed);
    EXPECT_EQ(r.where.line, line) << r.message;
    world->run(10);
    EXPECT_FALSE(runtime->stopped("cap"));
  }
  EXPECT_NEAR(charge(), 50.0 / 240, 1e-9);  // the old code ran throughout
  EXPECT_EQ(runtime->plugins_of("cap"), std::vector<std::string>{"cap.charger"});
}

TEST_F(HotReload, TheModsStateAndEveryPropertySurviveAReload) {
  start();
  world->run(10);
  EXPECT_EQ(ticks(), 10);
  mods.write("cap/runtime.lua", capacitor("2"));
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  EXPECT_NEAR(charge(), 10.0 / 240, 1e-12);  // the world's properties were not touched
  world->step();
  EXPECT_EQ(ticks(), 11 + 1000);  // the count went on (state kept), and on_reload ran once
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  world->step();
  EXPECT_EQ(ticks(), 12 + 2000);
}

TEST_F(HotReload, ALuaErrorDisablesTheStageAndAReloadBringsItBack) {
  start();
  mods.write("cap/runtime.lua",
             capacitor("1", "if c[i] >= 0.5 then error(\"overcharged \" .. w:name(i)) end"));
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  bool disabled = false;
  for (int i = 0; i < 240; ++i) {
    world->step();
    if (const Event* e = find_event(*world, "stage_disabled")) {
      disabled = true;
      EXPECT_EQ(e->source, "cap.charger");
      EXPECT_TRUE(contains(e->text, "cap/runtime.lua:10: overcharged jar")) << e->text;
      EXPECT_TRUE(contains(e->text, "stack traceback")) << e->text;
    }
  }
  EXPECT_TRUE(disabled);
  EXPECT_EQ(world->step_count(), 240u);  // the world went on
  EXPECT_NEAR(charge(), 0.5, 0.005);     // and the stage did nothing more
  int disabled_reports = 0;
  for (const auto& r : runtime->poll()) disabled_reports += r.kind == Kind::StageDisabled;
  EXPECT_EQ(disabled_reports, 1);

  mods.write("cap/runtime.lua", capacitor("1"));
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  world->run(120);
  EXPECT_NEAR(charge(), 1.0, 0.005);  // running again
}

TEST_F(HotReload, StagesWhoseDeclarationsChangeAreRecreatedAndNewOnesAppear) {
  start();
  world->run(5);
  const std::string with_glow = capacitor("1") + R"LUA(
mod.derived {
  name = "cap.glow", reads = { "charge" }, provides = { light = "number" },
  update = function(w) local c, l = w:read("charge"), w:output("light") for i in c:each() do l[i] = c[i] end end,
}
mod.interaction {
  name = "cap.shaker", reads = { "charge" }, derived = { "cap.glow" }, target = "cap.charger",
  apply = function(w) end,
}
)LUA";
  mods.write("cap/runtime.lua", with_glow);
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  // New stages are live at once (built, primed), not after some later change.
  EXPECT_TRUE(world->has_stage("cap.glow"));
  EXPECT_TRUE(world->has_stage("cap.shaker"));
  // A changed declaration (an interaction function added) re-creates the
  // resolver and the interaction that targets it; the derived set stays.
  auto* glow = world->stage("cap.glow");
  std::string changed = with_glow;
  changed.replace(changed.find("needs = { \"charge\" },"), 21,
                  "needs = { \"charge\" }, functions = { poke = {} },");
  mods.write("cap/runtime.lua", changed);
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  auto* charger = dynamic_cast<lua::LuaResolver*>(world->stage("cap.charger"));
  ASSERT_TRUE(charger);
  ASSERT_EQ(charger->functions().size(), 1u);  // the new declaration, not the old stage
  EXPECT_EQ(charger->functions()[0].name, "poke");
  EXPECT_EQ(world->stage("cap.glow"), glow);
  EXPECT_TRUE(world->has_stage("cap.shaker"));
  world->run(5);
  EXPECT_EQ(ticks(), 10 + 2000);  // the state went on across the re-creation (and two reloads)
  // A stage gone from the file is gone from the world.
  mods.write("cap/runtime.lua", capacitor("1"));
  ASSERT_EQ(runtime->reload("cap").kind, Kind::Reloaded);
  EXPECT_FALSE(world->has_stage("cap.glow"));
  EXPECT_FALSE(world->has_stage("cap.shaker"));
  EXPECT_FALSE(registry.find("cap.glow"));
}

TEST_F(HotReload, UnloadingRemovesEverythingTheModRegistered) {
  World({registry});  // registers what any world does ("name")
  const std::vector<std::string> plugins_before = registry.order();
  const std::vector<std::string> properties_before = registry.properties().names();
  mods.write("cap/runtime.lua", capacitor("1") + R"LUA(
mod.derived {
  name = "cap.glow", reads = { "charge" }, provides = { light = "number" },
  update = function(w) end,
}
mod.interaction {
  name = "rigid_body_from_charge", reads = { "charge", "mass" }, target = "rigid_body",
  apply = function(w) for i in w:each("mass") do w.target.add_force(i, { 0, 1, 0 }) end end,
}
mod.on("contact_began", function() end)
)LUA");
  start();
  const ObjectId ball = world->create("ball");
  world->set(ball, "mass", 1.0);
  world->set(ball, "shape", std::string("sphere"));
  world->set(ball, "radius", 0.1);
  world->run(10);
  for (const char* p : {"cap.charger", "cap.glow", "rigid_body_from_charge"}) {
    EXPECT_TRUE(registry.find(p)) << p;
    EXPECT_TRUE(world->has_stage(p)) << p;
  }
  EXPECT_EQ(runtime->handlers_of("cap"), 1u);

  runtime->unload("cap");
  EXPECT_FALSE(runtime->has("cap"));
  EXPECT_EQ(runtime->handlers_of("cap"), 0u);
  EXPECT_EQ(registry.order(), plugins_before);  // exactly what was there before
  for (const char* p : {"cap.charger", "cap.glow", "rigid_body_from_charge"})
    EXPECT_FALSE(world->has_stage(p)) << p;
  // Property types stay (the objects still carry them), values untouched.
  std::vector<std::string> properties = registry.properties().names();
  EXPECT_EQ(properties.size(), properties_before.size() + 2);
  const double c = charge();
  world->run(10);
  EXPECT_EQ(charge(), c);
  EXPECT_TRUE(world->has_stage("rigid_body"));  // the native stages go on

  // Loading again registers it all again, with a fresh state.
  runtime->load("cap");
  world->step();
  EXPECT_TRUE(world->has_stage("cap.charger"));
  EXPECT_EQ(ticks(), 1);
}

TEST_F(HotReload, ALoadedModCanBeUsedByAnotherModsInteraction) {
  // Two mods, two Lua states: commands go from one to the other as data.
  mods.mod("sink", R"LUA(
mod.property { name = "level" }
mod.resolver {
  name = "sink.tank", writes = { "level" }, needs = { "level" }, functions = { pour = { "number" } },
  advance = function(w) local l = w:write("level") for i, q in w:commands("pour") do l[i] = l[i] + q end end,
}
)LUA");
  mods.mod("tap", R"LUA(
mod.interaction {
  name = "sink_from_tap", reads = { "level" }, target = "sink.tank",
  apply = function(w) for i in w:each("level") do w.target.pour(i, 0.5) end end,
}
)LUA",
           "depends = { \"sink\" }");
  lua::ModRuntime rt(registry, runtime_options(mods, &log));
  rt.load("tap");
  EXPECT_EQ(rt.loaded(), (std::vector<std::string>{"sink", "tap"}));  // its dependency first
  World w(registry);
  rt.attach(w);
  const ObjectId tank = w.create("tank");
  w.set(tank, "level", 0.0);
  w.run(4);
  EXPECT_DOUBLE_EQ(std::get<double>(w.get(tank, "level")),
                   2.0);                        // primed: a pour in each of 4 advances
  EXPECT_THROW(rt.unload("sink"), InputError);  // tap depends on it
  // The target's interaction function changes: the resolver and the other
  // mod's interaction onto it are re-created, and work together again.
  mods.write("sink/runtime.lua", R"LUA(
mod.property { name = "level" }
mod.resolver {
  name = "sink.tank", writes = { "level" }, needs = { "level" }, functions = { pour = { "number", "number" } },
  advance = function(w) local l = w:write("level") for i, q, k in w:commands("pour") do l[i] = l[i] + q * (k or 1) end end,
}
)LUA");
  ASSERT_EQ(rt.reload("sink").kind, Kind::Reloaded);
  w.step();  // the tap still passes one argument: its stage is disabled, the world goes on
  bool disabled = false;
  for (const auto& r : rt.poll())
    disabled = disabled || (r.kind == Kind::StageDisabled && contains(r.message, "sink_from_tap"));
  EXPECT_TRUE(disabled);
}

TEST_F(HotReload, ChangedSettingDefaultsReachTheLiveStagesButTheScenesValuesWin) {
  auto mod = [](const std::string& rate) {
    return "mod.property { name = \"level\" }\n"
           "mod.resolver { name = \"fill.r\", writes = { \"level\" }, needs = { \"level\" }, "
           "settings = { rate = " +
           rate +
           " },\n  advance = function(w, dt) local l = w:write(\"level\") "
           "for i in l:each() do l[i] = l[i] + w.settings.rate end end }\n";
  };
  mods.mod("fill", mod("1"));
  lua::ModRuntime rt(registry, runtime_options(mods, &log));
  rt.load("fill");
  WorldDef def;
  PluginSettings given;
  given.set("rate", 100.0);
  World plain(registry);
  rt.attach(plain);
  const ObjectId a = plain.create("a");
  plain.set(a, "level", 0.0);
  plain.step();
  EXPECT_EQ(std::get<double>(plain.get(a, "level")), 1.0);
  mods.write("fill/runtime.lua", mod("5"));
  ASSERT_EQ(rt.reload("fill").kind, Kind::Reloaded);
  plain.step();
  EXPECT_EQ(std::get<double>(plain.get(a, "level")), 6.0);  // the new default, in the same stage

  // A scene that sets the rate itself keeps it across reloads.
  TempMods other;
  other.mod("fill2", mod("1").replace(mod("1").find("fill.r"), 6, "fill.q"));
  lua::ModRuntimeOptions o3 = runtime_options(other, &log);
  o3.grants = {{"fill2", {"level"}, {}}};  // fill's property, shared by the scene's grant
  lua::ModRuntime rt3(registry, o3);
  rt3.load("fill2");
  def.plugins = {"fill.q"};
  def.settings["fill.q"] = given;
  World scened(registry, def);
  rt3.attach(scened);
  const ObjectId b = scened.create("b");
  scened.set(b, "level", 0.0);
  scened.step();
  other.write("fill2/runtime.lua", mod("7").replace(mod("7").find("fill.r"), 6, "fill.q"));
  ASSERT_EQ(rt3.reload("fill2").kind, Kind::Reloaded);
  scened.step();
  EXPECT_EQ(std::get<double>(scened.get(b, "level")), 200.0);
}

class Watching : public HotReload, public ::testing::WithParamInterface<bool> {};

TEST_P(Watching, AChangedFileIsNoticedAndReloadedWithinASecond) {
  lua::ModRuntimeOptions o = runtime_options(mods, &log);
  o.poll_files = GetParam();
  start(o);
  runtime->watch();
  world->run(10);
  EXPECT_TRUE(runtime->poll().empty());  // nothing changed yet
  mods.write("cap/runtime.lua", capacitor("100"));
  const auto t0 = std::chrono::steady_clock::now();
  bool reloaded = false;
  while (!reloaded && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(1)) {
    world->step();
    for (const auto& r : runtime->poll()) reloaded = reloaded || r.kind == Kind::Reloaded;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(reloaded);
  const double c = charge();
  world->step();
  EXPECT_NEAR(charge() - c, 100.0 / 240, 1e-9);
  // A file the runtime does not run (a scene) is noted, not reloaded.
  mods.write("cap/scene.lua", "-- a scene\n");
  std::vector<lua::ModReport> notes;
  const auto t1 = std::chrono::steady_clock::now();
  while (notes.empty() && std::chrono::steady_clock::now() - t1 < std::chrono::seconds(1)) {
    for (auto& r : runtime->poll()) notes.push_back(r);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0].kind, Kind::Note);
  EXPECT_TRUE(contains(notes[0].message, "scene.lua changed")) << notes[0].message;
}

INSTANTIATE_TEST_SUITE_P(InotifyAndPolling, Watching, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "Polling" : "Inotify"; });

}  // namespace
}  // namespace alloy::test
