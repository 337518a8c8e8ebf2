// Each mod's `state` table in snapshots (lua/state_codec.hpp, lua::ModRuntime
// save_states / prepare_states, World::add_state_owner): what a state may
// hold, its bytes, restore bit for bit, migrations (on_migrate) and the
// hostile cases, each a clear error that leaves the world and every mod's
// state as they were.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <lua.hpp>

#include "lua/lua_bridge.hpp"
#include "lua/state_codec.hpp"
#include "runtime/save_file.hpp"
#include "runtime/state_hash.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

using Bytes = std::vector<std::byte>;

// --- the codec on a bare Lua state -------------------------------------------------

class Codec : public ::testing::Test {
 protected:
  void SetUp() override {
    L = luaL_newstate();
    luaL_openlibs(L);
  }
  void TearDown() override { lua_close(L); }
  /// Runs `chunk` (which returns a table) and encodes what it returns.
  Bytes encode(const std::string& chunk, const lua::StateLimits& lim = {}) {
    push(chunk);
    lua::StackGuard g(L);
    Bytes b = lua::encode_state(L, -1, "m", lim);
    return b;
  }
  void push(const std::string& chunk) {
    if (luaL_dostring(L, chunk.c_str()) != 0) throw std::runtime_error(lua_tostring(L, -1));
  }
  std::string encode_error(const std::string& chunk, const lua::StateLimits& lim = {}) {
    const int top = lua_gettop(L);
    try {
      encode(chunk, lim);
    } catch (const InputError& e) {
      EXPECT_EQ(lua_gettop(L), top + 1) << "the encoder must leave the stack as it was";
      lua_settop(L, top);
      return e.what();
    }
    lua_settop(L, top);
    return "(no error)";
  }
  std::string check_error(const Bytes& b, const lua::StateLimits& lim = {}) {
    try {
      lua::check_state(b, "m", lim);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
  /// Decodes `b` and encodes the result again.
  Bytes round_trip(const Bytes& b) {
    lua::check_state(b, "m", {});
    std::string err;
    EXPECT_TRUE(lua::decode_state(L, b, &err)) << err;
    Bytes again = lua::encode_state(L, -1, "m", {});
    lua_pop(L, 1);
    return again;
  }
  lua_State* L = nullptr;
};

TEST_F(Codec, ExactDoublesStringsAndNestedTablesComeBackBitForBit) {
  const Bytes b = encode(R"LUA(return {
    third = 1/3, tenth = 0.1, negzero = -0.0, inf = math.huge, ninf = -math.huge,
    nan = 0/0, tiny = 4.9406564584124654e-324, big = 2^53 + 1,
    bin = "a\0b\255", yes = true, no = false,
    list = { 10, 20, { deep = { deeper = "x" } } },
    [1.5] = "a float key", [-7] = "a negative key", [math.huge] = "inf key",
  })LUA");
  EXPECT_EQ(round_trip(b), b);
  std::string err;
  ASSERT_TRUE(lua::decode_state(L, b, &err)) << err;
  lua_setglobal(L, "s");
  push(R"LUA(
    local s = s
    local function bits(x) return string.format("%a", x) end
    assert(s.third == 1/3 and s.tenth == 0.1 and 1/s.negzero == -math.huge)
    assert(s.inf == math.huge and s.ninf == -math.huge and s.nan ~= s.nan)
    assert(s.tiny == 4.9406564584124654e-324 and s.big == 2^53 + 1)
    assert(s.bin == "a\0b\255" and s.yes == true and s.no == false)
    assert(s.list[3].deep.deeper == "x" and s.list[2] == 20)
    assert(s[1.5] == "a float key" and s[-7] == "a negative key" and s[math.huge] == "inf key")
    return {})LUA");
}

TEST_F(Codec, TheSameStateGivesTheSameBytesWhateverTheInsertionOrder) {
  const Bytes a = encode(R"LUA(local t = {} for i = 1, 200 do t["k" .. i] = i; t[i] = -i end
                               return { t = t, z = 1, a = 2 })LUA");
  const Bytes b = encode(R"LUA(local t = {} for i = 200, 1, -1 do t[i] = -i; t["k" .. i] = i end
                               t.junk = 1; t.junk = nil
                               return { a = 2, t = t, z = 1 })LUA");
  EXPECT_EQ(a, b);
}

TEST_F(Codec, WhatAStateMayNotHoldIsRefusedNamingTheModAndTheKeyPath) {
  EXPECT_TRUE(contains(encode_error("return { a = { b = { 1, print } } }"),
                       "mod 'm': state.a.b[2] is a function"));
  EXPECT_TRUE(
      contains(encode_error("return { co = coroutine.create(print) }"), "state.co is a coroutine"));
  EXPECT_TRUE(contains(encode_error("return { f = io.stdout }"), "state.f is a userdata"));
  EXPECT_TRUE(contains(encode_error("return { ['odd key\\n'] = { [true] = 1 } }"),
                       "state[\"odd key\\x0a\"] has a key that is a boolean"));
  EXPECT_TRUE(
      contains(encode_error("return { t = { [{}] = 1 } }"), "state.t has a key that is a table"));
  EXPECT_TRUE(contains(encode_error("local t = { x = {} } t.x.back = t return t"),
                       "state.x.back is state again: a cycle"));
  EXPECT_TRUE(contains(encode_error("local s = {} return { a = s, b = s }"),
                       "state.b is a table already saved under another key"));
  EXPECT_TRUE(contains(
      encode_error("return { p = setmetatable({}, { __pairs = function() error('ran') end }) }"),
      "state.p has a metatable"));
  EXPECT_TRUE(contains(
      encode_error("return { i = setmetatable({}, { __index = function() error('ran') end }) }"),
      "state.i has a metatable"));
  EXPECT_TRUE(contains(encode_error("return setmetatable({}, {})"), "state has a metatable"));
  // Without the prelude's vec3 and quat (a bare Lua state), every cdata value.
  EXPECT_TRUE(contains(encode_error("return { c = require('ffi').new('int[1]') }"),
                       "state.c is a cdata value"));
  // Lua itself refuses a NaN key (t[0/0] = 1 raises), so only damaged bytes
  // can hold one: DamagedBytesAreRefused... checks the decoder refuses it.
}

TEST_F(Codec, DepthCountAndBytesAreBounded) {
  lua::StateLimits lim;
  lim.depth = 8;
  EXPECT_TRUE(contains(encode_error("local t = {} local s = t for i = 1, 10000 do s.n = {} s = s.n "
                                    "end return t",
                                    lim),
                       "state.n.n.n.n.n.n.n.n nests tables deeper than the limit of 8"));
  lim = {};
  lim.entries = 1000;
  EXPECT_TRUE(
      contains(encode_error("local t = {} for i = 1, 5000 do t[i] = i end return { t = t }", lim),
               "state.t takes the state past its limit of 1000 entries"));
  lim = {};
  lim.bytes = 100;
  EXPECT_TRUE(contains(encode_error("return { [string.rep('k', 200)] = 1 }", lim),
                       "would make the state larger than its limit of 100 bytes"));
}

// A 100 MB string (the mod's memory budget permitting): refused before a byte
// of it is copied. Most of the test's time is string.rep making it.
TEST_F(Codec, AHundredMegabyteStringIsRefusedBeforeItIsCopied) {
  // A 100 MB string: refused before a byte of it is copied.
  push("BIG = string.rep('x', 100 * 2^20) return {}");
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(contains(encode_error("return { big = BIG }"),
                       "state.big would make the state larger than its limit of 16777216 bytes"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  push("BIG = nil collectgarbage() return {}");
}

/// Bytes put together by hand, for the decoder's hostile cases.
struct Raw {
  Bytes b;
  Raw& u8(int v) {
    b.push_back(std::byte(v));
    return *this;
  }
  Raw& u64(std::uint64_t v) {
    put(v);
    return *this;
  }
  Raw& f64(double v) {
    put(v);
    return *this;
  }
  Raw& str(const std::string& s) {
    u8('s').u64(s.size());
    for (char c : s) u8(c);
    return *this;
  }
  template <class T>
  void put(T v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    b.insert(b.end(), p, p + sizeof v);
  }
};

TEST_F(Codec, DamagedBytesAreRefusedNamingTheModAndTheByte) {
  const Bytes good = encode("return { a = 1, b = 'text', c = { true, false } }");
  EXPECT_EQ(check_error(good), "(no error)");
  // Truncated anywhere: refused, never read past the end.
  for (std::size_t n = 0; n < good.size(); ++n) {
    const std::string e = check_error(Bytes(good.begin(), good.begin() + long(n)));
    EXPECT_TRUE(contains(e, "mod 'm': its saved state is damaged")) << n << ": " << e;
  }
  // Every single flipped byte is refused or reads as a valid state (a
  // number's bits, a string's text); none crashes.
  for (std::size_t i = 0; i < good.size(); ++i) {
    Bytes bad = good;
    bad[i] ^= std::byte(0xff);
    (void)check_error(bad);
  }
  Bytes trailing = good;
  trailing.push_back(std::byte(0));
  EXPECT_TRUE(contains(check_error(trailing), "1 bytes follow the end of the state"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(2).u8('{').u64(0).b), "it is in format 2"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(1).u8('n').f64(1).b), "the state is not a table"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(1).u8('{').u64(1).u8('t').u8('t').u64(0).u64(0).b),
                       "a key is neither a number nor a string"));
  EXPECT_TRUE(
      contains(check_error(Raw{}.u8(1).u8('{').u64(1).u8('n').f64(NAN).u8('t').b), "a key is NaN"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(1).u8('{').u64(2).str("b").u8('t').str("a").u8('t').b),
                       "keys out of order or repeated"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(1).u8('{').u64(2).str("a").u8('t').str("a").u8('f').b),
                       "keys out of order or repeated"));
  EXPECT_TRUE(contains(check_error(Raw{}.u8(1).u8('{').u64(~0ull).b),
                       "a table of 18446744073709551615 entries, past the end"));
  EXPECT_TRUE(
      contains(check_error(Raw{}.u8(1).u8('{').u64(1).u8('s').u64(100ull << 20).u64(0).u64(0).b),
               "a string of 104857600 bytes, past the end"));
  EXPECT_TRUE(
      contains(check_error(Raw{}.u8(1).u8('{').u64(1).str("a").u8('?').b), "an unknown value tag"));
  // Nested 10,000 deep: refused at the limit, without recursing further.
  Raw deep;
  deep.u8(1).u8('{');
  for (int i = 0; i < 10000; ++i) deep.u64(1).str("n").u8('{');
  deep.u64(0);
  EXPECT_TRUE(contains(check_error(deep.b), "tables nest deeper than the limit of 64"));
  lua::StateLimits lim;
  lim.entries = 3;
  EXPECT_TRUE(contains(check_error(encode("return { 1, 2, 3, 4 }"), lim),
                       "more entries than the limit of 3"));
  EXPECT_TRUE(contains(check_error({}), "it is empty"));
}

