// Floods: what a hostile mod (or scene) can make the host do besides running
// its code, and the budgets that bound it (ModBudget in lua/mod_state.hpp):
// printed bytes, events, queued commands and the host memory they take, per
// step and per run, and the size of the errors it raises. Each case runs an
// evil mod beside a good one and asserts that the process lives, the good mod
// keeps stepping, what reached the log (and the world's events) is bounded,
// the host memory of the queues is bounded, and the message names the mod,
// the budget and the line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <functional>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Kind = lua::ModReport::Kind;

/// The good mod of the other hostile tests, with an event every step for the
/// evil handlers to handle.
const char* kGoodTicking = R"LUA(
mod.property { name = "good_count" }
mod.resolver {
  name = "good.counter", writes = { "good_count" }, needs = { "good_count" },
  advance = function(w)
    local c = w:write("good_count") for i in c:each() do c[i] = c[i] + 1 end
    w:emit("good_tick")  -- something for the evil handlers to handle
  end,
}
)LUA";

const std::string kMark = "mod.property { name = \"evil_mark\" }\n";

/// A resolver whose advance runs `code`.
std::string resolver(const std::string& code) {
  return "mod.resolver { name = \"evil.stage\", writes = { \"evil_mark\" }, needs = { "
         "\"evil_mark\" },\n"
         "  advance = function(w)\n" +
         code + "\n  end }\n";
}

/// `code` runs in a resolver's advance, from line 4 (`w` is its world).
std::string in_resolver(const std::string& code) {
  return kMark + resolver(code);
}

/// `code` runs in an interaction on the rigid body, from line 5, with
/// `i` the ball's slot and `add_force` the target's function.
std::string in_interaction(const std::string& code) {
  return kMark +
         "mod.interaction { name = \"evil.pusher\", reads = { \"mass\", \"evil_mark\" },\n"
         "  needs = { \"evil_mark\" }, target = \"rigid_body\", apply = function(w)\n"
         "    local i, add_force = w:find(\"ball\"), w.target.add_force\n" +
         code + "\n  end }\n";
}

/// `code` runs in a handler of every event, from line 3.
std::string in_handler(const std::string& code) {
  return kMark + "mod.on(\"*\", function(e, state)\n" + code + "\nend)\n" + resolver("");
}

struct Flood {
  const char* name;
  std::string runtime;  ///< the evil mod's runtime.lua
  Kind outcome;         ///< Stopped (a budget) or StageDisabled (an error)
  const char* message;  ///< part of the report: the budget, or the error
  int line;             ///< the line of evil/runtime.lua the report names (0: not checked)
  std::function<void(lua::ModBudget&)> tweak = {};
  int steps = 3;
};

/// Case-specific budgets: small ones make the per-run cases quick.
void small_run(lua::ModBudget& b) {
  b.print_bytes_per_run = 100u << 10;
  b.events_per_run = 2000;
  b.event_bytes_per_run = 1u << 20;
}

