// Running the doorbell headless and reading what happened: the events of a
// run as plain records, strikes, and the paper's chain of events per cycle.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy::doorbell::test {

using alloy::test::EventRecords;
using alloy::test::Record;
using alloy::test::source;

struct RunOptions {
  std::optional<double> dt;       ///< overrides the scene's step
  double emf_scale = 1;           ///< the battery's emf times this
  std::optional<double> seconds;  ///< default: the scene's
};

struct RunResult : EventRecords {
  double dt = 0;
  std::uint64_t steps = 0;
  double final_coil_current = 0;

  /// Times of the bell's strikes (its `sound` events).
  std::vector<double> strikes() const {
    std::vector<double> t;
    for (const Record* e : of("sound", "bell")) t.push_back(e->time);
    return t;
  }
};

inline RunResult run_scene(const std::string& scene, const RunOptions& options = {}) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene loaded = lua::load_scene(source(scene), registry);
  World& world = *loaded.world;
  if (options.dt) world.set_dt(*options.dt);
  const ObjectId battery = world.find("battery");
  if (options.emf_scale != 1)
    world.set(battery, "emf", std::get<double>(world.get(battery, "emf")) * options.emf_scale);
  RunResult r;
  r.record(world);
  r.dt = world.dt();
  const double seconds = options.seconds ? *options.seconds : loaded.seconds;
  r.steps = std::uint64_t(std::llround(seconds / r.dt));
  world.run(r.steps);
  r.final_coil_current = std::get<double>(world.get(world.find("coil"), "current"));
  return r;
}

/// The paper's chain (4.1.2 - 4.1.6) for one strike of the bell: the circuit
/// closes, the electromagnet comes on, the striker leaves the contact, the
/// circuit is broken, the bell is struck, each at a later step than the one
/// before. `closures` counts the coil's circuit_closed events since the
/// previous strike: 1 for a clean cycle (more when a contact bounced).
struct Cycle {
  std::uint64_t closed = 0, on = 0, left = 0, broken = 0, struck = 0;
  int closures = 0;
  bool in_order = false;
};

inline std::vector<Cycle> cycles(const RunResult& r, const std::string& striker = "finger",
                                 const std::string& contact = "interrupter") {
  std::vector<Cycle> out;
  Cycle c;
  auto reset = [&] { c = Cycle{}; };
  for (const Record& e : r.events) {
    if (e.type == "circuit_closed" && e.a == "coil") {
      ++c.closures;
      c.closed = e.step, c.on = c.left = c.broken = 0;  // the chain starts again here
    } else if (e.type == "electromagnet_on" && e.a == "coil" && c.closed && !c.on) {
      c.on = e.step;
    } else if (e.type == "contact_ended" &&
               ((e.a == striker && e.b == contact) || (e.a == contact && e.b == striker)) && c.on &&
               !c.left) {
      c.left = e.step;
    } else if (e.type == "circuit_opened" && e.a == "coil" && c.left && !c.broken) {
      c.broken = e.step;
    } else if (e.type == "sound" && e.a == "bell") {
      c.struck = e.step;
      c.in_order = c.closed && c.on && c.left && c.broken && c.closed < c.on && c.on < c.left &&
                   c.left < c.broken && c.broken < c.struck;
      out.push_back(c);
      reset();
    }
  }
  return out;
}

struct Intervals {
  double mean = 0, min = 0, max = 0;
  double spread() const { return (max - min) / mean; }  ///< (max - min) / mean
};

inline Intervals intervals(const std::vector<double>& t) {
  Intervals s;
  if (t.size() < 2) return s;
  s.min = 1e300, s.max = -1e300;
  for (std::size_t i = 1; i < t.size(); ++i) {
    const double d = t[i] - t[i - 1];
    s.mean += d, s.min = std::min(s.min, d), s.max = std::max(s.max, d);
  }
  s.mean /= double(t.size() - 1);
  return s;
}

}  // namespace alloy::doorbell::test