// --- a mod's state in a world's snapshots ----------------------------------------------

/// The counter mod: its resolver counts steps in `state` and writes what it
/// counted to `count`, so a state that did not come back shows in a property
/// (and in the state hash) at the first step after a restore.
std::string counter_runtime(const std::string& extra = "") {
  return R"LUA(
mod.property { name = "count" }
mod.resolver {
  name = "counter.tick", writes = { "count" }, needs = { "count" },
  advance = function(w, dt)
    local s = w.state
    s.n = s.n + 1
    s.sum = s.sum + dt / 3        -- an inexact double: must come back bit for bit
    s.log[#s.log + 1] = s.n % 7
    if #s.log > 5 then table.remove(s.log, 1) end
    s.v = s.v + vec3(dt / 7, 0, 1)  -- a vec3 and a quat: kept as their doubles
    s.q = s.q * quat.from_angle_z(dt)
    local c = w:write("count")
    for i in c:each() do c[i] = s.n * 1000 + s.sum + s.log[1] + s.v.x + s.q:angle_z() end
  end,
}
function mod.on_load(state)
  state.n = 0; state.sum = 0; state.log = {}; state.v = vec3(0, 0, 0); state.q = quat.identity
end
)LUA" + extra;
}

void write_counter(const TempMods& mods, const std::string& version,
                   const std::string& extra = "") {
  mods.write("counter/mod.lua", "return { name = \"counter\", version = \"" + version +
                                    "\", runtime = \"runtime.lua\" }\n");
  mods.write("counter/runtime.lua", counter_runtime(extra));
}

