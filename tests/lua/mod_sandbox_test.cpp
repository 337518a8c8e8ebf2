// The sandbox and budgets of player mods (lua/mod_state.hpp, budget_ticks.hpp,
// stage_prelude.lua): escape and abuse attempts, each contained. The process
// lives, the world goes on, another mod's stage keeps working, and the message
// names the mod and where it was. Also: runs stay deterministic (ordered
// pairs, a seeded generator), and the budget ticks keep line numbers.
#include <gtest/gtest.h>

#include "lua/budget_ticks.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

/// The evil mod: `code` runs in its resolver's advance, at line 5.
std::string evil(const std::string& code) {
  return "mod.property { name = \"evil_mark\" }\n"
         "mod.resolver { name = \"evil.stage\", reads = { \"mass\" }, writes = { \"evil_mark\" }, "
         "needs = { \"evil_mark\" },\n"
         "  advance = function(w)\n"
         "    local mark = w:write(\"evil_mark\")\n" +
         code +
         "\n"
         "  end }\n";
}

struct Attempt {
  const char* name;
  const char* code;
  Kind outcome;         ///< StageDisabled (a Lua error) or Stopped (a budget)
  const char* message;  ///< part of the report
  bool at_line = true;  ///< the report names evil/runtime.lua:5
};

const Attempt kAttempts[] = {
    {"io", "io.open('/etc/passwd')", Kind::StageDisabled,
     "attempt to index global 'io' (a nil value)"},
    {"os", "os.execute('touch /tmp/alloy_pwned')", Kind::StageDisabled, "global 'os'"},
    {"require ffi", "local ffi = require 'ffi'", Kind::StageDisabled, "requires 'ffi'"},
    {"require a path", "require '../../etc/passwd'", Kind::StageDisabled, "paths are not allowed"},
    {"jit", "jit.off()", Kind::StageDisabled, "global 'jit'"},
    {"debug.sethook", "debug.sethook(function() end, '', 1)", Kind::StageDisabled,
     "global 'debug'"},
    {"package", "local x = package.loaded", Kind::StageDisabled, "global 'package'"},
    {"string.dump", "string.dump(function() end)", Kind::StageDisabled, "field 'dump'"},
    {"method dump", "local d = ('x').dump(print)", Kind::StageDisabled, "field 'dump'"},
    {"bytecode", "local f, e = load('\\27LJ\\2\\0\\0') error(e, 0)", Kind::StageDisabled,
     "binary chunk"},
    {"bytecode mode", "load('return 1', 'x', 'b')", Kind::StageDisabled, "only text chunks"},
    {"getfenv", "local g = getfenv(print)", Kind::StageDisabled, "global 'getfenv'"},
    {"setfenv", "setfenv(1, {})", Kind::StageDisabled, "global 'setfenv'"},
    {"string metatable", "local s = getmetatable('').__index", Kind::StageDisabled,
     "attempt to index a boolean value"},
    {"host table metatable", "setmetatable(alloy, {})", Kind::StageDisabled, "protected metatable"},
    {"host table rawset", "rawset(alloy, 'version', 'x')", Kind::StageDisabled,
     "belongs to the host"},
    {"column metatable", "getmetatable(w:read('mass')).__index = nil", Kind::StageDisabled,
     "index a string value"},
    {"column rawset", "rawset(w:read('mass'), 0, 1)", Kind::StageDisabled,
     "table expected, got userdata"},
    {"collectgarbage", "collectgarbage('stop')", Kind::StageDisabled, "global 'collectgarbage'"},
    {"newproxy", "newproxy(true)", Kind::StageDisabled, "global 'newproxy'"},
    {"reserved tick name", "local f, e = load('local __alloy_tick = 1') error(e, 0)",
     Kind::StageDisabled, "reserved for the host"},
    {"infinite loop", "while true do end", Kind::Stopped,
     "ran more than 2 million ticks (loop iterations and calls) in one step (a runaway loop?)"},
    {"goto loop", "::again:: goto again", Kind::Stopped, "a runaway loop"},
    {"loop swallowing its stop", "while true do pcall(function() while true do end end) end",
     Kind::Stopped, "runaway loop"},
    {"xpcall handler loop",
     "xpcall(function() while true do end end, function() while true do end end)", Kind::Stopped,
     "runaway loop"},
    {"loop in a coroutine", "coroutine.wrap(function() while true do end end)()", Kind::Stopped,
     "runaway loop"},
    {"loop in loaded text", "load('while true do end')()", Kind::Stopped, "runaway loop"},
    {"memory bomb", "local t = {} while true do t[#t + 1] = { 1, 2, 3 } end", Kind::Stopped,
     "memory budget of 8 MiB (an allocation bomb?)"},
    {"huge string.rep", "local s = string.rep('x', 1e9)", Kind::Stopped,
     "ran out of its memory budget of 8 MiB", false},
    {"deep recursion", "local function f() return 1 + f() end f()", Kind::StageDisabled,
     "stack overflow"},
    {"pattern bomb", "local s = ('a'):rep(5000) s:find(('a*'):rep(8) .. 'b')", Kind::Stopped,
     "string.find: the pattern took more than 10 million steps"},
    {"unpack bomb", "unpack({}, 1, 1e8)", Kind::StageDisabled, "too many results to unpack"},
    {"slot out of range", "local m = w:read('mass') local x = m[1e9]", Kind::StageDisabled,
     "no object in slot 1000000000"},
    {"write past the end", "mark[2^31] = 1", Kind::StageDisabled, "no object in slot"},
    {"NaN into a property", "for i in mark:each() do mark[i] = 0/0 end", Kind::StageDisabled,
     "must be finite"},
    {"column kept for later",
     "if w.state.keep then local x = w.state.keep[0] else w.state.keep = w:read('mass') end",
     Kind::StageDisabled, "can only be used while the stage that got it runs"},
    {"queue without a target", "w.target.add_force(0, {0, 1e9, 0})", Kind::StageDisabled,
     "index field 'target'"},
};

