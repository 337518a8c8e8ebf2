// Ownership against hostile mods (issue 18, item 5): a Lua resolver writes
// only its own mod's properties and what a scene grants it; a mod cannot
// redefine another's property type, the kit's materials and parts, or patch
// the kit; a mod's files stay inside its folder; host tables refuse rawset;
// an allocation the budget refused stops the mod even under a pcall.
//
// Each case asserts that the process lives (the test goes on), that the world
// goes on (two well-behaved mods keep stepping: `good`, and `witness`, whose
// counter the evil mod covets), that nothing outside changed (the ball, the
// witness's counter, the kit's steel), and that the message names the mods
// and the file and line.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

// The other mod: its counter is what a hostile resolver wants to overwrite.
const char* kWitness = R"LUA(
mod.property { name = "witness" }
mod.resolver {
  name = "witness.count", writes = { "witness" }, needs = { "witness" },
  advance = function(w) local c = w:write("witness") for i in c:each() do c[i] = c[i] + 1 end end,
}
)LUA";

/// A runtime whose resolver (line 2) declares `writes` and runs `body`.
std::string writer(const std::string& writes, const std::string& body = "") {
  return "mod.property { name = \"evil_mark\" }\n"
         "mod.resolver { name = \"evil.stage\", writes = { " +
         writes +
         " }, needs = { \"evil_mark\" },\n"
         "  advance = function(w)\n" +
         body +
         "\n"
         "  end }\n";
}

/// A world with the good and the witness mods, a ball, and a thing that
/// carries every mod's counter; `evil` is loaded (or refused) in between.
struct Arena {
  PluginRegistry registry;
  TempMods mods;
  std::vector<std::string> log;
  std::unique_ptr<lua::ModRuntime> runtime;
  std::unique_ptr<World> world;
  ObjectId ball, thing;
  std::string refusal;  ///< why evil was not loaded ("" if it was)

  explicit Arena(const std::string& evil_runtime, std::vector<lua::WriteGrant> grants = {},
                 const std::string& evil_manifest = "") {
    register_native_plugins(registry);
    mods.mod("good", kGood);
    mods.mod("witness", kWitness);
    if (!evil_runtime.empty()) mods.mod("evil", evil_runtime, evil_manifest);
    lua::ModRuntimeOptions o = runtime_options(mods, &log);
    o.budget.memory_bytes = 8u << 20;
    o.budget.ticks_per_step = 2'000'000;
    o.budget.seconds_per_step = 2;
    o.grants = std::move(grants);
    runtime = std::make_unique<lua::ModRuntime>(registry, o);
    runtime->load("good");
    runtime->load("witness");
    try {
      runtime->load("evil");
    } catch (const InputError& e) {
      refusal = e.what();
      if (refusal.empty()) refusal = "(empty message)";
    }
    world = std::make_unique<World>(registry);
    runtime->attach(*world);
    ball = world->create("ball");
    world->set(ball, "shape", std::string("sphere"));
    world->set(ball, "radius", 0.1);
    world->set(ball, "mass", 4.0);
    world->set(ball, "position", Vec3{1, 2, 3});
    thing = world->create("thing");
    world->set(thing, "good_count", 0.0);
    world->set(thing, "witness", 0.0);
    if (registry.properties().find("evil_mark")) world->set(thing, "evil_mark", 0.0);
  }

  double number(ObjectId id, const char* p) const { return std::get<double>(world->get(id, p)); }
  Vec3 vec(ObjectId id, const char* p) const { return std::get<Vec3>(world->get(id, p)); }

  /// Runs `steps` and checks that the world went on with the good mods in it.
  void run_and_check_the_others(int steps = 3) {
    world->run(steps);
    EXPECT_EQ(world->step_count(), std::uint64_t(steps));
    EXPECT_EQ(number(thing, "good_count"), steps);
    EXPECT_EQ(number(thing, "witness"), steps) << "the witness's counter was touched";
    EXPECT_FALSE(runtime->stopped("good"));
    EXPECT_FALSE(runtime->stopped("witness"));
  }