struct CounterWorld {
  CounterWorld(const TempMods& mods, std::vector<std::string>* log, lua::ModBudget budget = {}) {
    register_native_plugins(registry);
    auto o = runtime_options(mods, log);
    o.budget = budget;
    runtime = std::make_unique<lua::ModRuntime>(registry, std::move(o));
    runtime->load("counter");
    world = std::make_unique<World>(registry);
    runtime->attach(*world);
    jar = world->create("jar");
    world->set(jar, "count", 0.0);
    world->start();
  }
  double count() const { return std::get<double>(world->get(jar, "count")); }
  Bytes state() const { return world->snapshot().mod_states.at(0).bytes; }

  PluginRegistry registry;
  std::unique_ptr<lua::ModRuntime> runtime;
  std::unique_ptr<World> world;
  ObjectId jar;
};

TEST(ModStateSnapshot, ASnapshotHoldsEachModsStateWithItsVersion) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld c(mods, nullptr);
  c.world->run(10);
  const Snapshot s = c.world->snapshot();
  ASSERT_EQ(s.mod_states.size(), 1u);
  EXPECT_EQ(s.mod_states[0].mod, "counter");
  EXPECT_EQ(s.mod_states[0].version, "1.0");
  EXPECT_GT(s.size().bytes, s.mod_states[0].bytes.size());
}

