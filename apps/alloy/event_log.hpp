// What `alloy run` does with the world's events: write them as JSON lines
// (`--events FILE.jsonl`) and narrate them on standard output.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <ostream>
#include <string>
#include <tuple>

#include "runtime/world.hpp"

namespace alloy::app {

/// One JSON object per line: step, time, type, source, a, b, then the event's
/// named values and text. Written to a temp file and renamed on close.
///
/// What a mod's stages emit is bounded per mod (`mod`: the mod an event came
/// from, "" for the engine's own): past `bytes_per_mod` its events are
/// counted, not written, and close() adds one "events_dropped" line per mod.
/// The mods' own budgets (lua/mod_state.hpp) stop a flood long before; this
/// bounds what one run writes whatever those budgets are set to.
class EventLog {
 public:
  EventLog(const std::string& path, std::uint64_t bytes_per_mod = 64u << 20);
  ~EventLog();
  void write(const World& world, const Event& e, const std::string& mod = "");
  void close(const World& world);

 private:
  std::string path_, temp_;
  std::ofstream out_;
  bool closed_ = false;
  std::uint64_t bytes_per_mod_;
  struct Written {
    std::uint64_t bytes = 0, dropped_events = 0, dropped_bytes = 0;
  };
  std::map<std::string, Written> by_mod_;
};

/// Human narration: "step 240  t=1.000 s  contact began: ball - floor".
///
/// A machine that repeats itself (a doorbell buzzing at 13 Hz, a resting
/// contact flickering) would flood the terminal, and folding each event on
/// its own clock would show lines from different cycles out of order. So:
/// an event not seen in the last second is always told; repeats are told only
/// in a window at the start of each simulated second, so that whole cycles
/// are shown in their order, and the rest is counted. Events of one type in
/// the same step share a line ("circuit closed: battery, coil").
class Narrator {
 public:
  explicit Narrator(std::ostream& out, double window = 0.25, std::uint64_t bytes_per_mod = 1u << 20)
      : out_(out), window_(window), bytes_per_mod_(bytes_per_mod) {}
  /// `mod`: the mod whose stage emitted `e` ("" for the engine's own). What
  /// one mod gets narrated is bounded (bytes_per_mod); the rest is counted.
  void narrate(const World& world, const Event& e, const std::string& mod = "");
  /// Writes a line that is not an event (a mod's print, a report) in its
  /// place: after the narration of the steps before it.
  void line(const std::string& text);
  /// Ends a step: its narration is written now, before anything of the next
  /// step (lines are otherwise held to gather one step's events of a type).
  void end_step() { flush(); }
  /// Flushes the last line and prints counts and timing.
  void summary(const World& world, double wall_seconds);

 private:
  void flush();
  std::ostream& out_;
  double window_;
  std::uint64_t bytes_per_mod_;
  std::map<std::string, std::uint64_t> narrated_, dropped_;  // bytes, per mod
  std::string line_mod_;
  std::map<std::tuple<std::string, ObjectId, ObjectId>, double> last_seen_;
  std::map<std::string, std::uint64_t> counts_;
  std::uint64_t folded_ = 0;
  // The line being built: events of one type in one step.
  std::uint64_t line_step_ = ~0ull;
  std::string line_type_, line_;
};

}  // namespace alloy::app
