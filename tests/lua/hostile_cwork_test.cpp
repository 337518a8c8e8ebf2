// Hostile code that makes C do unbounded work or recurse on the C stack
// (issue 18, "bounded C work"): pattern bombs, which backtrack inside the
// matcher where no tick reaches, and recursion through C functions that call
// back into Lua (gsub, sort, format, tostring, print, coroutines), which
// overflows the C stack. Each is tried in a mod's stage (beside a good mod
// that must keep stepping), in a scene file and in a manifest. The process
// lives, the message names the mod, the file and the line, and the work
// stays bounded: every case ends after a bounded number of steps (the
// limits, not a clock, stop it).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

/// The evil mod: `code` runs in its resolver's advance, at line 5.
std::string evil(const std::string& code) {
  return "mod.property { name = \"evil_mark\" }\n"
         "mod.resolver { name = \"evil.stage\", writes = { \"evil_mark\" }, "
         "needs = { \"evil_mark\" },\n"
         "  advance = function(w)\n"
         "    local mark = w:write(\"evil_mark\")\n" +
         code +
         "\n"
         "  end }\n";
}

struct Attempt {
  const char* name;
  const char* code;  ///< one line (line 5 of the evil mod's runtime file)
  Kind outcome;      ///< Stopped (a budget) or StageDisabled (a Lua error)
  const char* message;
};

constexpr const char* kCStack = "C stack limit: calls nested too deeply through C functions";
// Recursion through sort, format, tostring and print also grows the Lua
// stack: LuaJIT's own limit ("stack overflow") or the C stack guard stops
// it, whichever comes first (that depends on the build's frame sizes). Both
// are clean errors at the line. Through gsub and coroutines only the guard
// stands between the script and SIGSEGV.
constexpr const char* kEitherStack = "stack";

const Attempt kAttempts[] = {
    // Pattern bombs: each would run for seconds to hours in LuaJIT's matcher.
    {"lazy scan to a missing b", "local s = ('a'):rep(1e5) s:find('.-b')", Kind::Stopped,
     "string.find: the pattern took more than 10 million steps on a string of 100000 bytes"},
    {"three lazy repetitions", "string.rep('a', 3000):find('a-a-a-b')", Kind::Stopped,
     "string.find: the pattern took more than 10 million steps"},
    {"nested greedy repetitions", "local s = ('a'):rep(2000) s:match(('a*'):rep(6) .. 'b')",
     Kind::Stopped, "string.match: the pattern took more than 10 million steps"},
    {"balanced match on a huge input", "local s = ('('):rep(2e5) s:find('%b()')", Kind::Stopped,
     "string.find: the pattern took more than"},
    {"back-reference scans", "local s = ('ab'):rep(5e4) s:find('(.-)%1%1x')", Kind::Stopped,
     "string.find: the pattern took more than"},
    {"gmatch loop", "for x in ('a'):rep(1e5):gmatch('a-a-b') do end", Kind::Stopped,
     "string.gmatch: the pattern took more than"},
    {"gsub bomb", "local s, n = ('a'):rep(3e4):gsub('.-.-b', '')", Kind::Stopped,
     "string.gsub: the pattern took more than"},
    {"many cheap gsubs add up", "local s = ('a'):rep(1e5) for i = 1, 1000 do s:gsub('', 'xy') end",
     Kind::Stopped, "ran more than 2 million ticks"},
    {"pattern bomb caught by pcall, again and again",
     "local s = ('a'):rep(3000) while true do pcall(string.find, s, 'a-a-a-b') end", Kind::Stopped,
     "string.find: the pattern took more than"},
    // Recursion through C functions.
    {"gsub callback recursion", "local function f() return (string.gsub('a', 'a', f)) end f()",
     Kind::StageDisabled, kCStack},
    {"gsub table recursion",
     "local t t = setmetatable({}, { __index = function() return (('a'):gsub('a', t)) end }) "
     "t.x = nil local y = t.y",
     Kind::StageDisabled, kCStack},
    {"sort comparator recursion",
     "local function f() table.sort({ 3, 1, 2 }, function(a, b) f() return a < b end) end f()",
     Kind::StageDisabled, kEitherStack},
    {"sort __lt recursion",
     "local mt = {} mt.__lt = function() table.sort({ setmetatable({}, mt), setmetatable({}, "
     "mt) }) return true end table.sort({ setmetatable({}, mt), setmetatable({}, mt) })",
     Kind::StageDisabled, kEitherStack},
    {"format __tostring recursion",
     "local mt = {} mt.__tostring = function(s) return string.format('%s', s) .. '' end "
     "local x = string.format('%s', setmetatable({}, mt))",
     Kind::StageDisabled, kEitherStack},
    {"tostring recursion",
     "local mt = {} mt.__tostring = function(s) return tostring(s) .. '' end "
     "local x = tostring(setmetatable({}, mt))",
     Kind::StageDisabled, kEitherStack},
    {"print recursion",
     "local mt = {} mt.__tostring = function(s) print(s) return 'x' end print(setmetatable({}, "
     "mt))",
     Kind::StageDisabled, kEitherStack},
    {"coroutine.resume nesting",
     "local function f() local ok, e = coroutine.resume(coroutine.create(f)) if not ok then "
     "error(e, 0) end end f()",
     Kind::StageDisabled, kCStack},
    {"coroutine.wrap nesting", "local function f() return coroutine.wrap(f)() end f()",
     Kind::StageDisabled, kCStack},
    {"a chain through gsub, sort and coroutines",
     "local f f = function() return coroutine.wrap(function() table.sort({ 2, 1 }, function(a, b) "
     "string.gsub('a', 'a', f) return a < b end) end)() end f()",
     Kind::StageDisabled, kCStack},
};

