// What `alloy view` is asked to do (the command line's options).
#pragma once

#include <filesystem>
#include <string>

#include "lua/scene_loader.hpp"

namespace alloy::viewer {

struct ViewerOptions {
  std::filesystem::path scene;
  int width = 1280, height = 800;
  /// No display needed: dummy video driver, software renderer, no audio,
  /// fixed frame time.
  bool headless = false;
  /// Frames to run before closing by itself (0: until the window is closed).
  int frames = 0;
  std::string screenshot;  ///< PNG of the last frame, written when the run ends
  std::string script;      ///< input script (input_script.hpp)
  std::string save;        ///< scene file written when the run ends
  /// Recording of the run (runtime/replay.hpp: every edit, undo and step),
  /// written when the run ends or another world is loaded (New, Open,
  /// Reset), which starts the next part, FILE-2.EXT, FILE-3.EXT, ... from
  /// that world's snapshot; `alloy replay FILE` checks a part.
  std::string record;
  double time_scale = 1;
  bool paused = false;
  bool audio = true;
  bool panels = true;  ///< false: the play area alone (clean pictures)
  lua::LoadOptions load;
};

}  // namespace alloy::viewer
