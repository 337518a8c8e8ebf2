// The bulk form of interaction functions (lua/stage_prelude.lua,
// LuaStage::perform_bulk): `w.target.add_force_each(col)` gives a buffer
// indexed by slot whose entries are queued for the members of `col` when the
// call returns. It must queue exactly what one call per object queues, on
// native and Lua targets, and refuse what the per-object form refuses.
#include <gtest/gtest.h>

#include "lua/lua_stages.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

// Two forms of one field (F = -k m p on the objects with a charge), and a Lua
// resolver whose function takes one number (its bulk form, push_each).
const char* kField = R"LUA(
mod.property { name = "charge" }
mod.property { name = "level" }

mod.interaction {
  name = "field.single", reads = { "position", "mass", "charge" }, target = "rigid_body",
  apply = function(w)
    local pos, mass, q = w:read("position"), w:read("mass"), w:read("charge")
    for i in q:each() do
      w.target.add_force(i, pos[i] * (-2 * mass[i] * q[i]))
    end
  end,
}

mod.interaction {
  name = "field.bulk", reads = { "position", "mass", "charge" }, target = "rigid_body",
  apply = function(w)
    local pos, mass, q = w:read("position"), w:read("mass"), w:read("charge")
    local force = w.target.add_force_each(q)
    for i in q:each() do
      force[i] = pos[i] * (-2 * mass[i] * q[i])
    end
    assert(w.target.add_force_each(q) == force, "the same buffer within a call")
  end,
}

mod.resolver {
  name = "field.levels", writes = { "level" }, needs = { "level" },
  functions = { push = { "number" } },
  advance = function(w)
    local l = w:write("level")
    for i, x in w:commands("push") do l[i] = l[i] + x end
  end,
}

mod.interaction {
  name = "field.pusher", reads = { "level" }, target = "field.levels",
  apply = function(w)
    local l = w:read("level")
    local push = w.target.push_each("level")  -- a column may be named
    for i in l:each() do push[i] = i + 1 end
    push[0] = (push[0] or 0) + 10  -- read back and added to
  end,
}
)LUA";

class Bulk : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    mods.mod("field", kField);
    runtime = std::make_unique<lua::ModRuntime>(registry, runtime_options(mods, &log));
    runtime->load("field");
  }
  /// Spheres in a grid; every other one has a charge.
  std::unique_ptr<World> world(const std::string& stage) {
    WorldDef def;
    def.plugins = {"rigid_body", stage};
    auto w = std::make_unique<World>(registry, def);
    for (int i = 0; i < 12; ++i) {
      const ObjectId o = w->create("ball" + std::to_string(i));
      w->set(o, "shape", std::string("sphere"));
      w->set(o, "radius", 0.05);
      w->set(o, "mass", 1.0 + 0.1 * i);
      w->set(o, "position", Vec3{0.5 * (i % 4), 0.5 * (i / 4), 0.1 * i});
      if (i % 2 == 0) w->set(o, "charge", 0.5 + i);
    }
    return w;
  }
  /// Failures reported since the last call ("" if none).
  std::string failures() { return stage_failures(*runtime); }

  PluginRegistry registry;
  TempMods mods;
  std::vector<std::string> log;
  std::unique_ptr<lua::ModRuntime> runtime;
};

TEST_F(Bulk, QueuesExactlyWhatOneCallPerObjectQueues) {
  auto single = world("field.single"), bulk = world("field.bulk");
  single->run(30);
  bulk->run(30);
  EXPECT_EQ(failures(), "");
  for (int i = 0; i < 12; ++i) {
    const std::string name = "ball" + std::to_string(i);
    const Vec3 a = get<Vec3>(*single, name, "position"), b = get<Vec3>(*bulk, name, "position");
    EXPECT_EQ(a.x, b.x) << name;
    EXPECT_EQ(a.y, b.y) << name;
    EXPECT_EQ(a.z, b.z) << name;
    // Only the charged ones felt the field (no gravity here).
    const Vec3 start{0.5 * (i % 4), 0.5 * (i / 4), 0.1 * i};
    if (i == 0) continue;  // at the origin: no force either way
    EXPECT_EQ(a.x == start.x && a.y == start.y && a.z == start.z, i % 2 == 1) << name;
  }
}

TEST_F(Bulk, WorksOnALuaResolverToo) {
  WorldDef def;
  def.plugins = {"field.levels", "field.pusher"};
  World w(registry, def);
  std::vector<ObjectId> o;
  for (int i = 0; i < 3; ++i) {
    o.push_back(w.create());
    w.set(o.back(), "level", 0.0);
  }
  w.run(3);
  EXPECT_EQ(failures(), "");
  // Each performed batch adds slot + 1 to every level, and 10 more to slot 0's.
  const double batches = std::get<double>(w.get(o[1], "level")) / 2;
  EXPECT_GE(batches, 2.0);
  EXPECT_DOUBLE_EQ(std::get<double>(w.get(o[0], "level")), batches * (1 + 10));
  EXPECT_DOUBLE_EQ(std::get<double>(w.get(o[2], "level")), batches * 3);
}

