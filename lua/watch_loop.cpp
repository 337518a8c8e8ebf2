#include "lua/watch_loop.hpp"

#include <atomic>
#include <csignal>
#include <thread>

namespace alloy::lua {

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_interrupt(int) {
  g_interrupted = true;
}
}  // namespace

WatchLoop::WatchLoop(ModRuntime* mods, std::ostream& out) : mods_(mods), out_(out) {
  g_interrupted = false;
  previous_handler_ = std::signal(SIGINT, on_interrupt);
  if (mods_) {
    mods_->watch();
    out_ << "watching";
    for (const auto& m : mods_->loaded()) out_ << " " << m;
    out_ << " for changes (Ctrl-C to stop)\n";
  } else {
    out_ << "watching: the scene uses no mod with Lua stages; running in real time (Ctrl-C to "
            "stop)\n";
  }
}

WatchLoop::~WatchLoop() {
  std::signal(SIGINT, previous_handler_ ? previous_handler_ : SIG_DFL);
}

bool WatchLoop::between_steps(const World& world) {
  if (world_start_ < 0) {
    world_start_ = world.time() - world.dt();
    start_ = std::chrono::steady_clock::now();
  }
  // What happened reaches the mods' log (stderr) as it happens, and the
  // world's observers as events (mod_reloaded, mod_reload_failed).
  if (mods_) mods_->poll();
  const auto due = start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(world.time() - world_start_));
  std::this_thread::sleep_until(due);
  return !g_interrupted;
}

}  // namespace alloy::lua