class HostileCWork : public ::testing::TestWithParam<Attempt> {};

TEST_P(HostileCWork, IsBoundedAndTheWorldGoesOn) {
  const Attempt& a = GetParam();
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("good", kGood);
  mods.mod("evil", evil(a.code));
  lua::ModRuntimeOptions o = runtime_options(mods, nullptr);
  o.budget.memory_bytes = 16u << 20;
  o.budget.ticks_per_step = 2'000'000;
  o.budget.seconds_per_step = 30;  // the ticks and the steps stop every case, not the clock
  lua::ModRuntime runtime(registry, o);
  runtime.load("good");
  runtime.load("evil");
  World world(registry);
  runtime.attach(world);
  const ObjectId thing = world.create("thing");
  world.set(thing, "good_count", 0.0);
  world.set(thing, "evil_mark", 0.0);
  world.run(3);

  EXPECT_EQ(world.step_count(), 3u);
  EXPECT_EQ(std::get<double>(world.get(thing, "good_count")), 3.0);
  EXPECT_FALSE(runtime.stopped("good"));
  std::vector<lua::ModReport> reports;
  for (auto& r : runtime.poll())
    if (r.kind == Kind::StageDisabled || r.kind == Kind::Stopped) reports.push_back(r);
  ASSERT_EQ(reports.size(), 1u) << (reports.empty() ? "nothing reported" : reports[1].message);
  const lua::ModReport& r = reports[0];
  EXPECT_EQ(r.kind, a.outcome) << r.message;
  EXPECT_EQ(r.mod, "evil");
  EXPECT_TRUE(contains(r.message, "mod 'evil'")) << r.message;
  EXPECT_TRUE(contains(r.message, a.message)) << r.message;
  EXPECT_TRUE(contains(r.message, "evil/runtime.lua:5")) << r.message;
  EXPECT_EQ(runtime.stopped("evil"), a.outcome == Kind::Stopped);
  EXPECT_LE(runtime.memory_of("evil"), o.budget.memory_bytes);
}