class Sandbox : public ::testing::TestWithParam<Attempt> {};

TEST_P(Sandbox, EachEscapeOrAbuseIsContained) {
  const Attempt& a = GetParam();
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("good", kGood);
  mods.mod("evil", evil(a.code));
  std::vector<std::string> log;
  lua::ModRuntimeOptions o = runtime_options(mods, &log);
  o.budget.memory_bytes = 8u << 20;
  o.budget.ticks_per_step = 2'000'000;
  o.budget.seconds_per_step = 2;
  lua::ModRuntime runtime(registry, o);
  runtime.load("good");
  runtime.load("evil");
  World world(registry);
  runtime.attach(world);
  const ObjectId thing = world.create("thing");
  world.set(thing, "good_count", 0.0);
  world.set(thing, "evil_mark", 0.0);
  world.run(3);

  // The world went on, and the other mod with it.
  EXPECT_EQ(world.step_count(), 3u);
  EXPECT_EQ(std::get<double>(world.get(thing, "good_count")), 3.0);
  EXPECT_FALSE(runtime.stopped("good"));
  // The evil mod was stopped or its stage disabled, with a clear message.
  std::vector<lua::ModReport> reports;
  for (auto& r : runtime.poll())
    if (r.kind == Kind::StageDisabled || r.kind == Kind::Stopped) reports.push_back(r);
  ASSERT_EQ(reports.size(), 1u) << (reports.empty() ? "nothing reported" : reports[1].message);
  const lua::ModReport& r = reports[0];
  EXPECT_EQ(r.kind, a.outcome) << r.message;
  EXPECT_EQ(r.mod, "evil");
  EXPECT_TRUE(contains(r.message, "mod 'evil'")) << r.message;
  EXPECT_TRUE(contains(r.message, a.message)) << r.message;
  if (a.at_line) {
    EXPECT_TRUE(contains(r.message, "evil/runtime.lua:5")) << r.message;
  }
  EXPECT_EQ(runtime.stopped("evil"), a.outcome == Kind::Stopped);
  EXPECT_LE(runtime.memory_of("evil"), o.budget.memory_bytes);
}