  /// Evil was refused at load: it registered nothing, and the ball is as it was.
  void check_refused(const std::vector<std::string>& parts) {
    EXPECT_FALSE(refusal.empty()) << "the evil mod was loaded";
    EXPECT_FALSE(runtime->has("evil"));
    EXPECT_EQ(registry.find("evil.stage"), nullptr);
    for (const auto& p : parts)
      EXPECT_TRUE(contains(refusal, p)) << "'" << p << "' not in: " << refusal;
    run_and_check_the_others();
    EXPECT_EQ(number(ball, "mass"), 4.0);
    const Vec3 at = vec(ball, "position");
    EXPECT_NEAR(at.x, 1, 1e-9);
    EXPECT_NEAR(at.z, 3, 1e-9);
  }
};

// --- a resolver writes only its own properties ---------------------------------------

struct ForeignWrite {
  const char* property;
  const char* owner;  ///< as the message names it
};

class ResolverWrites : public ::testing::TestWithParam<ForeignWrite> {};

TEST_P(ResolverWrites, AnotherOwnersPropertyIsRefusedAtLoadNamingBoth) {
  const ForeignWrite& f = GetParam();
  Arena a(writer("\"evil_mark\", \"" + std::string(f.property) + "\""));
  a.check_refused({"evil/runtime.lua:2", "resolver 'evil.stage' of mod 'evil'",
                   "writes '" + std::string(f.property) + "'", f.owner, "grants"});
}

INSTANTIATE_TEST_SUITE_P(
    Ownership, ResolverWrites,
    ::testing::Values(ForeignWrite{"position", "the native plugin 'rigid_body'"},
                      ForeignWrite{"mass", "the native plugin 'rigid_body'"},
                      ForeignWrite{"velocity", "the native plugin 'rigid_body'"},
                      ForeignWrite{"orientation", "the native plugin 'rigid_body'"},
                      ForeignWrite{"witness", "mod 'witness'"}),
    [](const auto& info) { return std::string(info.param.property); });

TEST(HostileOwnership, AGrantLetsAResolverWriteWhatItWasGranted) {
  Arena a(writer("\"evil_mark\", \"witness\", \"mass\"",
                 "    local m, c = w:write(\"mass\"), w:write(\"witness\")\n"
                 "    m[w:find(\"ball\")] = 5\n"
                 "    c[w:find(\"thing\")] = 100"),
          {{"evil", {"witness", "mass"}, ErrorLocation{"scene.lua", 3, ""}}});
  ASSERT_TRUE(a.refusal.empty()) << a.refusal;
  a.world->run(2);
  EXPECT_EQ(a.number(a.ball, "mass"), 5.0);
  EXPECT_EQ(a.number(a.thing, "good_count"), 2.0);
  EXPECT_GE(a.number(a.thing, "witness"), 100.0);  // granted: the scene asked for it
}

TEST(HostileOwnership, AGrantOfOneThingIsNotAGrantOfAnother) {
  Arena a(writer("\"evil_mark\", \"witness\", \"mass\""),
          {{"evil", {"witness"}, ErrorLocation{"scene.lua", 3, ""}}});
  a.check_refused({"evil/runtime.lua:2", "writes 'mass'", "the native plugin 'rigid_body'"});
}

TEST(HostileOwnership, AGrantOfAPropertyThatDoesNotExistIsAClearError) {
  Arena a(writer("\"evil_mark\""), {{"evil", {"posiiton"}, ErrorLocation{"scene.lua", 3, ""}}});
  a.check_refused({"scene.lua:3", "mod 'evil' is granted property 'posiiton', which does not exist",
                   "did you mean 'position'"});
}

TEST(HostileOwnership, RedefiningAnotherModsPropertyTypeIsRefused) {
  Arena a(
      "mod.property { name = \"evil_mark\" }\n"
      "mod.property { name = \"witness\" }\n");
  a.check_refused({"evil/runtime.lua:2", "'witness'", "belongs to mod 'witness'",
                   "mod 'evil' cannot define it"});
}