INSTANTIATE_TEST_SUITE_P(Attempts, HostileCWork, ::testing::ValuesIn(kAttempts),
                         [](const auto& info) {
                           std::string n;
                           for (char c : std::string(info.param.name))
                             n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

// A bounded pattern is not refused: long subjects with ordinary patterns
// still work in a mod, and cost ticks in proportion.
TEST(HostileCWork, OrdinaryPatternsOnLongStringsStillWork) {
  PluginRegistry registry;
  TempMods mods;
  mods.mod("parse", R"LUA(
mod.property { name = "fields" }
mod.resolver { name = "parse.stage", writes = { "fields" }, needs = { "fields" },
  advance = function(w)
    local text = ("key_%d = value %d\n"):rep(2000):gsub("%%d", "7")
    local n = 0
    for k, v in text:gmatch("(%w+)%s*=%s*([^\n]+)") do n = n + 1 end
    local a, b = text:find("(%w+)%s*=%s*(%w+)%s*(%d+)\n$")
    local f = w:write("fields")
    for i in f:each() do f[i] = n + (a and 0.5 or 0) end
  end }
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  runtime.load("parse");
  World world(registry);
  runtime.attach(world);
  const ObjectId o = world.create("o");
  world.set(o, "fields", 0.0);
  world.step();
  EXPECT_EQ(stage_failures(runtime), "");
  EXPECT_EQ(std::get<double>(world.get(o, "fields")), 2000.5);
}

// The host's own bindings read a mod's tables with lua_getfield, which runs
// __index: recursion through them is bounded too.
TEST(HostileCWork, RecursionThroughAHostBindingFailsTheLoadAtItsLine) {
  PluginRegistry registry;
  TempMods mods;
  mods.mod("knot",
           "local t\nt = setmetatable({}, { __index = function() mod.property(t) end })\n"
           "mod.property(t)\n");
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  try {
    runtime.load("knot");
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), kEitherStack)) << e.what();
    EXPECT_TRUE(contains(e.what(), "knot/runtime.lua:")) << e.what();
  }
}

// --- scene files and manifests: the same guards while a scene loads ----------------

struct SceneAttempt {
  const char* name;
  const char* code;  ///< the scene's line 2
  const char* message;
};

const SceneAttempt kSceneAttempts[] = {
    {"pattern bomb", "local i = string.rep('a', 3000):find('a-a-a-b')",
     "string.find: the pattern took more than 2 million steps"},
    {"lazy scan", "local i = ('a'):rep(1e5):find('.-b')",
     "string.find: the pattern took more than"},
    {"gsub callback recursion", "local function f() return (string.gsub('a', 'a', f)) end f()",
     kCStack},
    {"coroutine.wrap nesting", "local function f() return coroutine.wrap(f)() end f()", kCStack},
    {"pattern bombs in a pcall loop",
     "local s = ('a'):rep(3000) while true do pcall(string.find, s, 'a-a-a-b') end",
     "ran too long (more than 20 million Lua instructions, pattern matching included)"},
    {"sort comparator recursion",
     "local function f() table.sort({ 3, 1, 2 }, function(a, b) f() return a < b end) end f()",
     kEitherStack},
};

class HostileScene : public ::testing::TestWithParam<SceneAttempt> {};