INSTANTIATE_TEST_SUITE_P(Attempts, Sandbox, ::testing::ValuesIn(kAttempts), [](const auto& info) {
  std::string n;
  for (char c : std::string(info.param.name))
    n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return n;
});

TEST(ModSandbox, AModUsingTheReservedTickNameIsRefusedAtLoad) {
  PluginRegistry registry;
  TempMods mods;
  mods.mod("sly", "local x = 1\nlocal __alloy_tick = function() end\n");
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  try {
    runtime.load("sly");
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 2) << e.what();
    EXPECT_TRUE(contains(e.what(), "reserved for the host")) << e.what();
  }
}

TEST(ModSandbox, AStoppedModComesBackWithAFreshStateAfterAReload) {
  PluginRegistry registry;
  TempMods mods;
  const std::string body = R"LUA(
mod.property { name = "n" }
mod.resolver { name = "loop.stage", writes = { "n" }, needs = { "n" },
  advance = function(w)
    w.state.calls = w.state.calls + 1
    local n = w:write("n")
    for i in n:each() do n[i] = w.state.calls end
    LOOP
  end }
function mod.on_load(state) state.calls = 0 end
)LUA";
  auto with = [&](const std::string& loop) {
    std::string s = body;
    s.replace(s.find("LOOP"), 4, loop);
    return s;
  };
  mods.mod("loop", with("if w.state.calls == 3 then while true do end end"));
  lua::ModRuntimeOptions o = runtime_options(mods, nullptr);
  o.budget.ticks_per_step = 100'000;
  lua::ModRuntime runtime(registry, o);
  runtime.load("loop");
  World world(registry);
  runtime.attach(world);
  const ObjectId x = world.create("x");
  world.set(x, "n", 0.0);
  world.run(5);
  EXPECT_TRUE(runtime.stopped("loop"));
  EXPECT_TRUE(contains(runtime.stop_reason("loop"), "loop/runtime.lua:8"))
      << runtime.stop_reason("loop");
  EXPECT_EQ(std::get<double>(world.get(x, "n")), 3.0);  // the write before the loop, then nothing
  EXPECT_TRUE(find_event(world, "mod_stopped") == nullptr);  // reported once, at step 3
  // A failed reload leaves it stopped; a good one starts it over (on_load, a new state table).
  mods.write("loop/runtime.lua", "syntax error here");
  EXPECT_EQ(runtime.reload("loop").kind, Kind::ReloadFailed);
  EXPECT_TRUE(runtime.stopped("loop"));
  mods.write("loop/runtime.lua", with(""));
  EXPECT_EQ(runtime.reload("loop").kind, Kind::Reloaded);
  EXPECT_FALSE(runtime.stopped("loop"));
  world.run(2);
  EXPECT_EQ(std::get<double>(world.get(x, "n")), 2.0);
}

