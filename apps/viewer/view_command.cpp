#include "apps/viewer/view_command.hpp"

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <sstream>

#include "apps/viewer/viewer.hpp"

namespace alloy::viewer {

CLI::App* add_view_command(CLI::App& app, ViewerOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "view", "Open a scene in the viewer: build and change contraptions while they run");
  cmd->add_option("scene", o.scene, "Scene file (.lua) or mod folder; none: a new, empty board");
  cmd->add_option("--screenshot", o.screenshot, "Write the last frame as a PNG (runs headless)");
  cmd->add_option("--frames", o.frames,
                  "Frames to run, then close (1/60 s of simulated time each when headless)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--headless", o.headless,
                "No display: SDL's dummy video driver and software renderer");
  cmd->add_option(
      "--script", o.script,
      "Input script: mouse and key events at frames (see apps/viewer/input_script.hpp)");
  cmd->add_option("--save", o.save, "Save the scene as a Lua file when the run ends");
  cmd->add_option("--record", o.record,
                  "Record the run (every edit, undo and step) into FILE when it ends; "
                  "a New, Open or Reset starts the next part, FILE-2.EXT, ...; "
                  "check each with `alloy replay FILE`");
  cmd->add_option("--time-scale", o.time_scale, "Simulated seconds per second of the clock")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--paused", o.paused, "Start paused");
  cmd->add_flag("!--no-audio", o.audio, "No sound");
  cmd->add_flag("!--no-panels", o.panels, "The play area alone, without the panels");
  cmd->add_option(
      "--size",
      [&o](const CLI::results_t& r) {
        int w = 0, h = 0;
        char x = 0;
        std::istringstream in(r.at(0));
        if (!(in >> w >> x >> h) || x != 'x' || w < 200 || h < 150 || w > 8192 || h > 8192)
          return false;
        o.width = w;
        o.height = h;
        return true;
      },
      "Window size WxH in pixels (default 1280x800)");
  return cmd;
}

int run_view(ViewerOptions o, std::ostream& out, std::ostream& err) {
  if (!o.screenshot.empty()) o.headless = true;
  if (o.headless) o.audio = false;
  if (o.headless && o.frames == 0) o.frames = 1;
  if (const char* env = std::getenv("ALLOY_MODS")) {
    std::stringstream ss(env);
    for (std::string dir; std::getline(ss, dir, ':');)
      if (!dir.empty()) o.load.mod_paths.emplace_back(dir);
  }
  o.load.mod_paths.emplace_back(std::string(ALLOY_SOURCE_DIR) + "/mods");
  try {
    Viewer viewer(o);
    return viewer.run(out, err);
  } catch (const InputError& e) {
    err << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "alloy view: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace alloy::viewer