// After a restore, stepping gives the same bits as the uninterrupted run:
// every property (state hash) and every later state.
void expect_continues(World& run, World& resumed, const Snapshot& s, int steps) {
  std::vector<StateHash> hashes;
  std::vector<Bytes> states;
  for (int i = 0; i < steps; ++i) {
    run.step();
    hashes.push_back(hash_state(run));
    states.push_back(run.snapshot().mod_states.at(0).bytes);
  }
  resumed.restore(s);
  for (int i = 0; i < steps; ++i) {
    resumed.step();
    ASSERT_EQ(hash_state(resumed).world, hashes[i].world)
        << "differs from the uninterrupted run at step " << resumed.step_count();
    ASSERT_EQ(resumed.snapshot().mod_states.at(0).bytes, states[i])
        << "the mod's state differs at step " << resumed.step_count();
  }
}

TEST(ModStateSnapshot, RestoredInTheSameWorldItContinuesBitForBit) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld c(mods, nullptr);
  c.world->run(40);
  const Snapshot s = c.world->snapshot();
  expect_continues(*c.world, *c.world, s, 300);
}

TEST(ModStateSnapshot, RestoredInAnotherWorldOfTheSameSceneItContinuesBitForBit) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld a(mods, nullptr), b(mods, nullptr);
  a.world->run(40);
  b.world->run(3);  // elsewhere, with another state
  const Snapshot s = a.world->snapshot();
  expect_continues(*a.world, *b.world, s, 300);
}

