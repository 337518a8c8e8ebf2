// Lua binds whatever a native resolver declares (PluginDef::functions,
// runtime/interaction_function.hpp), not a list of resolvers it knows: a
// native resolver written for this test, which lua/ has never heard of,
// declares two functions, and a mod's interaction calls them per object and
// in bulk. The calls must arrive with their objects and arguments, in order;
// a native resolver that declares nothing is refused, naming those that can
// be reached.
#include <gtest/gtest.h>

#include "tests/lua/mod_test_support.hpp"

namespace alloy::test {
namespace {

/// A native resolver that only records what it is asked to do.
class Recorder final : public Resolver {
 public:
  struct Call {
    std::string fn;
    ObjectId object;
    std::vector<double> args;
  };
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess&, double) override {}
  std::vector<Call> calls;
};

PluginDef recorder_plugin() {
  PluginDef def;
  def.info = {.name = "recorder.native",
              .kind = StageKind::Resolver,
              .needs = {"recorded"},
              .doc = "records the calls it is given (test)"};
  def.properties = {PropertyDef{.name = "recorded", .doc = "test"}};
  auto rec = [](Stage& s) -> Recorder& { return static_cast<Recorder&>(s); };
  InteractionFunction push;
  push.decl = {"push", {ArgKind::Number}};
  push.call = [rec](Stage& s, ObjectId id, const double* a) {
    rec(s).calls.push_back({"push", id, {a[0]}});
  };
  InteractionFunction nudge;
  nudge.decl = {"nudge", {ArgKind::Vec3, ArgKind::Object}};
  nudge.call = [rec](Stage& s, ObjectId id, const double* a) {
    rec(s).calls.push_back({"nudge", id, {a[0], a[1], a[2], a[3]}});
  };
  def.functions = {push, nudge};
  def.create = [](PluginContext&) -> std::unique_ptr<Stage> {
    return std::make_unique<Recorder>();
  };
  return def;
}

const char* kCaller = R"LUA(
mod.interaction {
  name = "caller.each", reads = { "recorded" }, target = "recorder.native",
  apply = function(w)
    local r, t = w:read("recorded"), w.target
    local first
    for i in r:each() do
      first = first or i
      t.push(i, r[i] * 2)
      t.nudge(i, vec3(r[i], 0, -1), first)
    end
    local bulk = t.push_each(r)
    for i in r:each() do bulk[i] = -r[i] end
  end,
}
)LUA";

TEST(DeclaredTarget, LuaCallsWhatANativeResolverItDoesNotKnowDeclares) {
  PluginRegistry registry;
  register_native_plugins(registry);
  registry.add(recorder_plugin());
  TempMods mods;
  mods.mod("caller", kCaller);
  std::vector<std::string> log;
  lua::ModRuntime runtime(registry, runtime_options(mods, &log));
  runtime.load("caller");
  WorldDef wd;
  wd.plugins = {"recorder.native", "caller.each"};
  World world(registry, wd);
  std::vector<ObjectId> ids;
  for (int i = 0; i < 3; ++i) {
    ids.push_back(world.create("o" + std::to_string(i)));
    world.set(ids.back(), "recorded", double(i + 1));
  }
  runtime.attach(world);
  world.step();
  ASSERT_EQ(stage_failures(runtime), "");
  auto* rec = dynamic_cast<Recorder*>(world.stage("recorder.native"));
  ASSERT_NE(rec, nullptr);
  // The calls are performed in the target's next advance, or as the binding
  // hands them over: either way all of them, in the order they were made.
  world.step();
  ASSERT_GE(rec->calls.size(), 9u);
  std::vector<Recorder::Call> first(rec->calls.begin(), rec->calls.begin() + 9);
  for (int i = 0; i < 3; ++i) {
    const auto& p = first[std::size_t(2 * i)];
    EXPECT_EQ(p.fn, "push");
    EXPECT_EQ(p.object, ids[std::size_t(i)]);
    EXPECT_EQ(p.args, std::vector<double>({2.0 * (i + 1)}));
    const auto& n = first[std::size_t(2 * i + 1)];
    EXPECT_EQ(n.fn, "nudge");
    EXPECT_EQ(n.object, ids[std::size_t(i)]);
    ASSERT_EQ(n.args.size(), 4u);
    EXPECT_EQ(n.args[0], double(i + 1));
    EXPECT_EQ(n.args[2], -1.0);
    EXPECT_EQ(n.args[3], double(ids[0].index));  // an object argument arrives as its slot
  }
  for (int i = 0; i < 3; ++i) {  // the bulk form, after the per-object calls
    const auto& b = first[std::size_t(6 + i)];
    EXPECT_EQ(b.fn, "push");
    EXPECT_EQ(b.object, ids[std::size_t(i)]);
    EXPECT_EQ(b.args, std::vector<double>({-(i + 1.0)}));
  }
}

TEST(DeclaredTarget, ANativeResolverThatDeclaresNothingIsRefusedNamingThoseThatDo) {
  PluginRegistry registry;
  register_native_plugins(registry);
  registry.add(recorder_plugin());
  TempMods mods;
  mods.mod("quiet", R"LUA(
mod.interaction { name = "quiet.on_sound", reads = { "mass" }, target = "sound", apply = function(w) end }
)LUA");
  std::vector<std::string> log;
  lua::ModRuntime runtime(registry, runtime_options(mods, &log));
  try {
    runtime.load("quiet");
    FAIL() << "a target without functions was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "not a resolver Lua can queue on")) << m;
    EXPECT_TRUE(contains(m, "rigid_body, rigid_body.box2d, recorder.native")) << m;
  }
}

}  // namespace
}  // namespace alloy::test
