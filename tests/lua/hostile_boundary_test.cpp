// Memory safety across the Lua boundary (docs/architecture.md, "The Lua
// boundary: no borrowed pointer while Lua runs"): hostile mods that try to
// make the host write through a pointer it lent for a call that is over, or
// that moved. Coroutines suspended inside the metamethods of an argument and
// resumed later (from an event handler, the next step, another stage, after
// a reload), interaction functions re-entered from such metamethods, errors
// thrown from them, and handles (columns, buffers, iterators, `w`, lone
// functions) kept past their call.
//
// Each case asserts: the process lives (a crash ends the test binary), the
// world goes on (a second, well-behaved mod keeps counting), the evil mod's
// write had no effect on an object it aimed at (the victim: no velocity, no
// spin, its Lua properties untouched), and the report names the mod, and the
// file and line of the evil call.
#include <gtest/gtest.h>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

// The first lines of every evil mod: its properties, and a table whose every
// field read yields (then gives `v`).
const std::string kPreamble =
    "mod.property { name = \"probe\" }\n"
    "mod.property { name = \"sink\" }\n"
    "mod.property { name = \"aim\", kind = \"vec3\" }\n"
    "local function yielding(v) return setmetatable({}, { __index = function() "
    "coroutine.yield() return v end }) end\n";

// Resumes `co` for as long as it is suspended, failing with its error.
const char* kResumeOnEvents = R"LUA(
mod.on("*", function(e) while co and coroutine.status(co) == "suspended" do assert(coroutine.resume(co)) end end)
)LUA";

struct Hostile {
  const char* name;
  std::string code;  ///< the evil mod's runtime.lua after kPreamble; "--@" marks the line reported
  const char* message;  ///< part of the report
  std::string reload;   ///< if set, runtime.lua becomes kPreamble + this after step 2, reloaded
  bool ball_pushed = false;  ///< a legitimate force on "ball" must have acted
};

// The interaction most cases use: on the rigid body, run while an object has a probe.
std::string interaction(const std::string& apply, const std::string& reads = "\"probe\"") {
  return "mod.interaction { name = \"rigid_body_from_probe\", reads = { " + reads +
         " }, needs = { \"probe\" }, target = \"rigid_body\",\n  apply = function(w)\n" + apply +
         "\n  end }\n";
}

// A Lua resolver of the evil mod with interaction functions kick(i, vec3)
// and nudge(i, number) that add to `sink`, and an interaction on it.
std::string on_sink(const std::string& apply) {
  return "mod.resolver { name = \"evil.sink\", writes = { \"sink\" }, needs = { \"sink\" },\n"
         "  functions = { kick = { \"vec3\" }, nudge = { \"number\" } },\n"
         "  advance = function(w) local s = w:write(\"sink\")\n"
         "    for i, v in w:commands(\"kick\") do s[i] = s[i] + v.x end\n"
         "    for i, x in w:commands(\"nudge\") do s[i] = s[i] + x end end }\n"
         "mod.interaction { name = \"evil.kicker\", reads = { \"probe\" }, needs = { \"probe\" }, "
         "target = \"evil.sink\",\n  apply = function(w)\n" +
         apply + "\n  end }\n";
}

const char* kNoMetamethod = "host functions run no metamethod";
const char* kNotInCall = "can only be used while the stage that got it runs";