TEST(ModStateSnapshot, AVec3AndAQuatComeBackAsThemselves) {
  TempMods mods;
  write_counter(mods, "1.0", R"LUA(
mod.resolver { name = "counter.check", writes = {}, advance = function(w)
  local v, q = w.state.v, w.state.q
  assert(tostring(v):find("vec3") or type(v) == "cdata", "state.v is a " .. type(v))
  local moved = v + vec3(1, 1, 1)   -- arithmetic: a vec3, not a table
  local turned = q:rotate(vec3(1, 0, 0))
  w.state.checked = (w.state.checked or 0) + 1
end }
)LUA");
  std::vector<std::string> log;
  CounterWorld c(mods, &log);
  c.world->run(10);
  const Snapshot s = c.world->snapshot();
  c.world->run(10);
  c.world->restore(s);
  c.world->run(3);
  EXPECT_EQ(stage_failures(*c.runtime), "");
  EXPECT_TRUE(c.world->snapshot().mod_states[0].bytes != s.mod_states[0].bytes);
}

TEST(ModStateSnapshot, AStateThatCannotBeSavedRefusesTheSnapshotNamingModAndKey) {
  TempMods mods;
  write_counter(mods, "1.0", R"LUA(
mod.resolver { name = "counter.bad", writes = {}, advance = function(w)
  if w.state.n == 5 then w.state.log.cb = { fn = function() end } end
end }
)LUA");
  CounterWorld c(mods, nullptr);
  c.world->run(10);
  try {
    (void)c.world->snapshot();
    FAIL() << "a function in a mod's state was saved";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "mod 'counter': state.log.cb.fn is a function")) << e.what();
  }
}

// The state hash covers the mods' state tables: two worlds equal in every
// property, object and stage but not in one mod's state hash differently, and
// the difference is named as that mod's state alone.
TEST(ModStateHash, TwoWorldsThatDifferOnlyInAModsStateHashDifferently) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld a(mods, nullptr), b(mods, nullptr);
  a.world->run(40);
  const Snapshot at40 = a.world->snapshot();
  a.world->step();
  Snapshot mixed = at40;  // step 40's world with step 41's mod state
  mixed.mod_states = a.world->snapshot().mod_states;
  ASSERT_NE(mixed.mod_states, at40.mod_states);
  a.world->restore(at40);
  b.world->restore(mixed);
  const StateHash ha = hash_state(*a.world), hb = hash_state(*b.world);
  EXPECT_EQ(ha.columns, hb.columns);
  EXPECT_EQ(ha.objects, hb.objects);
  EXPECT_EQ(ha.schedule, hb.schedule);
  EXPECT_EQ(ha.stages, hb.stages);
  EXPECT_NE(hex(ha.world), hex(hb.world)) << "a desync in a mod's state alone went unseen";
  EXPECT_EQ(hash_differences(ha, hb), std::vector<std::string>{"state of mod 'counter'"});
  // The version is hashed too: the same bytes under another version differ.
  Snapshot renamed = at40;
  renamed.mod_states[0].version = "1.0.1";
  EXPECT_NE(hash_state(renamed).world, hash_state(at40).world);
  EXPECT_EQ(hash_state(at40).world, ha.world);
}

// --- migrations -------------------------------------------------------------------------

// Version 2 keeps its count under `ticks` and counts its migrations in the
// state itself and in a global of its Lua state (which no restore touches).
constexpr const char* kMigrate = R"LUA(
MIGRATIONS = 0
function mod.on_migrate(old, state)
  MIGRATIONS = MIGRATIONS + 1
  print("migrating from " .. old .. " (" .. MIGRATIONS .. ")")
  assert(old == "1.0", "unexpected version " .. old)
  state.migrated_from = old
  state.n = state.n + 100000       -- the count goes on, from a new base
  return state
