// `alloy run --watch` (and any app that steps a world by hand): paces the run
// in real time, so that a person can edit a mod while it runs, and between
// steps reloads the mods whose files changed (ModRuntime::poll). Ctrl-C ends
// the run cleanly.
#pragma once

#include <chrono>
#include <ostream>

#include "lua/mod_runtime.hpp"

namespace alloy::lua {

class WatchLoop {
 public:
  /// `mods` may be null (a scene without Lua stages: nothing to reload).
  WatchLoop(ModRuntime* mods, std::ostream& out);
  ~WatchLoop();
  WatchLoop(const WatchLoop&) = delete;
  WatchLoop& operator=(const WatchLoop&) = delete;

  /// Call after each step: sleeps until the wall clock has caught up with the
  /// world's time and handles changed files. False once interrupted.
  bool between_steps(const World& world);

 private:
  ModRuntime* mods_;
  std::ostream& out_;
  std::chrono::steady_clock::time_point start_;
  double world_start_ = -1;
  void (*previous_handler_)(int) = nullptr;
};

}  // namespace alloy::lua