std::vector<Hostile> cases() {
  std::vector<Hostile> c;
  // --- coroutines suspended inside an argument's conversion ----------------------
  c.push_back({"yield in add_force's vec3, resumed from an event handler (issue 18)",
               "local co\n" + interaction(R"LUA(
    w:emit("poke")
    if co then return end
    co = coroutine.create(function()
      w.target.add_force(w:find("victim"), yielding(1e6)) --@
    end)
    assert(coroutine.resume(co)))LUA") +
                   kResumeOnEvents,
               kNoMetamethod});
  c.push_back({"yield in add_force_at's point, resumed from an event handler",
               "local co\n" + interaction(R"LUA(
    w:emit("poke")
    if co then return end
    co = coroutine.create(function()
      w.target.add_force_at(w:find("victim"), vec3(1e6, 0, 0), yielding(0)) --@
    end)
    assert(coroutine.resume(co)))LUA") +
                   kResumeOnEvents,
               kNoMetamethod});
  c.push_back({"yield in add_torque's vec3, resumed in the next steps' calls", interaction(R"LUA(
    local s = w.state
    if s.co then if coroutine.status(s.co) == "suspended" then assert(coroutine.resume(s.co)) end return end
    s.co = coroutine.create(function()
      w.target.add_torque(w:find("victim"), yielding(1e6)) --@
    end)
    assert(coroutine.resume(s.co)))LUA"),
               kNoMetamethod});
  c.push_back({"yield in add_force_at's point, resumed after the queue grew and moved",
               interaction(R"LUA(
    local s, t, ball = w.state, w.target, w:find("ball")
    if s.co then
      for k = 1, 300 do t.add_force(ball, vec3(0, 0, 0)) end
      if coroutine.status(s.co) == "suspended" then assert(coroutine.resume(s.co)) end
      return
    end
    for k = 1, 40 do t.add_force(ball, vec3(0, 0, 0)) end
    s.co = coroutine.create(function() t.add_force_at(w:find("victim"), vec3(1e6, 0, 0), yielding(0)) end) --@
    assert(coroutine.resume(s.co)))LUA"),
               kNoMetamethod});
  c.push_back({"yield in a write to add_force_each's buffer, resumed from an event handler",
               "local co\n" +
                   interaction(R"LUA(
    w:emit("poke")
    if co then return end
    local f = w.target.add_force_each(w:read("mass"))
    co = coroutine.create(function() f[w:find("victim")] = yielding(1e6) end) --@
    assert(coroutine.resume(co)))LUA",
                               "\"probe\", \"mass\"") +
                   kResumeOnEvents,
               kNoMetamethod});
  c.push_back({"yield in a Lua resolver's vec3 argument, resumed after its buffer grew",
               "local co, pokes = nil, 0\n" + on_sink(R"LUA(
    w:emit("poke")
    if co then for k = 1, 3000 do w.target.kick(w:find("ball"), vec3(0, 0, 0)) end return end
    co = coroutine.create(function() w.target.kick(w:find("victim"), yielding(1)) end) --@
    assert(coroutine.resume(co)))LUA") +
                   R"LUA(
mod.on("poke", function(e)
  pokes = pokes + 1
  if pokes >= 2 then while co and coroutine.status(co) == "suspended" do assert(coroutine.resume(co)) end end
end)
)LUA",
               kNoMetamethod});
  c.push_back({"yield in a write to a Lua resolver's bulk buffer, resumed from an event handler",
               "local co\n" + on_sink(R"LUA(
    w:emit("poke")
    if co then return end
    local f = w.target.kick_each(w:read("probe"))
    co = coroutine.create(function() f[0] = yielding(1e6) end) --@
    assert(coroutine.resume(co)))LUA") +
                   kResumeOnEvents,
               kNoMetamethod});
  c.push_back({"yield in a derived set's vec3 output, resumed from an event handler", R"LUA(local co
mod.derived { name = "evil.field", reads = { "probe" }, provides = { push = "vec3" },
  update = function(w)
    if co then return end
    local out = w:output("push")
    co = coroutine.create(function() out[w:find("victim")] = yielding(1) end) --@
    assert(coroutine.resume(co))
  end }
mod.interaction { name = "rigid_body_from_field", reads = { "probe" }, derived = { "evil.field" },
  target = "rigid_body", apply = function(w) w:emit("poke") end }
)LUA" + std::string(kResumeOnEvents),
               kNoMetamethod});
  c.push_back({"yield in a resolver's vec3 property write, resumed from an event handler",
               R"LUA(local co
mod.resolver { name = "evil.aimer", writes = { "aim" }, needs = { "aim" },
  advance = function(w)
    w:emit("poke")
    if co then return end
    local a = w:write("aim")
    co = coroutine.create(function() a[w:find("victim")] = yielding(1e6) end) --@
    assert(coroutine.resume(co))
  end }
)LUA" + std::string(kResumeOnEvents),
               kNoMetamethod});
  c.push_back({"a number argument given as a table whose fields yield", on_sink(R"LUA(
    local co = coroutine.wrap(function() w.target.nudge(w:find("victim"), yielding(1e6)) end) --@
    co())LUA"),
               "'nudge' takes a number, got table"});
  c.push_back({"the object given as a table whose metamethods yield", interaction(R"LUA(
    local y = function() coroutine.yield() return true end
    local slot = setmetatable({}, { __index = y, __lt = y, __le = y, __eq = y })
    local co = coroutine.wrap(function() w.target.add_force(slot, vec3(1e6, 0, 0)) end) --@
    co())LUA"),
               "takes an object (a slot number) first, got table"});
  c.push_back({"a coroutine suspended in add_force's argument, resumed by another stage",
               "local co\n" + interaction(R"LUA(
    if co then return end
    co = coroutine.create(function() w.target.add_force(w:find("victim"), yielding(1e6)) end) --@
    assert(coroutine.resume(co)))LUA") +
                   R"LUA(
mod.interaction { name = "evil.resumer", reads = { "probe" }, needs = { "probe" }, target = "rigid_body",
  apply = function(w) while co and coroutine.status(co) == "suspended" do assert(coroutine.resume(co)) end end }
)LUA",
               kNoMetamethod});
  c.push_back({"a coroutine suspended in add_force's argument, kept across a reload",
               interaction(R"LUA(
    local s = w.state
    if s.co then return end
    s.co = coroutine.create(function() w.target.add_force(w:find("victim"), yielding(1e6)) end) --@
    assert(coroutine.resume(s.co)))LUA"),
               kNoMetamethod,
               interaction(R"LUA(
    local co = w.state.co
    while co and coroutine.status(co) == "suspended" do assert(coroutine.resume(co)) end)LUA",
                           "\"probe\", \"mass\"")});
  // --- re-entry and errors from inside a conversion ------------------------------------
  c.push_back({"add_force re-entered from the metamethod of add_force_at's point",
               interaction(R"LUA(
    local t, victim = w.target, w:find("victim")
    for k = 1, 15 do t.add_force(w:find("ball"), vec3(0, 0, 0)) end
    local p = setmetatable({}, { __index = function()
      for k = 1, 1000 do t.add_force(victim, vec3(1e3, 0, 0)) end
      return 0
    end })
    t.add_force_at(victim, vec3(1, 0, 0), p) --@)LUA"),
               kNoMetamethod});
  c.push_back({"a Lua resolver's function re-entered from its own argument's metamethod",
               on_sink(R"LUA(
    local t, victim = w.target, w:find("victim")
    local v = setmetatable({}, { __index = function()
      for k = 1, 3000 do t.kick(victim, vec3(1, 0, 0)) end
      return 1
    end })
    t.kick(victim, v) --@)LUA"),
               kNoMetamethod});
  c.push_back({"an error from a metamethod mid-conversion, caught by pcall, and the call goes on",
               interaction(R"LUA(
    local s, t = w.state, w.target
    local p = setmetatable({}, { __index = function() error("boom") end })
    local ok, err = pcall(function() t.add_force_at(w:find("victim"), vec3(1e6, 0, 0), p) end) --@
    assert(not ok)
    t.add_force(w:find("ball"), vec3(50, 0, 0))
    s.err, s.n = s.err or err, (s.n or 0) + 1
    if s.n == 3 then error(s.err, 0) end)LUA"),
               kNoMetamethod, "", true});
  c.push_back({"a runaway metamethod inside add_force's argument", interaction(R"LUA(
    local v = setmetatable({}, { __index = function() while true do end end })
    w.target.add_force(w:find("victim"), v) --@)LUA"),
               kNoMetamethod});
  // --- handles kept past their call --------------------------------------------------
  c.push_back({"a column kept and read in an event handler", interaction(R"LUA(
    w.state.col = w:read("probe")
    w:emit("poke"))LUA") + R"LUA(
mod.on("poke", function(e, state) local x = state.col[0] end) --@
)LUA",
               kNotInCall});
  c.push_back({"add_force_each's buffer kept and written in an event handler",
               interaction(R"LUA(
    w.state.victim = w:find("victim")
    w.state.buf = w.target.add_force_each(w:read("mass"))
    w:emit("poke"))LUA",
                           "\"probe\", \"mass\"") +
                   R"LUA(
mod.on("poke", function(e, state) state.buf[state.victim] = vec3(1e6, 0, 0) end) --@
)LUA",
               "a buffer can only be used in the call that got it"});
  c.push_back({"add_force_each's buffer kept and written in a later step",
               interaction(R"LUA(
    local s = w.state
    if s.buf then s.buf[w:find("victim")] = vec3(1e6, 0, 0) return end --@
    s.buf = w.target.add_force_each(w:read("mass")))LUA",
                           "\"probe\", "
                           "\"mass\""),
               "a buffer can only be used in the call that got it"});
  c.push_back({"a commands iterator kept and resumed in an event handler", R"LUA(
mod.resolver { name = "evil.sink", writes = { "sink" }, needs = { "sink" }, functions = { kick = { "vec3" } },
  advance = function(w) w.state.it = w:commands("kick") w:emit("poke") end }
mod.interaction { name = "evil.kicker", reads = { "probe" }, needs = { "probe" }, target = "evil.sink",
  apply = function(w) w.target.kick(w:find("ball"), vec3(1, 0, 0)) end }
mod.on("poke", function(e, state) if state.it then local i, v = state.it() end end) --@
)LUA",
               "commands can only be read in the call that got them"});
  c.push_back({"a contacts iterator kept and resumed in an event handler", R"LUA(
mod.interaction { name = "rigid_body_from_probe", reads = { "probe" }, needs = { "probe" },
  derived = { "collisions" }, target = "rigid_body",
  apply = function(w) w.state.it = w:contacts("touching") w:emit("poke") end }
mod.on("poke", function(e, state) local a, b = state.it() end) --@
)LUA",
               "contacts can only be read in the call that got them"});
  c.push_back({"w kept and used in an event handler", interaction(R"LUA(
    w.state.w = w
    w:emit("poke"))LUA") + R"LUA(
mod.on("poke", function(e, state) local v = state.w:find("victim") end) --@
)LUA",
               "w:find can only be used while the stage that got it runs"});
  c.push_back({"add_force from a coroutine kept across a reload that re-created its stage",
               interaction(R"LUA(
    local s = w.state
    if s.co then return end
    local victim = w:find("victim")
    s.co = coroutine.wrap(function()
      coroutine.yield()
      w.target.add_force(victim, vec3(1e6, 0, 0)) --@
    end)
    s.co())LUA"),
               "'add_force' can only be used while the stage that got it runs",
               interaction("    local co = w.state.co if co then w.state.co = nil co() end",
                           "\"probe\", \"mass\"")});
  c.push_back({"lone functions of a re-created stage, used after the collector ran",
               interaction(R"LUA(
    local s = w.state
    if not s.find then s.find, s.each = w.find, w:read("probe").each end)LUA"),
               "w:find can only be used while the stage that got it runs",
               interaction(R"LUA(
    local s = w.state
    for k = 1, 300000 do local t = { k, k, k, k } end  -- garbage: a full cycle of the collector
    s.fill = {}  -- memory that the freed stage's data would go to, all bytes 1
    for k = 1, 4000 do s.fill[k] = string.rep("\1", 80 + k % 64) .. k end
    for i in s.each() do w.target.add_force(w:find("victim"), vec3(1e6, 0, 0)) end
    s.find(nil, "victim") --@)LUA",
                           "\"probe\", \"mass\"")});
  c.push_back({"the host's error metatable changed for every later error", interaction(R"LUA(
    local ok, err = pcall(function() w:emit("x", { a = 1e9 }) end)
    assert(not ok and type(err) == "table", "the host raised an error table")
    getmetatable(err).__tostring = function() return "hijacked" end --@)LUA"),
               "attempt to index"});
  return c;
}