TEST_F(Bulk, RefusesWhatTheSingleFormRefusesAtTheModsLine) {
  struct Case {
    const char* name;
    const char* body;  // line 5 of the mod's file
    const char* message;
  };
  const Case cases[] = {
      {"not_a_member", "local f = add(q) f[1] = vec3(1, 0, 0)",
       "slot 1 is not a member of column 'charge'"},
      {"not_a_slot", "local f = add(q) f[1e9] = vec3(1, 0, 0)", "slot 1000000000 is not a member"},
      {"not_finite", "local f = add(q) f[0] = vec3(0/0, 0, 0)", "values must be finite"},
      {"not_a_vec3", "local f = add(q) f[0] = 'up'", "must be a vec3"},
      {"no_bulk_form", "w.target.add_force_at_each(q)",
       "attempt to call field 'add_force_at_each'"},
      {"not_a_column", "add(q[0])", "takes a column the stage reads"},
      {"kept_for_later",
       "if w.state.f then w.state.f[0] = vec3(1, 0, 0) else w.state.f = add(q) end",
       "only be used in the call that got it"},
  };
  for (const Case& c : cases) {
    TempMods m;
    m.mod("bad", std::string(R"LUA(
mod.interaction {
  name = "bad.)LUA") +
                     c.name + R"LUA(", reads = { "charge" }, target = "rigid_body",
  apply = function(w) local q, add = w:read("charge"), w.target.add_force_each
    )LUA" + c.body + R"LUA(
  end,
}
mod.property { name = "charge" }
)LUA");
    PluginRegistry reg;
    register_native_plugins(reg);
    lua::ModRuntime rt(reg, runtime_options(m, &log));
    rt.load("bad");
    WorldDef def;
    def.plugins = {"rigid_body", std::string("bad.") + c.name};
    World w(reg, def);
    ObjectId charged;
    for (int i = 0; i < 2; ++i) {
      const ObjectId o = w.create();
      w.set(o, "shape", std::string("sphere"));
      w.set(o, "radius", 0.05);
      w.set(o, "mass", 1.0);
      w.set(o, "position", Vec3{1, 0, 0});
      if (i == 0) w.set(o, "charge", 1.0), charged = o;
    }
    w.run(3);
    std::string text;
    for (const auto& r : rt.poll()) text += r.message + "\n";
    EXPECT_TRUE(contains(text, c.message)) << c.name << ": " << text;
    EXPECT_TRUE(contains(text, "bad/runtime.lua:5:")) << c.name << ": " << text;
    // A failed call queues nothing: the charged ball did not move.
    EXPECT_EQ(std::get<Vec3>(w.get(charged, "position")).x, 1.0) << c.name;
  }
}

// col:each() has two forms (lua/stage_prelude.lua): members 0 .. count-1
// (every slot a member, the common case) go without a position table; any
// other list is walked through the members. Both must give exactly the
// members, in order, and a loop kept past its call must end there.
TEST(Each, GivesTheMembersInOrderWhetherTheSlotsAreDenseOrNot) {
  PluginRegistry registry;
  register_native_plugins(registry);
  TempMods mods;
  mods.mod("lister", R"LUA(
mod.property { name = "tag" }
mod.interaction {
  name = "lister", reads = { "tag" }, target = "rigid_body",
  apply = function(w)
    local kept = w.state.kept
    if kept then  -- before this call reads the column again
      local f, s, c = kept[1], kept[2], kept[3]
      local a, b, d = f(s, c), f(s, "1"), f(s, {})
      w:emit("lister.kept", { text = tostring(a) .. " " .. tostring(b) .. " " .. tostring(d) })
    end
    local t = w:read("tag")
    local seen = {}
    for i in t:each() do seen[#seen + 1] = tostring(i) end
    w:emit("lister.members", { text = table.concat(seen, " ") })
    w.state.kept = { t:each() }
  end,
}
)LUA");
  std::vector<std::string> log;
  lua::ModRuntime runtime(registry, runtime_options(mods, &log));
  runtime.load("lister");
  // Objects 0..n-1; `tagged(i)` says which carry the tag; `gone` is destroyed.
  auto members = [&](int n, bool (*tagged)(int), int gone) {
    WorldDef def;
    def.plugins = {"rigid_body", "lister"};
    World w(registry, def);
    for (int i = 0; i < n; ++i) {
      const ObjectId o = w.create("o" + std::to_string(i));
      w.set(o, "shape", std::string("sphere"));  // a body: the stage runs for the rigid body
      w.set(o, "radius", 0.05);
      w.set(o, "mass", 1.0);
      w.set(o, "position", Vec3{double(i), 0, 0});
      if (tagged(i)) w.set(o, "tag", 1.0);
    }
    if (gone >= 0) w.destroy(w.find("o" + std::to_string(gone)));  // after: no slot reused
    w.run(2);
    const Event* kept = find_event(w, "lister.kept");
    EXPECT_NE(kept, nullptr);
    if (kept) {
      EXPECT_EQ(kept->text, "nil nil nil");
    }
    const Event* e = find_event(w, "lister.members");
    return e ? e->text : std::string("(no event)");
  };
  auto all = [](int) { return true; };
  EXPECT_EQ(members(5, all, -1), "0 1 2 3 4");  // dense
  EXPECT_EQ(members(
                6, [](int i) { return i % 2 == 1; }, -1),
            "1 3 5");  // every other
  EXPECT_EQ(members(
                5, [](int i) { return i != 0; }, -1),
            "1 2 3 4");                      // from 1
  EXPECT_EQ(members(5, all, 2), "0 1 3 4");  // a hole
  EXPECT_EQ(members(
                5, [](int i) { return i < 3; }, -1),
            "0 1 2");  // dense, then none
  EXPECT_EQ(stage_failures(runtime), "");
}

}  // namespace
}  // namespace alloy::test