TEST_P(HostileScene, FailsCleanlyAtItsLine) {
  const SceneAttempt& a = GetParam();
  TempMods dir;
  dir.write("scene.lua", std::string("world { dt = 1/100 }\n") + a.code + "\n");
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions options;
  options.instruction_limit = 20'000'000;
  options.pattern_steps = 2'000'000;
  try {
    lua::check(dir / "scene.lua", registry, options);
    FAIL() << "the scene loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), a.message)) << e.what();
    EXPECT_EQ(e.where().line, 2) << e.what();
    EXPECT_TRUE(contains(e.where().file, "scene.lua")) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Attempts, HostileScene, ::testing::ValuesIn(kSceneAttempts),
                         [](const auto& info) {
                           std::string n;
                           for (char c : std::string(info.param.name))
                             n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

TEST(HostileScene, TheTimeLimitStopsWhatTheInstructionCountWouldLetRun) {
  TempMods dir;
  dir.write("scene.lua", "world { dt = 1/100 }\nwhile true do end\n");
  PluginRegistry registry;
  lua::LoadOptions options;
  options.instruction_limit = 1'000'000'000'000;
  options.seconds_limit = 0.05;
  try {
    lua::check(dir / "scene.lua", registry, options);
    FAIL() << "the scene loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "ran too long (more than 0.05 s)")) << e.what();
    EXPECT_EQ(e.where().line, 2) << e.what();
  }
}

#ifdef ALLOY_BINARY
// The built CLI: a hostile scene makes `alloy check` and `alloy run` exit
// with an error at its line, not hang or die of a signal.
TEST(HostileScene, AlloyCheckAndRunExitWithTheLine) {
  TempMods dir;
  dir.write("bomb.lua", "world { dt = 1/100 }\nlocal i = string.rep('a', 3000):find('a-a-a-b')\n");
  dir.write("recurse.lua",
            "world { dt = 1/100 }\nlocal function f() return (string.gsub('a', 'a', f)) end f()\n");
  for (const char* scene : {"bomb.lua", "recurse.lua"}) {
    for (const char* command : {"check", "run"}) {
      const std::string out = (dir / "out.txt").string();
      const std::string line = std::string(ALLOY_BINARY) + " " + command + " " +
                               (dir / scene).string() + " > " + out + " 2>&1";
      const int status = std::system(line.c_str());
      ASSERT_TRUE(WIFEXITED(status)) << line << ": killed by a signal";
      EXPECT_NE(WEXITSTATUS(status), 0) << line;
      std::ifstream in(out);
      std::stringstream text;
      text << in.rdbuf();
      EXPECT_TRUE(contains(text.str(), std::string(scene) + ":2")) << line << "\n" << text.str();
    }
  }
}
#endif

struct ManifestAttempt {
  const char* name;
  const char* code;  ///< before `return { ... }`, on line 1
  const char* message;
};

const ManifestAttempt kManifestAttempts[] = {
    {"pattern bomb", "local i = ('a'):rep(1e5):find('.-b')",
     "string.find: the pattern took more than 1 million steps"},
    {"gsub recursion", "local function f() return (('a'):gsub('a', f)) end f()", kCStack},
    {"endless loop", "while true do end", "ran too long"},
    {"string bomb", "local s = 'x' while true do s = s .. s end", "out of memory"},
};

class HostileManifest : public ::testing::TestWithParam<ManifestAttempt> {};

TEST_P(HostileManifest, IsRefusedByTheRuntimeAndByTheSceneLoader) {
  const ManifestAttempt& a = GetParam();
  TempMods mods;
  mods.write("bad/mod.lua", std::string(a.code) + "\nreturn { name = \"bad\", version = \"1\" }\n");
  mods.write("bad/init.lua", "return {}\n");
  mods.write("scene.lua", "world { dt = 1/100 }\nlocal bad = require 'bad'\n");
  PluginRegistry registry;
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  try {
    runtime.load("bad");
    FAIL() << "the runtime loaded it";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), a.message)) << e.what();
    EXPECT_TRUE(contains(e.what(), "bad/mod.lua")) << e.what();
  }
  lua::LoadOptions options;
  options.mod_paths = {mods.path()};
  try {
    lua::check(mods / "scene.lua", registry, options);
    FAIL() << "the scene loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), a.message)) << e.what();
    EXPECT_TRUE(contains(e.what(), "bad/mod.lua")) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Attempts, HostileManifest, ::testing::ValuesIn(kManifestAttempts),
                         [](const auto& info) {
                           std::string n;
                           for (char c : std::string(info.param.name))
                             n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

}  // namespace
}  // namespace alloy::test
