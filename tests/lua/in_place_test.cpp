// Load records written in place (lua/stage_prelude.lua record_function,
// RigidBodyResolver::open_loads): a Lua interaction on the rigid body writes
// add_force / add_torque / add_force_at straight into the body's queue. It
// must queue exactly what the same calls from C++ queue, also past the room
// first opened (the queue grows during the call); the bulk form
// (add_force_each) keeps one record per object however often it is written;
// and a call that fails after queueing must leave nothing queued.
#include <gtest/gtest.h>

#include "lua/lua_stages.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

constexpr int kBodies = 600;  // more than the first room (16 records)

const char* kLoads = R"LUA(
mod.interaction {
  name = "loads.lua", reads = { "position", "mass" }, target = "rigid_body",
  apply = function(w)
    local pos, mass, t = w:read("position"), w:read("mass"), w.target
    assert(#mass == mass:count() and #mass > 0 and type(mass) == "userdata", "a column is a userdata with a length")
    for i in mass:each() do
      local p = pos[i]
      if i % 3 == 0 then t.add_force(i, p * (-2 * mass[i]))
      elseif i % 3 == 1 then t.add_torque(i, vec3(0, 0, 0.01 * mass[i]))
      else t.add_force_at(i, vec3(0.5, 0, 0), p + vec3(0, 0.01, 0)) end
    end
  end,
}

mod.interaction {
  name = "loads.bulk", reads = { "position", "mass" }, target = "rigid_body",
  apply = function(w)
    local pos, mass = w:read("position"), w:read("mass")
    local force, torque = w.target.add_force_each(mass), w.target.add_torque_each(mass)
    for i in mass:each() do
      if i % 3 == 0 then
        force[i] = vec3(1e3, 0, 0)  -- overwritten: one record, the last value
        force[i] = pos[i] * (-2 * mass[i])
        assert(force[i] == pos[i] * (-2 * mass[i]), "a value reads back")
      elseif i % 3 == 1 then
        torque[i] = vec3(0, 0, 0.01 * mass[i])
      else
        assert(force[i] == nil, "nothing written yet")
      end
    end
  end,
}

mod.interaction {
  name = "loads.fails", reads = { "mass" }, target = "rigid_body",
  apply = function(w)
    local mass = w:read("mass")
    for i in mass:each() do w.target.add_force(i, vec3(100, 0, 0)) end
    error("after queueing")
  end,
}
)LUA";

/// The same loads from C++, through the rigid body's own functions.
class LoadsCpp final : public Interaction {
 public:
  LoadsCpp(rigid::RigidBodyResolver& rigid, bool bulk) : rigid_(rigid), bulk_(bulk) {}
  void apply(const WorldView& w) override {
    const auto pos = w.column<Vec3>(w.property("position"));
    const auto mass = w.column<double>(w.property("mass"));
    for (std::uint32_t s : mass.members()) {
      const ObjectId id = w.store().id_at(s);
      const Vec3 p = pos[s];
      if (s % 3 == 0)
        rigid_.add_force(id, p * (-2 * mass[s]));
      else if (s % 3 == 1)
        rigid_.add_torque(id, Vec3{0, 0, 0.01 * mass[s]});
      else if (!bulk_)
        rigid_.add_force(id, Vec3{0.5, 0, 0}, p + Vec3{0, 0.01, 0});
    }
  }

 private:
  rigid::RigidBodyResolver& rigid_;
  bool bulk_;  // as loads.bulk: no forces at a point
};

class InPlace : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    for (bool bulk : {false, true}) {
      PluginDef def;
      def.info = {.name = bulk ? "loads.cpp_bulk" : "loads.cpp",
                  .kind = StageKind::Interaction,
                  .reads = {"position", "mass"},
                  .target = "rigid_body"};
      def.create = [bulk](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<LoadsCpp>(ctx.target<rigid::RigidBodyResolver>(), bulk);
      };
      registry.add(std::move(def));
    }
    mods.mod("loads", kLoads);
    runtime = std::make_unique<lua::ModRuntime>(registry, runtime_options(mods, &log));
    runtime->load("loads");
  }
  std::unique_ptr<World> world(const std::string& stage) {
    WorldDef def;
    def.plugins = {"rigid_body", stage};
    auto w = std::make_unique<World>(registry, def);
    for (int i = 0; i < kBodies; ++i) {
      const ObjectId o = w->create("ball" + std::to_string(i));
      w->set(o, "shape", std::string("sphere"));
      w->set(o, "radius", 0.05);
      w->set(o, "mass", 1.0 + 0.01 * (i % 13));
      w->set(o, "position", Vec3{0.5 * (i % 25), 0.5 * (i / 25), 0});
    }
    return w;
  }
  /// Runs both and expects the same poses, body by body.
  void same_as(const std::string& lua_stage, const std::string& cpp_stage);
  std::string failures() { return stage_failures(*runtime); }

  PluginRegistry registry;
  TempMods mods;
  std::vector<std::string> log;
  std::unique_ptr<lua::ModRuntime> runtime;
};

TEST_F(InPlace, QueuesExactlyWhatTheRigidBodysOwnFunctionsQueue) {
  same_as("loads.lua", "loads.cpp");
}

TEST_F(InPlace, TheBulkFormKeepsOneRecordPerObject) {
  same_as("loads.bulk", "loads.cpp_bulk");
}

void InPlace::same_as(const std::string& lua_stage, const std::string& cpp_stage) {
  auto lua = world(lua_stage), cpp = world(cpp_stage);
  lua->run(20);
  cpp->run(20);
  EXPECT_EQ(failures(), "");
  int moved = 0, turned = 0;
  for (int i = 0; i < kBodies; ++i) {
    const std::string name = "ball" + std::to_string(i);
    const Vec3 a = get<Vec3>(*lua, name, "position"), b = get<Vec3>(*cpp, name, "position");
    EXPECT_EQ(a.x, b.x) << name;
    EXPECT_EQ(a.y, b.y) << name;
    EXPECT_EQ(a.z, b.z) << name;
    const Quat qa = get<Quat>(*lua, name, "orientation"), qb = get<Quat>(*cpp, name, "orientation");
    EXPECT_EQ(qa.w, qb.w) << name;
    EXPECT_EQ(qa.z, qb.z) << name;
    const Vec3 start{0.5 * (i % 25), 0.5 * (i / 25), 0};
    moved += a.x != start.x || a.y != start.y;
    turned += qa.w != 1;
  }
  // Every kind of load took effect: forces moved bodies, torques turned them.
  EXPECT_GT(moved, kBodies / 4);
  EXPECT_GT(turned, kBodies / 4);
}

TEST_F(InPlace, AFailedCallLeavesNothingQueued) {
  auto w = world("loads.fails");
  w->run(3);
  EXPECT_TRUE(contains(failures(), "after queueing"));
  for (int i = 0; i < kBodies; i += 37) {
    const std::string name = "ball" + std::to_string(i);
    EXPECT_EQ(get<Vec3>(*w, name, "position").x, 0.5 * (i % 25)) << name;
  }
}

}  // namespace
}  // namespace alloy::test