// The host builds values in a mod's state outside any protected call (the
// event table a handler gets). A mod creeping up to its memory limit must be
// stopped at one of its own allocations, never make one of the host's fail:
// that would be an unprotected Lua error, thrown through the world. The limit
// is swept over a range of offsets so that the edge falls, run after run, on
// every allocation of a step, the host's included.
TEST(ModSandbox, AModAtTheEdgeOfItsMemoryCannotMakeTheHostFail) {
  const char* kCreep = R"LUA(
mod.property { name = "creep_mark" }
mod.resolver { name = "creep.stage", writes = { "creep_mark" }, needs = { "creep_mark" },
  advance = function(w)
    w.state.keep = w.state.keep or {}
    local k = w.state.keep
    k[#k + 1] = string.rep("x", 150) .. #k
    w:emit("creep_ping", { text = "a", n = #k })
  end }
mod.on("creep_ping", function(e, state) state.seen = (state.seen or 0) + 1 end)
)LUA";
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("creep", kCreep);  // alone: the budget is every mod's
  auto run = [&](std::size_t memory) {
    std::vector<std::string> log;
    lua::ModRuntimeOptions o = runtime_options(mods, &log);
    o.budget.memory_bytes = memory;
    lua::ModRuntime runtime(registry, o);
    runtime.load("creep");
    const std::size_t loaded = runtime.memory_of("creep");
    World world(registry);
    runtime.attach(world);
    const ObjectId thing = world.create("thing");
    world.set(thing, "creep_mark", 0.0);
    EXPECT_NO_THROW(world.run(150)) << "limit " << memory;
    EXPECT_EQ(world.step_count(), 150u);  // the world went on
    return std::pair{loaded, runtime.stopped("creep")};
  };
  const std::size_t loaded = run(64u << 20).first;
  int stopped = 0;
  for (std::size_t offset = 0; offset < 1024; offset += 16)
    stopped += run(loaded + (4u << 10) + offset).second ? 1 : 0;
  EXPECT_EQ(stopped, 64);  // every run reached the edge, and was stopped there
}

// An object argument that is no slot at all (negative, fractional, past any
// uint32) is refused where the mod called, before it reaches the buffer: the
// C++ side once converted -1 to an unsigned slot (UBSan, found by the mod API
// fuzzer; tests/fuzz/regressions/mod_api/ubsan_negative_object_slot_*).
TEST(ModSandbox, AnObjectArgumentThatIsNoSlotIsRefusedAtTheModsLine) {
  for (const char* slot : {"-1", "0.5", "2^40"}) {
    PluginRegistry registry;
    register_native_plugins(registry);
    TempMods mods;
    mods.mod("good", kGood);
    mods.mod("evil", std::string(R"LUA(mod.property { name = "evil_mark" }
mod.resolver { name = "evil.sink", writes = { "evil_mark" }, needs = { "evil_mark" },
  functions = { tag = { "object" } }, advance = function(w) end }
mod.interaction { name = "evil.tagger", reads = { "evil_mark" }, target = "evil.sink",
  apply = function(w) w.target.tag(w:find("thing"), )LUA") + slot + ") end }\n");
    lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
    runtime.load("good");
    runtime.load("evil");
    World world(registry);
    runtime.attach(world);
    const ObjectId thing = world.create("thing");
    world.set(thing, "good_count", 0.0);
    world.set(thing, "evil_mark", 0.0);
    world.run(3);
    EXPECT_EQ(std::get<double>(world.get(thing, "good_count")), 3.0);
    std::string reports;
    for (const auto& r : runtime.poll()) reports += r.message + "\n";
    EXPECT_TRUE(contains(reports, "'tag': no object in slot")) << slot << ": " << reports;
    EXPECT_TRUE(contains(reports, "evil/runtime.lua:5")) << slot << ": " << reports;
  }
}

TEST(ModSandbox, ModsShareNothingButTheWorld) {
  PluginRegistry registry;
  TempMods mods;
  mods.mod("a", "shared = 'from a'\nstring.upper = function() return 'hijacked' end\n");
  mods.mod("b", R"LUA(
mod.property { name = "seen" }
mod.resolver { name = "b.look", writes = { "seen" }, needs = { "seen" },
  advance = function(w)
    local s = w:write("seen")
    for i in s:each() do s[i] = (shared == nil and string.upper("x") == "X") and 1 or 0 end
  end }
)LUA");
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  runtime.load("a");
  runtime.load("b");
  World world(registry);
  runtime.attach(world);
  const ObjectId o = world.create("o");
  world.set(o, "seen", 0.0);
  world.step();
  EXPECT_EQ(std::get<double>(world.get(o, "seen")), 1.0);
}

TEST(ModSandbox, PairsIsOrderedAndRandomIsSeededSoRunsRepeat) {
  auto run = [](const std::string& mod_name) {
    PluginRegistry registry;
    TempMods mods;
    mods.mod(mod_name, R"LUA(
mod.property { name = "out", kind = "string" }
mod.resolver { name = "r", writes = { "out" }, needs = { "out" },
  advance = function(w)
    local t = { zeta = 1, alpha = 2, [3] = "c", [1] = "a", mid = 3, [2.5] = "b", [true] = 4 }
    local keys = {}
    for k in pairs(t) do keys[#keys + 1] = tostring(k) end
    local r = {}
    for i = 1, 4 do r[#r + 1] = string.format("%.6f", math.random()) end
    r[#r + 1] = tostring(math.random(1, 6))
    local o = w:write("out")
    for i in o:each() do o[i] = table.concat(keys, ",") .. "|" .. table.concat(r, ",") end
  end }
)LUA");
    lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
    runtime.load(mod_name);
    World world(registry);
    runtime.attach(world);
    const ObjectId o = world.create("o");
    world.set(o, "out", std::string());
    world.step();
    return std::get<std::string>(world.get(o, "out"));
  };
  const std::string a = run("dice"), b = run("dice"), c = run("coin");
  EXPECT_EQ(a.substr(0, a.find('|')), "1,2.5,3,alpha,mid,zeta,true");  // numbers, strings, booleans
  EXPECT_EQ(a, b);                                          // the same run, the same numbers
  EXPECT_NE(a.substr(a.find('|')), c.substr(c.find('|')));  // seeded by the mod's name
}

TEST(BudgetTicks, LoopsAndFunctionBodiesGetATickOnTheirOwnLine) {
  const std::string src =
      "local s = \"while true do\" -- do\n"
      "for i = 1, 3 do x = i end\n"
      "repeat y = 1 until y\n"
      "local function f(a, b)\n  return a\nend\n"
      "::top:: z = [[ do ]]\n"
      "local g = function(...) end\n";
  const std::string out = lua::add_budget_ticks(src, "t.lua");
  EXPECT_EQ(out,
            "return function(__alloy_tick) return function(...)"
            "local s = \"while true do\" -- do\n"
            "for i = 1, 3 do __alloy_tick(); x = i end\n"
            "repeat __alloy_tick(); y = 1 until y\n"
            "local function f(a, b) __alloy_tick();\n  return a\nend\n"
            "::top:: __alloy_tick(); z = [[ do ]]\n"
            "local g = function(...) __alloy_tick(); end\n"
            "\nend end");
  // Lines are kept: the n-th line of the source is the n-th of the result.
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), std::count(src.begin(), src.end(), '\n') + 1);
  EXPECT_THROW(lua::add_budget_ticks("local x\nlocal __alloy_tick", "t.lua"), InputError);
  // Keywords inside strings, comments and names are left alone.
  EXPECT_EQ(
      lua::add_budget_ticks("local undo, redo = 'do', [==[repeat]==] --[[ function() ]]", "t.lua"),
      "return function(__alloy_tick) return function(...)local undo, redo = 'do', [==[repeat]==] "
      "--[[ function() ]]\nend end");
}

}  // namespace
}  // namespace alloy::test

namespace alloy::test {
namespace {

TEST(ModSandbox, AManifestCannotNameFilesOutsideItsFolder) {
  PluginRegistry registry;
  TempMods mods;
  mods.write("sneaky/mod.lua",
             "return { name = \"sneaky\", version = \"1\", runtime = \"../../etc/passwd\" }\n");
  lua::ModRuntime runtime(registry, runtime_options(mods, nullptr));
  try {
    runtime.load("sneaky");
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "sneaky/mod.lua")) << e.what();
    EXPECT_TRUE(contains(e.what(), "must name a file inside the mod's folder")) << e.what();
  }
}

}  // namespace
}  // namespace alloy::test