std::vector<Flood> floods() {
  return {
      {"print in a loop", in_resolver("    while true do print('flood') end"), Kind::Stopped,
       "printed more than 64 KiB in one step (its budget print_bytes_per_step)", 4},
      {"print of a huge string", in_resolver("    print(string.rep('x', 4e6))"), Kind::Stopped,
       "print_bytes_per_step", 4},
      {"print with many arguments",
       in_resolver("    local t = {} for k = 1, 7000 do t[k] = ('y'):rep(40) end print(unpack(t))"),
       Kind::Stopped, "print_bytes_per_step", 4},
      {"print of objects with a huge __tostring",
       in_resolver(
           "    local o = setmetatable({}, { __tostring = function() return ('z'):rep(1e6) end })\n"
           "    for k = 1, 100 do print(o, o) end"),
       Kind::Stopped, "print_bytes_per_step", 5},
      {"print swallowed by pcall",
       in_resolver("    for k = 1, 1e6 do pcall(print, ('p'):rep(1000)) end"), Kind::Stopped,
       "print_bytes_per_step", 4},
      {"print spread over many steps", in_resolver("    print(('s'):rep(10000))"), Kind::Stopped,
       "printed more than 100 KiB since it was loaded (its budget print_bytes_per_run)", 4,
       small_run, 20},
      {"print in a handler", in_handler("  for k = 1, 1e6 do print('handler', k) end"),
       Kind::Stopped, "print_bytes_per_step", 3},
      {"huge error string", in_resolver("    error(string.rep('e', 4e6))"), Kind::StageDisabled,
       "more bytes dropped", 4},
      {"huge error table with __tostring",
       in_resolver("    error(setmetatable({ message = ('m'):rep(4e6), object = ('o'):rep(1e6) },\n"
                   "      { __tostring = function() return ('t'):rep(1e6) end }))"),
       Kind::StageDisabled, "more bytes dropped", 0},
      {"huge errors from many handlers",
       kMark + "for k = 1, 50 do mod.on('*', function() error(('h'):rep(1e6)) end) end\n" +
           resolver(""),
       Kind::StageDisabled, "more bytes dropped", 2},
      {"event flood", in_resolver("    while true do w:emit('spam') end"), Kind::Stopped,
       "emitted more than 1000 events in one step (its budget events_per_step)", 4},
      {"event flood swallowed by pcall",
       in_resolver("    while true do pcall(w.emit, w, 'spam') end"), Kind::Stopped,
       "events_per_step", 4},
      {"events with huge texts",
       in_resolver(
           "    local t = ('t'):rep(1e6) for k = 1, 100 do w:emit('big', { text = t }) end"),
       Kind::Stopped,
       "emitted events of more than 256 KiB in one step (its budget event_bytes_per_step)", 4},
      {"events with many fields",
       in_resolver("    local f = {} for k = 1, 5000 do f['field_number_' .. k] = k end\n"
                   "    for k = 1, 100 do w:emit('wide', f) end"),
       Kind::Stopped, "event_bytes_per_step", 5},
      {"events spread over many steps", in_resolver("    for k = 1, 300 do w:emit('tick') end"),
       Kind::Stopped,
       "emitted more than 2000 events since it was loaded (its budget events_per_run)", 4,
       small_run, 20},
      {"4 million add_force calls",
       in_interaction("    for n = 1, 4e6 do add_force(i, vec3(0, 1, 0)) end"), Kind::Stopped,
       "it queued more than 250000 commands in one step (its budget commands_per_step)", 5},
      {"add_force calls swallowed by pcall",
       in_interaction("    for n = 1, 4e6 do pcall(add_force, i, vec3(0, 1, 0)) end"),
       Kind::Stopped, "commands_per_step", 5},
      {"add_force over the host memory budget",
       in_interaction("    for n = 1, 4e6 do add_force(i, vec3(0, 1, 0)) end"), Kind::Stopped,
       "it queued commands taking more than 1 MiB in one step (its budget command_bytes_per_step)",
       5, [](lua::ModBudget& b) { b.command_bytes_per_step = 1u << 20; }},
      {"add_force over a small command count",
       in_interaction("    for n = 1, 4e6 do add_force(i, vec3(0, 1, 0)) end"), Kind::Stopped,
       "it queued more than 1000 commands in one step (its budget commands_per_step)", 5,
       [](lua::ModBudget& b) { b.commands_per_step = 1000; }},
      {"add_force over the count in many calls",
       "mod.property { name = \"evil_mark\" }\n"
       "for k = 1, 20 do mod.interaction { name = 'evil.p' .. k, reads = { 'mass', 'evil_mark' },\n"
       "  needs = { 'evil_mark' }, target = 'rigid_body', apply = function(w)\n"
       "    local i = w:find('ball') for n = 1, 400 do w.target.add_force(i, vec3(0, 1, 0)) end\n"
       "  end } end\n",
       Kind::Stopped, "commands_per_step", 0,
       [](lua::ModBudget& b) { b.commands_per_step = 5000; }},
      {"commands queued on a Lua resolver",
       "mod.property { name = \"evil_mark\" }\n"
       "mod.resolver { name = 'evil.sink', writes = { 'evil_mark' }, needs = { 'evil_mark' },\n"
       "  functions = { push = { 'number', 'vec3', 'number', 'number' } }, advance = function(w) "
       "end }\n"
       "mod.interaction { name = 'evil.feed', reads = { 'evil_mark' }, target = 'evil.sink',\n"
       "  apply = function(w) for n = 1, 4e6 do w.target.push(0, 1, vec3(1, 2, 3), 4, 5) end end "
       "}\n",
       Kind::Stopped, "command_bytes_per_step", 5},
      {"bulk writes over and over",
       in_interaction("    local f = w.target.add_force_each(w:read('mass'))\n"
                      "    for n = 1, 1e5 do f[i] = vec3(0, n, 0) end\n"
                      "    for n = 1, 1e6 do add_force(i, vec3(0, 1, 0)) end"),
       Kind::Stopped, "commands_per_step", 7},
      // Energy reports (w:energy, docs/modding.md "Energy"): bounded, finite,
      // into the mod's own accounts only, and budgeted like events.
      {"energy reports in a loop",
       in_resolver("    while true do w:energy('sink', 'spill', 1) end"), Kind::Stopped,
       "it made more than 10000 energy reports in one step (its budget energy_reports_per_step)",
       4},
      {"energy reports swallowed by pcall",
       in_resolver("    while true do pcall(w.energy, w, 'sink', 'spill', 1) end"), Kind::Stopped,
       "energy_reports_per_step", 4},
      {"a NaN energy report", in_resolver("    w:energy('sink', 'spill', 0 / 0)"),
       Kind::StageDisabled, "w:energy 'spill': the energy must be finite", 4},
      {"an infinite energy report", in_resolver("    w:energy('source', 'spring', math.huge)"),
       Kind::StageDisabled, "w:energy 'spring': the energy must be finite", 4},
      {"an energy report of 1e300 J", in_resolver("    w:energy('store', 'tank', 1e300)"),
       Kind::StageDisabled,
       "w:energy 'tank': 1e+300 J is beyond what one report may carry (1e+09 J, its budget "
       "energy_joules)",
       4},
      {"a transfer into a native coupling",
       in_resolver("    w:energy('transfer', 'evil.own', 1) w:energy('transfer', 'magnetism', -1)"),
       Kind::StageDisabled,
       "w:energy: transfer 'magnetism' is not this stage's: a mod's stage reports a transfer only "
       "under its physics' name ('evil.stage', the name its target books its loads by) or under "
       "'evil.<name>'",
       4},
      {"a transfer named after a native physics",
       kMark + "mod.interaction { name = 'rigid_body_from_light', reads = { 'evil_mark' },\n"
               "  needs = { 'evil_mark' }, target = 'rigid_body', apply = function(w)\n"
               "    w:energy('transfer', 'light', 1) end }\n",
       Kind::StageDisabled, "w:energy: transfer 'light' belongs to the native plugin 'light'", 4},
      {"an energy report of an unknown kind", in_resolver("    w:energy('gift', 'x', 1)"),
       Kind::StageDisabled, "w:energy: the kind must be 'source', 'sink', 'store' or 'transfer'",
       4},
      {"energy accounts without end",
       in_resolver("    for k = 1, 1e6 do w:energy('sink', 'account ' .. k, 1) end"),
       Kind::StageDisabled, "already keeps 32 accounts (its budget energy_accounts_per_stage)", 4},
      {"commands queued from a handler",
       "local keep\nmod.on('*', function() for n = 1, 1e6 do keep(0, vec3(0, 1, 0)) end end)\n" +
           in_interaction("    keep = add_force"),
       Kind::StageDisabled, "can only be used while the stage that got it runs", 2},
  };
}