TEST(HostileOwnership, APropertyWithTheNameOfANativeOneIsRefused) {
  // The same definition as the rigid body's, so only ownership refuses it.
  Arena a(
      "mod.property { name = \"evil_mark\" }\n"
      "mod.property { name = \"mass\", unit = \"kg\", min = 0, min_exclusive = true, max = 1e12 }\n"
      "mod.resolver { name = \"evil.stage\", writes = { \"mass\" }, needs = { \"evil_mark\" },\n"
      "  advance = function(w) end }\n");
  a.check_refused({"evil/runtime.lua:2", "'mass'", "the native plugin 'rigid_body'",
                   "mod 'evil' cannot define it"});
}

TEST(HostileOwnership, AModStillWritesItsOwnAndReloadsAsItWas) {
  Arena a(writer("\"evil_mark\"", "    local m = w:write(\"evil_mark\") m[w:find(\"thing\")] = 7"));
  ASSERT_TRUE(a.refusal.empty()) << a.refusal;
  a.run_and_check_the_others();
  EXPECT_EQ(a.number(a.thing, "evil_mark"), 7.0);
  EXPECT_EQ(a.runtime->reload("evil").kind, Kind::Reloaded);
}

// --- a mod's files stay in its folder ------------------------------------------------

TEST(HostileOwnership, ARuntimeFileLinkedToEtcPasswdIsRefused) {
  Arena a("");
  a.mods.write("evil/mod.lua",
               "return { name = \"evil\", version = \"1\", runtime = \"runtime.lua\" }");
  std::filesystem::create_symlink("/etc/passwd", a.mods / "evil/runtime.lua");
  try {
    a.runtime->load("evil");
    ADD_FAILURE() << "a symlink out of the mod was followed";
  } catch (const InputError& e) {
    a.refusal = e.what();
  }
  a.check_refused({"mod 'evil'", "evil/runtime.lua", "leads outside the mod's folder",
                   "/etc/passwd", "evil/mod.lua"});
}

TEST(HostileOwnership, ARuntimeFileLinkedIntoAnotherModIsRefused) {
  Arena a("");
  a.mods.write("evil/mod.lua",
               "return { name = \"evil\", version = \"1\", runtime = \"runtime.lua\" }");
  std::filesystem::create_symlink(a.mods / "witness/runtime.lua", a.mods / "evil/runtime.lua");
  try {
    a.runtime->load("evil");
  } catch (const InputError& e) {
    a.refusal = e.what();
  }
  a.check_refused({"mod 'evil'", "evil/runtime.lua", "witness/runtime.lua", "outside"});
}

TEST(HostileOwnership, ARequiredFileLinkedOutsideIsRefusedAtTheRequireLine) {
  Arena a("");
  a.mods.mod("evil", "mod.property { name = \"evil_mark\" }\nlocal s = require \"evil.secret\"\n");
  std::filesystem::create_symlink("/etc/passwd", a.mods / "evil/secret.lua");
  try {
    a.runtime->load("evil");
  } catch (const InputError& e) {
    a.refusal = e.what();
  }
  a.check_refused({"evil/runtime.lua:2", "mod 'evil'", "evil/secret.lua", "/etc/passwd"});
}

TEST(HostileOwnership, AFolderLinkedIntoAnotherModCannotBeRequiredThrough) {
  Arena a("");
  a.mods.mod("evil",
             "mod.property { name = \"evil_mark\" }\nlocal s = require \"evil.lib.runtime\"\n");
  std::filesystem::create_directory_symlink(a.mods / "witness", a.mods / "evil/lib");
  try {
    a.runtime->load("evil");
  } catch (const InputError& e) {
    a.refusal = e.what();
  }
  a.check_refused({"evil/runtime.lua:2", "mod 'evil'", "evil/lib/runtime.lua", "outside"});
}

TEST(HostileOwnership, DotDotInAManifestEntryIsRefused) {
  Arena a("mod.property { name = \"evil_mark\" }\n", {}, "main = \"../witness/runtime.lua\"");
  a.check_refused({"evil/mod.lua", "'main' must name a file inside the mod's folder"});
}

TEST(HostileOwnership, DotDotInARequireIsRefused) {
  Arena a("mod.property { name = \"evil_mark\" }\nrequire \"evil/../../witness/runtime\"\n");
  a.check_refused({"evil/runtime.lua:2", "paths are not allowed"});
}

// --- host tables refuse rawset ---------------------------------------------------------

