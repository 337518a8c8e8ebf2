// Helpers shared by the viewer tests: loading bundled scenes and making
// headless viewers.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "apps/viewer/viewer.hpp"
#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"

namespace alloy::viewer::test {

inline std::filesystem::path source(const std::string& rel) {
  return std::filesystem::path(ALLOY_SOURCE_DIR) / rel;
}

inline lua::LoadOptions load_options() {
  lua::LoadOptions o;
  o.mod_paths.push_back(source("mods"));
  return o;
}

/// A scene loaded outside any viewer, with its own registry.
struct Loaded {
  std::unique_ptr<PluginRegistry> registry = std::make_unique<PluginRegistry>();
  lua::LoadedScene scene;
  World& world() { return *scene.world; }
};

inline Loaded load(const std::filesystem::path& path) {
  Loaded l;
  register_native_plugins(*l.registry);
  l.scene = lua::load_scene(path, *l.registry, load_options());
  return l;
}

inline std::filesystem::path temp_dir() {
  auto d = std::filesystem::temp_directory_path() /
           ("alloy_viewer_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::create_directories(d);
  return d;
}

inline ViewerOptions headless(const std::filesystem::path& scene, bool panels = true) {
  ViewerOptions o;
  o.scene = scene;
  o.headless = true;
  o.audio = false;
  o.panels = panels;
  o.load = load_options();
  return o;
}

inline Vec2 position_of(World& w, const std::string& name) {
  const ObjectId id = w.find(name);
  EXPECT_TRUE(bool(id)) << "no object " << name;
  if (!id) return {};
  return xy(std::get<Vec3>(w.get(id, "position")));
}

/// A headless viewer on a new board, paused (no step between edits).
inline std::unique_ptr<Viewer> new_board() {
  ViewerOptions o = headless("");
  o.paused = true;
  auto v = std::make_unique<Viewer>(o);
  v->frame();
  return v;
}

/// The palette's entry with this label (a test failure if there is none).
inline const PaletteEntry& entry(const std::string& label) {
  for (const PaletteEntry& e : palette_entries())
    if (e.label == label) return e;
  ADD_FAILURE() << "no palette entry " << label;
  return palette_entries().front();
}

/// A key press (with modifiers), then one frame.
inline void key(Viewer& v, SDL_Keycode k, Uint16 mod = KMOD_NONE) {
  v.push_key(k, mod);
  v.frame();
}

/// A click without a move between press and release, then one frame.
inline void click(Viewer& v, Vec2 at) {
  v.push_mouse(SDL_MOUSEMOTION, at);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, at);
  v.push_mouse(SDL_MOUSEBUTTONUP, at);
  v.frame();
}

}  // namespace alloy::viewer::test
