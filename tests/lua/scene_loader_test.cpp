// lua/scene_loader: world settings, names, the mod search path, mods and
// their manifests, and the errors of loading that are not about one object.
#include "lua/scene_loader.hpp"

#include <gtest/gtest.h>

#include "resolvers/plugins.hpp"
#include "tests/lua/lua_test_support.hpp"

namespace alloy::lua {
namespace {

using test::get;
using test::source_path;

class SceneLoaderTest : public ::testing::Test {
 protected:
  void SetUp() override { register_native_plugins(registry); }

  /// The InputError of loading `relative`, or a failure if it loads.
  InputError load_error(const std::string& relative, const LoadOptions& options = {}) {
    try {
      load_scene(source_path(relative), registry, options);
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << relative << " loaded without error";
    return InputError("none");
  }

  PluginRegistry registry;
};

TEST_F(SceneLoaderTest, WorldSettingsBecomeTheWorldDef) {
  LoadedScene s = load_scene(source_path("tests/lua/scenes/settings.lua"), registry);
  EXPECT_EQ(s.name, "moon");
  EXPECT_EQ(s.description, "low gravity");
  EXPECT_DOUBLE_EQ(s.seconds, 2.5);
  EXPECT_DOUBLE_EQ(s.def.dt, 1.0 / 120);
  EXPECT_DOUBLE_EQ(s.world->dt(), 1.0 / 120);
  EXPECT_EQ(s.def.plugins,
            (std::vector<std::string>{"rigid_body", "gravity.uniform", "rigid_body_from_gravity"}));
  const PluginSettings& g = s.def.settings.at("gravity.uniform");
  EXPECT_EQ(g.vec3("g", {}), (Vec3{0, -1.62, 0}));  // {x, y}: z = 0
  EXPECT_EQ(g.where.line, 2);
  EXPECT_EQ(s.def.every.at("gravity.uniform"), 2);
  EXPECT_DOUBLE_EQ(get<double>(*s.world, "rock", "mass"), 2);
}

TEST_F(SceneLoaderTest, DefaultsWithoutWorldStatement) {
  LoadedScene s = load_scene(source_path("tests/lua/scenes/no_world.lua"), registry);
  EXPECT_EQ(s.name, "no_world");
  EXPECT_DOUBLE_EQ(s.seconds, 0);
  EXPECT_DOUBLE_EQ(s.def.dt, WorldDef{}.dt);
  EXPECT_TRUE(s.world->find("lonely"));
  EXPECT_EQ(s.world->step_count(), 0u);  // loaded, not started
}

TEST_F(SceneLoaderTest, ExtraModFoldersAreSearched) {
  const InputError e = load_error("tests/lua/scenes/uses_extra.lua");
  EXPECT_NE(std::string(e.what()).find("no mod named 'extra'"), std::string::npos) << e.what();
  EXPECT_EQ(e.where().line, 2);

  LoadOptions options;
  options.mod_paths.push_back(source_path("tests/lua/scenes/extra_mods"));
  LoadedScene s = load_scene(source_path("tests/lua/scenes/uses_extra.lua"), registry, options);
  EXPECT_DOUBLE_EQ(get<Vec3>(*s.world, "thing", "position").y, 3);
}

TEST_F(SceneLoaderTest, MissingAndWrongFilesAreInputErrors) {
  const InputError missing = load_error("tests/lua/scenes/does_not_exist.lua");
  EXPECT_NE(missing.where().file.find("does_not_exist.lua"), std::string::npos);
  const InputError not_lua = load_error("tests/lua/CMakeLists.txt");
  EXPECT_NE(std::string(not_lua.what()).find("a scene is a .lua file or a mod folder"),
            std::string::npos);
  // A library mod has no scene to run...
  const InputError library = load_error("mods/kit");
  EXPECT_NE(std::string(library.what()).find("has no scene"), std::string::npos) << library.what();
  EXPECT_NE(library.where().file.find("mod.lua"), std::string::npos);
}

TEST_F(SceneLoaderTest, ModsThatAreNotDeclaredCannotBeRequired) {
  const InputError e = load_error("tests/lua/bad_scenes/undeclared_dependency.lua");
  EXPECT_NE(std::string(e.what()).find("does not list it in depends"), std::string::npos)
      << e.what();
}

TEST_F(SceneLoaderTest, AMemoryHungrySceneIsStopped) {
  LoadOptions options;
  options.memory_limit = 4u << 20;
  const InputError e = load_error("tests/lua/limits/memory_hog.lua", options);
  EXPECT_NE(std::string(e.what()).find("out of memory"), std::string::npos) << e.what();
}

TEST_F(SceneLoaderTest, ASceneThatCatchesItsOwnOutOfMemoryIsStillStopped) {
  LoadOptions options;
  options.memory_limit = 4u << 20;
  const InputError e = load_error("tests/lua/limits/memory_hog_pcall.lua", options);
  EXPECT_NE(std::string(e.what()).find("out of memory"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("caught the error in a pcall"), std::string::npos)
      << e.what();
  EXPECT_NE(e.where().file.find("memory_hog_pcall.lua"), std::string::npos) << e.where().file;
}

TEST_F(SceneLoaderTest, ErrorsCaughtByTheScenesOwnPcallAreChargedToItsBudget) {
  LoadOptions options;
  options.instruction_limit = 10'000'000;
  const InputError e = load_error("tests/lua/limits/caught_errors.lua", options);
  EXPECT_NE(std::string(e.what()).find("ran too long"), std::string::npos) << e.what();
  EXPECT_NE(e.where().file.find("caught_errors.lua"), std::string::npos) << e.where().file;
  // The same scene with room for its 20,000 errors (2,000 instructions each)
  // loads: the charge is a cost, not a ban on pcall.
  options.instruction_limit = 100'000'000;
  EXPECT_NO_THROW(load_scene(source_path("tests/lua/limits/caught_errors.lua"), registry, options));
}

TEST_F(SceneLoaderTest, AnEndlessSceneIsStopped) {
  LoadOptions options;
  options.instruction_limit = 20'000'000;
  const InputError e = load_error("tests/lua/limits/endless_loop.lua", options);
  EXPECT_NE(std::string(e.what()).find("ran too long"), std::string::npos) << e.what();
  EXPECT_NE(e.where().file.find("endless_loop.lua"), std::string::npos);
}

TEST_F(SceneLoaderTest, LocateFillsInTheObjectsLine) {
  LoadedScene s = load_scene(source_path("tests/lua/scenes/no_world.lua"), registry);
  const InputError later(ErrorLocation{"", 0, "lonely"}, "refused by a resolver");
  const InputError located = locate(s, later);
  EXPECT_EQ(located.where().line, 2);
  EXPECT_NE(located.where().file.find("no_world.lua"), std::string::npos);
  EXPECT_EQ(located.bare(), "refused by a resolver");
}

TEST_F(SceneLoaderTest, TimelineInputsApplyAtTheirTime) {
  LoadedScene s = load_scene(source_path("tests/lua/scenes/timeline.lua"), registry);
  World& w = *s.world;
  EXPECT_EQ(w.pending_inputs(), 1u);
  const ObjectId bar = w.find("bar");
  w.run(110);  // 0.458 s: still held
  EXPECT_DOUBLE_EQ(std::get<Vec3>(w.get(bar, "position")).y, 1.0);
  w.run(130);  // let go at 0.5 s, then falls for half a second
  EXPECT_FALSE(std::get<bool>(w.get(bar, "pinned")));
  EXPECT_LT(std::get<Vec3>(w.get(bar, "position")).y, 0.0);
}

TEST_F(SceneLoaderTest, AreasHaveTheirOwnResolvers) {
  LoadedScene s = load_scene(source_path("tests/lua/scenes/areas.lua"), registry);
  World& w = *s.world;
  ASSERT_EQ(s.def.areas.size(), 1u);
  EXPECT_EQ(s.def.areas[0].name, "moon");
  w.run(120);  // 0.5 s
  EXPECT_EQ(w.area_of(w.find("moon_ball")), "moon");
  EXPECT_TRUE(w.has_stage("gravity.uniform@moon"));
  EXPECT_TRUE(w.has_stage("gravity.uniform"));
  const double moon_v = std::get<Vec3>(w.get(w.find("moon_ball"), "velocity")).y;
  const double earth_v = std::get<Vec3>(w.get(w.find("earth_ball"), "velocity")).y;
  EXPECT_NEAR(moon_v, -1.62 * 0.5, 0.02);
  EXPECT_NEAR(earth_v, -9.81 * 0.5, 0.05);
}

}  // namespace
}  // namespace alloy::lua