end
)LUA";

TEST(ModStateMigration, ASnapshotOfAnotherVersionIsMigratedOnceAndOnlyOnce) {
  TempMods v1, v2;
  write_counter(v1, "1.0");
  write_counter(v2, "2.0", kMigrate);
  std::vector<std::string> log;
  CounterWorld old(v1, nullptr), now(v2, &log);
  old.world->run(40);
  const Snapshot s = old.world->snapshot();
  now.world->restore(s);
  auto migrations = [&] {
    return std::count_if(log.begin(), log.end(),
                         [](const std::string& l) { return contains(l, "migrating from 1.0"); });
  };
  EXPECT_EQ(migrations(), 1);
  now.world->step();
  EXPECT_EQ(std::floor(now.count() / 1000), 100041) << "the migrated count goes on";
  now.world->run(100);
  EXPECT_EQ(migrations(), 1) << "stepping ran the migration again";
  // A snapshot of the migrated world is of version 2.0: no migration.
  const Snapshot s2 = now.world->snapshot();
  EXPECT_EQ(s2.mod_states[0].version, "2.0");
  now.world->restore(s2);
  now.world->run(10);
  EXPECT_EQ(migrations(), 1) << "a snapshot of the new version was migrated";
  bool noted = false;
  for (const auto& r : now.runtime->poll())
    noted = noted || (r.kind == lua::ModReport::Kind::Note &&
                      contains(r.message, "state of version 1.0 migrated to 2.0"));
  EXPECT_TRUE(noted);
}

// The same migration, through a save file's bytes (MSTA section): a save
// written by version 1.0 and loaded by 2.0 migrates once, and the state and
// its version come back from the file exactly as the snapshot held them.
TEST(ModStateMigration, ASaveFileOfAnotherVersionIsMigratedOnceWhenLoaded) {
  TempMods v1, v2;
  write_counter(v1, "1.0");
  write_counter(v2, "2.0", kMigrate);
  std::vector<std::string> log;
  CounterWorld old(v1, nullptr), now(v2, &log);
  old.world->run(40);
  SaveData d;
  d.meta = describe_world(*old.world);
  d.meta.scene_name = "counter";
  d.meta.mods = {{"counter", "1.0"}};
  d.snapshot = old.world->snapshot();
  SaveData back = decode_save(encode_save(d), "counter.alloysave");
  ASSERT_EQ(back.snapshot.mod_states.size(), 1u) << "the mod's state was not in the file";
  EXPECT_EQ(back.snapshot.mod_states[0].version, "1.0");
  EXPECT_EQ(back.snapshot.mod_states[0].bytes, old.state()) << "the state changed on disk";
  std::vector<std::string> notes;
  check_save_fits(back, "counter.alloysave", *now.world, {{"counter", "2.0"}}, &notes);
  EXPECT_EQ(notes.size(), 1u) << "the version change is not noted";
  now.world->restore(back.snapshot);
  auto migrations = [&] {
    return std::count_if(log.begin(), log.end(),
                         [](const std::string& l) { return contains(l, "migrating from 1.0"); });
  };
  EXPECT_EQ(migrations(), 1);
  now.world->run(60);
  EXPECT_EQ(migrations(), 1) << "stepping ran the migration again";
  EXPECT_EQ(std::floor(now.count() / 1000), 100100) << "the migrated count goes on from 40";
  // Saved again by 2.0 and loaded by 2.0: no second migration.
  SaveData again;
  again.meta = describe_world(*now.world);
  again.meta.mods = {{"counter", "2.0"}};
  again.snapshot = now.world->snapshot();
  const SaveData back2 = decode_save(encode_save(again), "counter2.alloysave");
  EXPECT_EQ(back2.snapshot.mod_states[0].version, "2.0");
  now.world->restore(back2.snapshot);
  now.world->run(5);
  EXPECT_EQ(migrations(), 1) << "a save of the new version was migrated";
}