struct RawsetAttempt {
  const char* name;
  const char* code;
};

class HostTables : public ::testing::TestWithParam<RawsetAttempt> {};

TEST_P(HostTables, RawsetIsRefusedAndTheStageDisabled) {
  const RawsetAttempt& r = GetParam();
  Arena a(writer("\"evil_mark\"", std::string("    ") + r.code));
  ASSERT_TRUE(a.refusal.empty()) << a.refusal;
  a.run_and_check_the_others();
  std::string failures = stage_failures(*a.runtime);
  EXPECT_TRUE(contains(failures, "belongs to the host and is read-only")) << failures;
  EXPECT_TRUE(contains(failures, "evil/runtime.lua:4")) << failures;
  EXPECT_TRUE(contains(failures, "evil.stage")) << failures;
  EXPECT_FALSE(a.runtime->stopped("evil"));  // an error, not a budget: only the stage goes
}

INSTANTIATE_TEST_SUITE_P(
    Ownership, HostTables,
    ::testing::Values(RawsetAttempt{"vec3", "rawset(vec3, 'new', function() return 1 end)"},
                      RawsetAttempt{"quat", "rawset(quat, 'identity', 0)"},
                      RawsetAttempt{"settings", "rawset(w.settings, 'x', 1)"},
                      RawsetAttempt{"alloy", "rawset(alloy, 'freeze', print)"}),
    [](const auto& info) { return std::string(info.param.name); });

// --- a refused allocation stops the mod, pcall or not --------------------------------

TEST(HostileOwnership, APcallThatSwallowsOutOfMemoryDoesNotLetTheModGoOn) {
  Arena a(writer("\"evil_mark\"",
                 "    local ok = pcall(string.rep, 'x', 1e8)\n"
                 "    for i = 1, 10 do w.state.after = (w.state.after or 0) + 1 end"));
  ASSERT_TRUE(a.refusal.empty()) << a.refusal;
  a.run_and_check_the_others();
  EXPECT_TRUE(a.runtime->stopped("evil"));
  const std::string reason = a.runtime->stop_reason("evil");
  EXPECT_TRUE(contains(reason, "mod 'evil' stopped: it ran out of its memory budget of 8 MiB"))
      << reason;
  EXPECT_TRUE(contains(reason, "evil/runtime.lua:5")) << reason;  // the loop after the pcall
  EXPECT_LE(a.runtime->memory_of("evil"), 8u << 20);
}

TEST(HostileOwnership, APcallSwallowingOutOfMemoryAsTheLastThingStillStops) {
  Arena a(writer("\"evil_mark\"", "    pcall(string.rep, 'x', 1e8)"));
  a.run_and_check_the_others();
  EXPECT_TRUE(a.runtime->stopped("evil"));
  EXPECT_TRUE(contains(a.runtime->stop_reason("evil"), "evil/runtime.lua"))
      << a.runtime->stop_reason("evil");
}

TEST(HostileOwnership, OutOfMemorySwallowedWhileLoadingRefusesTheMod) {
  Arena a(
      "mod.property { name = \"evil_mark\" }\nlocal ok = pcall(string.rep, 'x', 1e8)\n"
      "for i = 1, 3 do end\n");
  a.check_refused({"mod 'evil' stopped: it ran out of its memory budget", "evil/runtime.lua:3"});
}

// --- the kit, and other mods' modules, from a scene ---------------------------------