/// The peak resident memory of this process since the last reset, in bytes
/// (VmHWM): what the host held at its worst, queues included, whether or not
/// a budget counted it. Reset by writing 5 to /proc/self/clear_refs.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

std::uint64_t peak_resident_bytes() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) << 10;
  return 0;
}
std::uint64_t resident_bytes() {
  std::ifstream in("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  in >> size >> resident;
  return resident * std::uint64_t(::sysconf(_SC_PAGESIZE));
}
void reset_peak() {
  std::ofstream("/proc/self/clear_refs") << "5";
}

struct Seen {
  std::uint64_t log_bytes = 0;           ///< what the log callback received from evil
  std::uint64_t event_bytes = 0;         ///< of the events evil's stages published
  std::uint64_t max_events_in_step = 0;  ///< the most evil published in one step
};

class Floods : public ::testing::TestWithParam<Flood> {};

TEST_P(Floods, AreBoundedAndStopTheModNotTheWorld) {
  const Flood& f = GetParam();
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("good", kGoodTicking);
  mods.mod("evil", f.runtime);
  Seen run;
  std::vector<std::string> reports;
  lua::ModRuntimeOptions o;
  o.mod_paths = {mods.path()};
  o.log = [&](const std::string& mod, const std::string& line) {
    if (mod == "evil") run.log_bytes += line.size() + 1;
  };
  o.budget.seconds_per_step = 10;  // the wall-clock backstop is not what is tested here
  if (f.tweak) f.tweak(o.budget);
  lua::ModRuntime runtime(registry, o);
  runtime.load("good");
  runtime.load("evil");
  World world(registry);
  runtime.attach(world);
  std::uint64_t step = 0, in_step = 0;
  world.add_observer([&](const Event& e) {
    if (e.source.rfind("evil.", 0) != 0) return;
    if (e.step != step) step = e.step, in_step = 0;
    run.max_events_in_step = std::max(run.max_events_in_step, ++in_step);
    run.event_bytes += e.type.size() + e.text.size();
  });
  const ObjectId thing = world.create("thing");
  world.set(thing, "good_count", 0.0);
  world.set(thing, "evil_mark", 0.0);
  const ObjectId ball = world.create("ball");
  world.set(ball, "shape", std::string("sphere"));
  world.set(ball, "radius", 0.1);
  world.set(ball, "mass", 1.0);
  world.set(ball, "position", Vec3{0, 5, 0});
  world.set(ball, "evil_mark", 0.0);
  const std::uint64_t resident_before = resident_bytes();
  reset_peak();
  world.run(std::uint64_t(f.steps));
  const std::uint64_t peak = peak_resident_bytes();
  const std::uint64_t grown = peak - std::min(peak, resident_before);

  // The world went on, and the good mod with it.
  EXPECT_EQ(world.step_count(), std::uint64_t(f.steps));
  EXPECT_EQ(std::get<double>(world.get(thing, "good_count")), double(f.steps));
  EXPECT_FALSE(runtime.stopped("good"));
  // The evil mod: stopped (or its stage disabled), with a message naming it,
  // the budget or the cut, and its line.
  std::string text;
  bool seen = false;
  for (const auto& r : runtime.poll())
    if (r.mod == "evil" && r.kind == f.outcome) {
      seen = true;
      text += r.message + "\n";
    }
  ASSERT_TRUE(seen) << "nothing reported; stop reason: " << runtime.stop_reason("evil");
  EXPECT_EQ(runtime.stopped("evil"), f.outcome == Kind::Stopped) << text;
  EXPECT_TRUE(contains(text, "mod 'evil'")) << text;
  EXPECT_TRUE(contains(text, f.message)) << text;
  if (f.line > 0) {
    EXPECT_TRUE(contains(text, "evil/runtime.lua:" + std::to_string(f.line))) << text;
  }
  // Output bounded: the log got at most the print budget of a run and a few
  // bounded messages; the world's events at most the event budgets.
  const lua::ModBudget& b = o.budget;
  EXPECT_LE(run.log_bytes, b.print_bytes_per_run + 64 * (b.error_bytes + 1024))
      << text.substr(0, 300);
  EXPECT_LE(text.size(), 64 * (b.error_bytes + 1024));
  EXPECT_LE(run.max_events_in_step, b.events_per_step + 2);  // + the stop's own event
  EXPECT_LE(run.event_bytes, b.event_bytes_per_run + 64 * (b.error_bytes + 1024));
  // Host memory bounded: the queues never held more than the budget, and the
  // mod's state stayed within its own.
  const lua::ModState::Output out = runtime.output_of("evil");
  EXPECT_LE(out.command_bytes, b.command_bytes_per_step * std::uint64_t(f.steps));
  EXPECT_LE(out.commands, b.commands_per_step * std::uint64_t(f.steps));
  EXPECT_LE(out.print_bytes, b.print_bytes_per_run);
  EXPECT_LE(out.events, b.events_per_run);
  EXPECT_LE(runtime.memory_of("evil"), b.memory_bytes);
  // The process at its peak: its Lua states (two budgets), the queues'
  // budget and slack; without the budgets 4 million commands held 256 MB.
  // Not under AddressSanitizer, which keeps freed blocks resident in its
  // quarantine (256 MiB by default) and pads every block: there the resident
  // size says nothing of the host's use (the counters above are checked in
  // every build).
  if (!kAddressSanitizer)
    EXPECT_LE(grown, 2 * b.memory_bytes + b.command_bytes_per_step + (32u << 20)) << grown;
  RecordProperty("peak_host_bytes", std::to_string(grown));
}

INSTANTIATE_TEST_SUITE_P(Hostile, Floods, ::testing::ValuesIn(floods()), [](const auto& info) {
  std::string n;
  for (char c : std::string(info.param.name))
    n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return n;
});

/// A good mod stepping in a world of its own, and what the evil one logged.
struct Bystander {
  PluginRegistry registry;
  TempMods mods;
  std::uint64_t evil_log_bytes = 0;
  lua::ModRuntimeOptions options() {
    lua::ModRuntimeOptions o;
    o.mod_paths = {mods.path()};
    o.log = [this](const std::string& mod, const std::string& line) {
      if (mod == "evil") evil_log_bytes += line.size() + 1;
    };
    return o;
  }
  Bystander() {
    register_native_plugins(registry);
    mods.mod("good", kGoodTicking);
  }
  /// Steps a world with the good mod's object; true if it counted every step.
  bool good_keeps_stepping(lua::ModRuntime& runtime) {
    World world(registry);
    runtime.attach(world);
    const ObjectId thing = world.create("thing");
    world.set(thing, "good_count", 0.0);
    world.run(3);
    return std::get<double>(world.get(thing, "good_count")) == 3.0;
  }
};

TEST(FloodsWhileLoading, APrintLoopInTheFileOrOnLoadFailsTheLoadWithBoundedOutput) {
  for (const char* code :
       {"while true do print('loading...') end\n",
        "function mod.on_load(state)\n  while true do print(('x'):rep(100)) end\nend\n"}) {
    SCOPED_TRACE(code);
    Bystander b;
    b.mods.mod("evil", std::string("mod.property { name = \"evil_mark\" }\n") + code);
    lua::ModRuntime runtime(b.registry, b.options());
    runtime.load("good");
    try {
      runtime.load("evil");
      FAIL() << "loaded";
    } catch (const InputError& e) {
      EXPECT_TRUE(contains(e.what(),
                           "mod 'evil' stopped: it printed more than 64 KiB while loading "
                           "(its budget print_bytes_per_step)"))
          << e.what();
      EXPECT_TRUE(contains(e.what(), "evil/runtime.lua:" + std::string(code[0] == 'w' ? "2" : "3")))
          << e.what();
    }
    EXPECT_FALSE(runtime.has("evil"));
    EXPECT_LE(b.evil_log_bytes, (64u << 10) + 100);
    EXPECT_TRUE(b.good_keeps_stepping(runtime));
  }
}

TEST(FloodsWhileLoading, APrintLoopInOnReloadStopsTheModAndTheWorldGoesOn) {
  Bystander b;
  b.mods.mod("evil", "mod.property { name = \"evil_mark\" }\n");
  lua::ModRuntime runtime(b.registry, b.options());
  runtime.load("good");
  runtime.load("evil");
  b.mods.write("evil/runtime.lua",
               "mod.property { name = \"evil_mark\" }\n"
               "function mod.on_reload(state) for k = 1, 1e6 do print('again', k) end end\n");
  const lua::ModReport r = runtime.reload("evil");
  EXPECT_EQ(r.kind, Kind::Reloaded);
  EXPECT_TRUE(contains(r.message,
                       "on_reload: mod 'evil' stopped: it printed more than 64 KiB "
                       "while loading (its budget print_bytes_per_step)"))
      << r.message;
  EXPECT_TRUE(contains(r.message, "evil/runtime.lua:2")) << r.message;
  EXPECT_TRUE(runtime.stopped("evil"));
  EXPECT_LE(b.evil_log_bytes, (64u << 10) + 4096);
  EXPECT_TRUE(b.good_keeps_stepping(runtime));
}

TEST(FloodsFromScenes, APrintLoopInASceneFailsItsLoadWithBoundedOutput) {
  Bystander b;
  b.mods.write("floody/scene.lua",
               "object { name = \"a\", position = { 0, 1, 0 } }\n"
               "for i = 1, 1e8 do print(('p'):rep(1000), i) end\n");
  std::uint64_t logged = 0;
  lua::LoadOptions o;
  o.mod_log = [&](const std::string&, const std::string& line) { logged += line.size() + 1; };
  o.mod_budget.print_bytes_per_run = 256u << 10;
  try {
    lua::load_scene(b.mods / "floody/scene.lua", b.registry, o);
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(
        e.what(), "floody/scene.lua:2: the scene printed more than 256 KiB (a print in a loop?)"))
        << e.what();
  }
  EXPECT_LE(logged, (256u << 10) + 100);
  EXPECT_GT(logged, 200u << 10);  // what fitted was printed
}

}  // namespace
}  // namespace alloy::test