TEST(ModStateMigration, WithoutOnMigrateTheStateIsKeptAsItIsAndTheReportSaysSo) {
  TempMods v1, v2;
  write_counter(v1, "1.0");
  write_counter(v2, "1.1");
  CounterWorld old(v1, nullptr), now(v2, nullptr);
  old.world->run(40);
  now.world->restore(old.world->snapshot());
  EXPECT_EQ(now.state(), old.state());
  bool noted = false;
  for (const auto& r : now.runtime->poll())
    noted = noted ||
            contains(r.message, "restored as it is into version 1.1 (the mod has no on_migrate)");
  EXPECT_TRUE(noted);
}

/// Restoring `s` into `c` fails with a message containing `expected`, and
/// nothing changed: not the world, not the mod's state, not the mod's
/// standing (it goes on stepping as before).
void expect_refused_untouched(CounterWorld& c, const Snapshot& s, const std::string& expected) {
  const Snapshot before = c.world->snapshot();
  const StateHash h = hash_state(before);
  try {
    c.world->restore(s);
    ADD_FAILURE() << "restored; expected: " << expected;
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), expected)) << e.what();
  }
  EXPECT_EQ(hash_state(*c.world).world, h.world);
  EXPECT_EQ(c.world->snapshot().mod_states, before.mod_states);
  EXPECT_FALSE(c.runtime->stopped("counter")) << c.runtime->stop_reason("counter");
  const double n = c.count();
  c.world->step();
  EXPECT_GT(c.count(), n) << "the mod no longer steps";
}

struct MigrationCase {
  const char* name;
  const char* on_migrate;
  const char* expected;
};

class BadMigration : public ::testing::TestWithParam<MigrationCase> {};

TEST_P(BadMigration, IsAClearErrorNamingTheModAndChangesNothing) {
  TempMods v1, v2;
  write_counter(v1, "1.0");
  write_counter(v2, "2.0", GetParam().on_migrate);
  lua::ModBudget budget;
  budget.ticks_to_load = 2'000'000;  // a loop that never ends stops in milliseconds
  CounterWorld old(v1, nullptr), now(v2, nullptr, budget);
  old.world->run(40);
  now.world->run(7);
  const auto t0 = std::chrono::steady_clock::now();
  expect_refused_untouched(now, old.world->snapshot(), GetParam().expected);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
}