void PrintTo(const Hostile& h, std::ostream* os) {
  *os << h.name;
}

int marked_line(const std::string& code) {
  const auto at = code.find("--@");
  if (at == std::string::npos) return 0;
  return 1 + int(std::count(code.begin(), code.begin() + std::ptrdiff_t(at), '\n'));
}

class HostileBoundary : public ::testing::TestWithParam<Hostile> {};

TEST_P(HostileBoundary, IsContained) {
  const Hostile& h = GetParam();
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("good", kGood);
  mods.mod("evil", kPreamble + h.code);
  std::vector<std::string> log;
  lua::ModRuntime runtime(registry, runtime_options(mods, &log));
  runtime.load("good");
  runtime.load("evil");
  World world(registry);
  runtime.attach(world);
  const ObjectId thing = world.create("thing");
  world.set(thing, "good_count", 0.0);
  world.set(thing, "probe", 0.0);
  auto ball_at = [&](const char* name, Vec3 at) {
    const ObjectId b = world.create(name);
    world.set(b, "shape", std::string("sphere"));
    world.set(b, "radius", 0.1);
    world.set(b, "mass", 1.0);
    world.set(b, "position", at);
    world.set(b, "velocity", Vec3{});
    world.set(b, "angular_velocity", Vec3{});
    world.set(b, "sink", 0.0);
    world.set(b, "aim", Vec3{});
    return b;
  };
  const ObjectId ball = ball_at("ball", Vec3{0, 0.1, 0});
  const ObjectId victim = ball_at("victim", Vec3{5, 0.1, 0});
  const ObjectId floor = world.create("floor");
  world.set(floor, "shape", std::string("box"));
  world.set(floor, "size", Vec3{1, 0.1, 1});
  world.set(floor, "static", true);
  world.set(floor, "position", Vec3{0, -0.05, 0});

  constexpr int kSteps = 6;
  std::vector<lua::ModReport> failures;
  for (int s = 0; s < kSteps; ++s) {
    world.step();
    for (auto& r : runtime.poll())
      if (r.kind == Kind::StageDisabled || r.kind == Kind::Stopped) failures.push_back(r);
    if (s == 1 && !h.reload.empty()) {
      mods.write("evil/runtime.lua", kPreamble + h.reload);
      const lua::ModReport r = runtime.reload("evil");
      ASSERT_EQ(r.kind, Kind::Reloaded) << r.message;
    }
  }

  // The process lives and the world goes on, the good mod with it.
  EXPECT_EQ(world.step_count(), std::uint64_t(kSteps));
  EXPECT_EQ(std::get<double>(world.get(thing, "good_count")), double(kSteps));
  EXPECT_FALSE(runtime.stopped("good"));
  // The victim felt nothing: no push, no spin, its Lua properties as they were.
  const auto v = std::get<Vec3>(world.get(victim, "velocity"));
  const auto spin = std::get<Vec3>(world.get(victim, "angular_velocity"));
  const auto at = std::get<Vec3>(world.get(victim, "position"));
  EXPECT_EQ(v.x, 0.0);
  EXPECT_EQ(v.z, 0.0);
  EXPECT_EQ(spin, Vec3{});
  EXPECT_EQ(at.x, 5.0);
  EXPECT_EQ(std::get<double>(world.get(victim, "sink")), 0.0);
  EXPECT_EQ(std::get<Vec3>(world.get(victim, "aim")), Vec3{});
  if (h.ball_pushed) {
    EXPECT_GT(std::get<Vec3>(world.get(ball, "velocity")).x, 0.01);
  }
  // The evil mod's failure, reported with the mod, the file and the line.
  ASSERT_FALSE(failures.empty()) << "nothing reported";
  for (const auto& r : failures) EXPECT_EQ(r.mod, "evil") << r.message;
  const lua::ModReport& r = failures.front();
  EXPECT_TRUE(contains(r.message, "mod 'evil'")) << r.message;
  EXPECT_TRUE(contains(r.message, h.message)) << r.message;
  int line = marked_line(kPreamble + h.code);
  if (line == 0) line = marked_line(kPreamble + h.reload);
  ASSERT_GT(line, 0) << "the case marks no line";
  EXPECT_TRUE(contains(r.message, "evil/runtime.lua:" + std::to_string(line) + ":")) << r.message;
}

INSTANTIATE_TEST_SUITE_P(Cases, HostileBoundary, ::testing::ValuesIn(cases()),
                         [](const auto& info) {
                           std::string n;
                           for (char ch : std::string(info.param.name))
                             n += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
                           return n;
                         });

}  // namespace
}  // namespace alloy::test