/// Loads mods/<scene> from a temp folder (the kit from the source tree).
struct SceneArena {
  PluginRegistry registry;
  TempMods mods;
  SceneArena() { register_native_plugins(registry); }
  lua::LoadedScene load(const std::string& mod) {
    lua::LoadOptions o;
    o.mod_paths = {mods.path(), source_path("mods")};
    o.mod_log = [](const std::string&, const std::string&) {};
    return lua::load_scene(mods / mod, registry, o);
  }
  std::string failure(const std::string& mod) {
    try {
      load(mod);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  /// A mod with a main file (parts) and a scene that requires it.
  void parts_mod(const std::string& name, const std::string& init) {
    mods.write(name + "/mod.lua",
               "return { name = \"" + name + "\", version = \"1\", depends = { \"kit\" } }\n");
    mods.write(name + "/init.lua", "local kit = require \"kit\"\n" + init);
  }
  void scene(const std::string& text) {
    mods.write("stage/mod.lua",
               "return { name = \"stage\", version = \"1\", depends = { \"kit\", \"evil\" }, "
               "scene = \"scene.lua\" }\n");
    mods.write("stage/scene.lua", text);
  }
};

const char* kSteelScene =
    "local kit = require \"kit\"\n"
    "local evil = require \"evil\"\n"
    "kit.disk { name = \"coin\", material = \"steel\", at = { 0, 1 }, radius = 0.1 }\n";

double steel_disk_mass() {
  return 7850 * 4.0 / 3.0 * std::numbers::pi * 0.001;
}

struct KitTamper {
  const char* name;
  const char* code;     ///< evil/init.lua from line 2
  const char* message;  ///< part of the refusal
};

class KitTampering : public ::testing::TestWithParam<KitTamper> {};

TEST_P(KitTampering, IsRefusedAtItsLineAndTheKitStaysAsItWas) {
  const KitTamper& t = GetParam();
  SceneArena s;
  s.parts_mod("evil", std::string(t.code) + "\nreturn {}\n");
  s.scene(kSteelScene);
  const std::string failure = s.failure("stage");
  EXPECT_TRUE(contains(failure, t.message)) << failure;
  EXPECT_TRUE(contains(failure, "evil/init.lua:2")) << failure;
  // The same tampering under a pcall: refused, and the scene's steel is the kit's.
  s.parts_mod("evil", "local ok, e = pcall(function() " + std::string(t.code) +
                          " end)\nassert(not ok, 'tampering went through')\nreturn {}\n");
  lua::LoadedScene scene = s.load("stage");
  EXPECT_NEAR(std::get<double>(scene.world->get(scene.world->find("coin"), "mass")),
              steel_disk_mass(), 1e-9);
  EXPECT_EQ(std::get<double>(scene.world->get(scene.world->find("coin"), "restitution")), 0.6);
}

INSTANTIATE_TEST_SUITE_P(
    Ownership, KitTampering,
    ::testing::Values(
        KitTamper{"redefine_steel",
                  "kit.add_material('steel', { density = 1, friction = 0, restitution = 1 })",
                  "material 'steel' belongs to mod 'kit'; mod 'evil' cannot redefine it"},
        KitTamper{"redefine_disk",
                  "kit.define('disk', { args = {}, build = function() return {} end })",
                  "part 'kit.disk' belongs to mod 'kit'; mod 'evil' cannot redefine it"},
        KitTamper{"assign_a_part", "kit.disk = function() end", "read-only"},
        KitTamper{"rawset_a_part", "rawset(kit, 'disk', function() end)", "belongs to the host"},
        KitTamper{"patch_a_material", "kit.material('steel').density = 1", "read-only"},
        KitTamper{"kit_metatable", "getmetatable(kit).__index = nil", "index a string value"},
        KitTamper{"kit_registry", "require('kit.registry').component = nil",
                  "mod 'kit' keeps this module to itself; mod 'evil' cannot use it"},
        KitTamper{"kit_materials", "require('kit.materials').steel.density = 1",
                  "keeps this module to itself"},
        KitTamper{"kit_parts", "require('kit.parts.bodies').disk.build = nil",
                  "keeps this module to itself"},
        KitTamper{"kit_geometry", "require('kit.geometry').sphere_volume = function() return 1 end",
                  "read-only"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(HostileOwnership, APartsDescriptionIsACopy) {
  SceneArena s;
  s.parts_mod(
      "evil",
      "local c = kit.component('disk')\n"
      "for _, a in ipairs(c.args) do if a[1] == 'material' then a.default = 'rubber' end end\n"
      "return {}\n");
  s.scene(kSteelScene);
  lua::LoadedScene scene = s.load("stage");
  EXPECT_NEAR(std::get<double>(scene.world->get(scene.world->find("coin"), "mass")),
              steel_disk_mass(), 1e-9);
}

TEST(HostileOwnership, AModsOwnMaterialsAndPartsAreItsOwnToReplace) {
  SceneArena s;
  s.parts_mod("evil",
              "kit.add_material('lead', { density = 11340, friction = 0.5, restitution = 0.1 })\n"
              "kit.add_material('lead', { density = 11000, friction = 0.5, restitution = 0.1 })\n"
              "return {}\n");
  s.scene(std::string(kSteelScene) +
          "kit.disk { name = \"bob\", material = \"lead\", at = { 1, 1 }, radius = 0.1 }\n"
          "kit.add_material('lead', { density = 1, friction = 0.5, restitution = 0.1 })\n");
  const std::string failure = s.failure("stage");
  // The scene (mod 'stage') cannot replace evil's lead either: the rule is the same for all.
  EXPECT_TRUE(contains(failure, "material 'lead' belongs to mod 'evil'; mod 'stage' cannot"))
      << failure;
  EXPECT_TRUE(contains(failure, "stage/scene.lua:5")) << failure;
}

TEST(HostileOwnership, AnotherModsModuleIsReadOnly) {
  SceneArena s;
  s.parts_mod("evil", "return { size = 1, make = function() return 2 end }\n");
  s.scene("local evil = require \"evil\"\nevil.make = nil\n");
  const std::string failure = s.failure("stage");
  EXPECT_TRUE(contains(failure, "read-only")) << failure;
  EXPECT_TRUE(contains(failure, "stage/scene.lua:2")) << failure;
}

// --- grants from a scene -------------------------------------------------------------

struct GrantScene : SceneArena {
  GrantScene(const std::string& grants) {
    mods.write("pusher/mod.lua",
               "return { name = \"pusher\", version = \"1\", runtime = \"runtime.lua\", "
               "scene = \"scene.lua\" }\n");
    mods.write(
        "pusher/runtime.lua",
        "mod.property { name = \"push\" }\n"
        "mod.resolver { name = \"pusher.mass\", writes = { \"mass\" }, needs = { \"push\" },\n"
        "  advance = function(w) local m = w:write(\"mass\") for i in w:each(\"push\") do "
        "m[i] = 2 end end }\n");
    mods.write("pusher/scene.lua", "world { dt = 0.01" + grants +
                                       " }\n"
                                       "object { name = \"box\", shape = \"sphere\", radius = "
                                       "0.1, mass = 1, position = { 0, 0, 0 }, push = 1 }\n");
  }
};

TEST(HostileOwnership, ASceneGrantLetsItsModWriteANativeProperty) {
  GrantScene s(", grants = { pusher = { \"mass\" } }");
  lua::LoadedScene scene = s.load("pusher");
  scene.world->run(2);
  EXPECT_EQ(std::get<double>(scene.world->get(scene.world->find("box"), "mass")), 2.0);
}

TEST(HostileOwnership, WithoutTheGrantTheSceneDoesNotLoad) {
  GrantScene s("");
  const std::string failure = s.failure("pusher");
  EXPECT_TRUE(contains(failure, "pusher/runtime.lua:2")) << failure;
  EXPECT_TRUE(contains(failure, "resolver 'pusher.mass' of mod 'pusher' writes 'mass'")) << failure;
  EXPECT_TRUE(contains(failure, "world { grants = { pusher = { \"mass\" } } }")) << failure;
}

TEST(HostileOwnership, ASceneGrantOfAnUnknownPropertyOrModIsAClearError) {
  GrantScene typo(", grants = { pusher = { \"mas\" } }");
  std::string failure = typo.failure("pusher");
  EXPECT_TRUE(contains(failure, "pusher/scene.lua:1")) << failure;
  EXPECT_TRUE(contains(failure, "granted property 'mas', which does not exist")) << failure;
  GrantScene stranger(", grants = { pusher = { \"mass\" }, nobody = { \"mass\" } }");
  failure = stranger.failure("pusher");
  EXPECT_TRUE(contains(failure, "pusher/scene.lua:1")) << failure;
  EXPECT_TRUE(contains(failure, "'grants' names mod 'nobody'")) << failure;
  GrantScene bad(", grants = { pusher = 3 }");
  EXPECT_TRUE(contains(bad.failure("pusher"), "must be a list of property names"));
}

}  // namespace
}  // namespace alloy::test
