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

/// Human narration: one line per event, "step 240  t=1.000 s  contact began: ball - floor".
/// Repeats of the same event on the same pair within `quiet` seconds of the
/// last line narrated for them are folded (resting contacts flicker), and
/// counted in the summary.
class Narrator {
 public:
  Narrator(std::ostream& out, double quiet = 0.25) : out_(out), quiet_(quiet) {}
  void narrate(const World& world, const Event& e);
  void summary(const World& world, double wall_seconds) const;

 private:
  std::ostream& out_;
  double quiet_;
  std::map<std::tuple<std::string, ObjectId, ObjectId>, double> last_;
  std::map<std::string, std::uint64_t> counts_;
  std::uint64_t folded_ = 0;
};

}  // namespace alloy::app
