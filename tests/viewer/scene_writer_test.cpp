// Tests for apps/viewer/scene_writer: a world saved as Lua loads again as the
// same scene (same objects, same properties), at the start and mid-run.
#include "apps/viewer/scene_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;

std::string name_or_slot(const World& w, ObjectId id) {
  return w.describe(id);
}

/// Every object of `a` is in `b` under the same name with the same
/// properties (references compared by name); and nothing more.
void expect_same_scene(const World& a, const World& b) {
  ASSERT_EQ(a.store().object_count(), b.store().object_count());
  const PropertyRegistry& reg = a.properties();
  for (std::uint32_t s = 0; s < a.store().slot_count(); ++s) {
    const ObjectId ia = a.store().id_at(s);
    if (!ia) continue;
    const std::string name = a.describe(ia);
    const ObjectId ib = b.find(name);
    ASSERT_TRUE(bool(ib)) << "object " << name << " is missing after the round trip";
    for (PropertyId p = 0; p < reg.size(); ++p) {
      const std::string& prop = reg.def(p).name;
      const auto pb = b.properties().find(prop);
      const bool has_a = a.store().has(ia, p), has_b = pb && b.store().has(ib, *pb);
      ASSERT_EQ(has_a, has_b) << name << "." << prop;
      if (!has_a) continue;
      const PropertyValue va = a.store().get(ia, p), vb = b.store().get(ib, *pb);
      if (const Quat* qa = std::get_if<Quat>(&va)) {
        const Quat qb = std::get<Quat>(vb);
        EXPECT_NEAR(qa->w, qb.w, 1e-15) << name << "." << prop;
        EXPECT_NEAR(qa->z, qb.z, 1e-15) << name << "." << prop;
        EXPECT_NEAR(qa->x, qb.x, 1e-15) << name << "." << prop;
        EXPECT_NEAR(qa->y, qb.y, 1e-15) << name << "." << prop;
      } else if (const ObjectId* ra = std::get_if<ObjectId>(&va)) {
        EXPECT_EQ(name_or_slot(a, *ra), name_or_slot(b, std::get<ObjectId>(vb)))
            << name << "." << prop;
      } else if (std::holds_alternative<RefList>(va)) {
        const RefList la = std::get<RefList>(va), lb = std::get<RefList>(vb);
        ASSERT_EQ(la.size(), lb.size());
        for (std::size_t i = 0; i < la.size(); ++i) EXPECT_EQ(a.describe(la[i]), b.describe(lb[i]));
      } else {
        EXPECT_TRUE(va == vb) << name << "." << prop << " differs after the round trip";
      }
    }
  }
}

TEST(SceneWriter, TheDemoSavedLoadsAsTheSameScene) {
  auto original = test::load(test::source("mods/rigid_demo"));
  const fs::path file = test::temp_dir() / "demo_saved.lua";
  save_scene(original.world(), {"rigid_demo", "saved", 5, "mods/rigid_demo"}, file);
  auto again = test::load(file);
  expect_same_scene(original.world(), again.world());
  EXPECT_EQ(again.scene.name, "rigid_demo");
  EXPECT_EQ(again.scene.seconds, 5);
  EXPECT_EQ(again.world().dt(), original.world().dt());
  // World settings travel too (the demo's gravity).
  ASSERT_TRUE(again.scene.def.settings.count("gravity.uniform"));
  EXPECT_TRUE(again.scene.def.settings.at("gravity.uniform").values() ==
              original.scene.def.settings.at("gravity.uniform").values());
}

TEST(SceneWriter, MidRunTheStateIsSavedAsItIs) {
  auto running = test::load(test::source("mods/rigid_demo"));
  running.world().run(300);  // 1.25 s: everything is moving
  const fs::path file = test::temp_dir() / "mid_run.lua";
  save_scene(running.world(), {}, file);
  auto again = test::load(file);
  expect_same_scene(running.world(), again.world());
  // And it runs on from there.
  again.world().run(100);
  EXPECT_TRUE(is_finite(std::get<Vec3>(again.world().get(again.world().find("ball"), "position"))));
}

TEST(SceneWriter, AlloyRunLoadsTheSavedFile) {
  auto original = test::load(test::source("mods/rigid_demo"));
  const fs::path file = test::temp_dir() / "for_run.lua";
  save_scene(original.world(), {"rigid_demo", "", 0, ""}, file);
#ifdef ALLOY_BINARY
  const std::string cmd =
      std::string(ALLOY_BINARY) + " run " + file.string() + " --seconds 0.5 --quiet";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
#endif
}

TEST(SceneWriter, UnnamedObjectsThatAreReferredToGetNames) {
  PluginRegistry registry;
  register_native_plugins(registry);
  World w(registry);
  const ObjectId bar = w.create();  // no name
  w.set(bar, "shape", std::string("box"));
  w.set(bar, "size", Vec3{0.4, 0.02, 0.02});
  w.set(bar, "mass", 1.0);
  w.set(bar, "position", Vec3{0, 1, 0});
  const ObjectId hinge = w.create("hinge");
  w.set(hinge, "joint", std::string("hinge"));
  w.set(hinge, "body_a", bar);
  w.set(hinge, "anchor", Vec3{-0.2, 1, 0});
  const std::string text = write_scene(w, {});
  EXPECT_NE(text.find("name = \"_" + std::to_string(bar.index) + "\""), std::string::npos) << text;
  const fs::path file = test::temp_dir() / "unnamed.lua";
  write_file_whole(file, text);
  auto again = test::load(file);
  const ObjectId h = again.world().find("hinge");
  ASSERT_TRUE(bool(h));
  const ObjectId a = std::get<ObjectId>(again.world().get(h, "body_a"));
  EXPECT_EQ(std::get<Vec3>(again.world().get(a, "position")), (Vec3{0, 1, 0}));
}

TEST(SceneWriter, FilesAreWrittenWholeOrNotAtAll) {
  const fs::path dir = test::temp_dir();
  EXPECT_THROW(write_file_whole(dir / "no_such_folder" / "x.lua", "x"), std::runtime_error);
  write_file_whole(dir / "x.lua", "first");
  write_file_whole(dir / "x.lua", "second");
  std::ifstream in(dir / "x.lua");
  std::string s;
  std::getline(in, s);
  EXPECT_EQ(s, "second");
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos)
        << "left behind: " << e.path();
}

}  // namespace
}  // namespace alloy::viewer
