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
class EventLog {
 public:
  EventLog(const std::string& path);
  ~EventLog();
  void write(const World& world, const Event& e);
  void close();

 private:
  std::string path_, temp_;
  std::ofstream out_;
  bool closed_ = false;
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
  explicit Narrator(std::ostream& out, double window = 0.25) : out_(out), window_(window) {}
  void narrate(const World& world, const Event& e);
  /// Flushes the last line and prints counts and timing.
  void summary(const World& world, double wall_seconds);

 private:
  void flush();
  std::ostream& out_;
  double window_;
  std::map<std::tuple<std::string, ObjectId, ObjectId>, double> last_seen_;
  std::map<std::string, std::uint64_t> counts_;
  std::uint64_t folded_ = 0;
  // The line being built: events of one type in one step.
  std::uint64_t line_step_ = ~0ull;
  std::string line_type_, line_;
};

}  // namespace alloy::app