INSTANTIATE_TEST_SUITE_P(
    Hostile, BadMigration,
    ::testing::Values(
        MigrationCase{"Raises",
                      "function mod.on_migrate(old, s) s.n = -1 error('no way from ' .. old) end",
                      "mod 'counter': on_migrate(\"1.0\", state) (to version 2.0) failed: "},
        MigrationCase{"RaisesWithLine",
                      "function mod.on_migrate(old, s)\n  s.n = nil\n  local x = nil + 1\nend",
                      "runtime.lua:"},
        MigrationCase{"LoopsForever", "function mod.on_migrate(old, s) while true do end end",
                      "mod 'counter' stopped: it ran more than 2 million ticks"},
        MigrationCase{"RecursesForever",
                      "local function f() return 1 + f() end function mod.on_migrate() f() end",
                      "mod 'counter': on_migrate(\"1.0\", state)"},
        MigrationCase{"AllocatesWithoutEnd",
                      "function mod.on_migrate(old, s) local t = {} for i = 1, 1e9 do t[i] = "
                      "{i} end end",
                      "mod 'counter': on_migrate(\"1.0\", state)"},
        MigrationCase{"ReturnsANumber", "function mod.on_migrate(old, s) return 42 end",
                      "returned a number; return the state table, or nothing"},
        MigrationCase{"PutsAFunctionInTheState",
                      "function mod.on_migrate(old, s) s.log.f = print end",
                      "after on_migrate(\"1.0\", state) (to version 2.0): mod 'counter': "
                      "state.log.f is a function"},
        MigrationCase{"ReturnsATableWithAMetatable",
                      "function mod.on_migrate(old, s) return setmetatable({}, { __index = s }) "
                      "end",
                      "state has a metatable"},
        MigrationCase{"ReturnsACycle", "function mod.on_migrate(old, s) s.self = s end",
                      "state.self is state again: a cycle"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(ModStateRestore, AMissingModIsAClearErrorNamingItAndChangesNothing) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld c(mods, nullptr);
  c.world->run(20);
  Snapshot s = c.world->snapshot();
  s.mod_states.push_back({"ghost", "3.1", s.mod_states[0].bytes});
  c.world->run(5);
  expect_refused_untouched(c, s,
                           "it holds the state of mod 'ghost' (version 3.1), which is not loaded "
                           "(loaded: counter)");
}

TEST(ModStateRestore, DamagedStateBytesAreAClearErrorAndChangeNothing) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld c(mods, nullptr);
  c.world->run(20);
  Snapshot s = c.world->snapshot();
  s.mod_states[0].bytes.resize(s.mod_states[0].bytes.size() - 3);
  c.world->run(5);
  expect_refused_untouched(c, s, "mod 'counter': its saved state is damaged at byte");
  Snapshot twice = c.world->snapshot();
  twice.mod_states.push_back(twice.mod_states[0]);
  expect_refused_untouched(c, twice, "it holds the state of mod 'counter' twice");
}

TEST(ModStateRestore, AStateLargerThanTheModsMemoryIsRefusedAndChangesNothing) {
  TempMods mods;
  write_counter(mods, "1.0");
  lua::ModBudget small;
  small.memory_bytes = 4u << 20;
  CounterWorld c(mods, nullptr, small);
  c.world->run(5);
  Snapshot s = c.world->snapshot();
  // A valid state of 12 MB of text: within the byte limit, past the memory.
  Raw r;
  r.u8(1).u8('{').u64(1).str("big").u8('s').u64(12u << 20);
  r.b.resize(r.b.size() + (12u << 20), std::byte('x'));
  s.mod_states[0].bytes = r.b;
  expect_refused_untouched(c, s, "does not fit in its Lua state");
}

TEST(ModStateRestore, AModTheSnapshotDoesNotHoldStartsWithANewStateAndItsOnLoad) {
  TempMods mods;
  write_counter(mods, "1.0");
  CounterWorld c(mods, nullptr);
  c.world->run(20);
  Snapshot s = c.world->snapshot();
  s.mod_states.clear();
  c.world->run(5);
  c.world->restore(s);
  c.world->step();
  EXPECT_EQ(std::floor(c.count() / 1000), 1) << "on_load's new state, counted once";
}

// --- the magic scene ----------------------------------------------------------------

TEST(ModStateMagic, TheMagicModsStateComesBackThroughARestore) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene scene = lua::load_scene(source_path("mods/magic"), registry);
  World& w = *scene.world;
  w.start();
  w.run(600);
  const Snapshot s = w.snapshot();
  ASSERT_EQ(s.mod_states.size(), 1u);
  EXPECT_EQ(s.mod_states[0].mod, "magic");
  w.run(300);
  ASSERT_NE(w.snapshot().mod_states, s.mod_states) << "the magic mod's state never changed";
  w.restore(s);
  EXPECT_EQ(w.snapshot().mod_states, s.mod_states);
}

// Magic's stones touch (the rigid body's saved contacts) and its mod keeps a
// state: the scene continues bit for bit, mod state included in the hash.
TEST(ModStateMagic, TheMagicSceneContinuesBitForBitWithItsModState) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene scene = lua::load_scene(source_path("mods/magic"), registry);
  World& w = *scene.world;
  w.start();
  w.run(40);
  expect_continues(w, w, w.snapshot(), 300);
}

}  // namespace
}  // namespace alloy::test
