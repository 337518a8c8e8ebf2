// The coupled scenes of the benchmarks (mods/doorbell, mods/motor) run
// headless at chosen rates, and the one figure each is judged by: the
// doorbell's strike period, the motor's steady speed. Shared by
// alloy_bench_coupled, alloy_bench_multirate and tests/coupled.
//
// A run loads the mod's own scene file with a few lines of Lua put in front
// of it that wrap world{}: the scene's settings stay what the mod says, and
// only the rates asked for are overridden. So the benchmarks follow the
// scenes as they change, and a rate left at 0 is the scene's default.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/electricity/electricity.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "runtime/world.hpp"

namespace alloy::bench::coupled {

/// Where the rates of a run differ from the scene's.
struct Rates {
  double dt = 0;                     ///< the world's step = the coupling window, s; 0: the scene's
  std::string solver;                ///< rigid_body solver "step" | "quick"; empty: the scene's
  int iterations = 0;                ///< rigid_body iterations (quick); 0: the scene's
  int electricity_substeps = 0;      ///< electricity substeps; 0: the scene's
  int rigid_substeps = 0;            ///< rigid_body substeps; 0: the scene's
  std::map<std::string, int> every;  ///< world every = { stage = n }
  /// magnetic_forces rates = true: the magnetic loads reach the rigid body
  /// with their rates, a first-order hold over its substeps; false: the scene's
  bool load_rates = false;
  std::string
      substep_contacts;  ///< rigid_body substep_contacts "kept" | "found"; empty: the scene's
  /// electricity rates = true and magnetism rates = true: a coil's current
  /// reaches the magnetism with its rate, and its pole strength moves on
  /// between windows; false: the scene's
  bool current_rates = false;
  /// The rigid body's engine: "box2d" runs the scene on rigid_body.box2d and
  /// collisions.box2d (world `use`); empty: the scene's (ODE)
  std::string engine;
  /// rigid_body.box2d's Box2D steps per world step, with no max_substep
  /// bound (the substep study of alloy_bench_engines); 0: its defaults
  int box2d_substeps = 0;
  /// electricity_from_collisions ahead = true: a touch predicted within half
  /// a step is connected at the step before it is seen; false: the scene's
  bool contacts_ahead = false;
};

/// The source tree (compiled in as ALLOY_SOURCE_DIR).
inline std::filesystem::path source_dir() {
  return std::filesystem::path(ALLOY_SOURCE_DIR);
}

/// The Lua put in front of a scene: wraps world{} to override the rates.
inline std::string rate_prelude(const Rates& r) {
  std::ostringstream s;
  s.precision(17);
  s << "do\n  local scene_world = world\n  world = function(w)\n";
  if (r.dt > 0) s << "    w.dt = " << r.dt << "\n";
  s << "    w.settings = w.settings or {}\n";
  auto setting = [&](const char* plugin, const char* key, const std::string& value) {
    s << "    w.settings[\"" << plugin << "\"] = w.settings[\"" << plugin << "\"] or {}\n"
      << "    w.settings[\"" << plugin << "\"]." << key << " = " << value << "\n";
  };
  if (!r.solver.empty()) setting("rigid_body", "solver", "\"" + r.solver + "\"");
  if (r.iterations > 0) setting("rigid_body", "iterations", std::to_string(r.iterations));
  if (r.rigid_substeps > 0) setting("rigid_body", "substeps", std::to_string(r.rigid_substeps));
  if (r.electricity_substeps > 0)
    setting("electricity", "substeps", std::to_string(r.electricity_substeps));
  if (r.load_rates) setting("magnetic_forces", "rates", "true");
  if (r.current_rates) {
    setting("electricity", "rates", "true");
    setting("magnetism", "rates", "true");
  }
  if (!r.substep_contacts.empty())
    setting("rigid_body", "substep_contacts", "\"" + r.substep_contacts + "\"");
  if (r.contacts_ahead) setting("electricity_from_collisions", "ahead", "true");
  if (!r.every.empty()) {
    s << "    w.every = w.every or {}\n";
    for (const auto& [stage, n] : r.every) s << "    w.every[\"" << stage << "\"] = " << n << "\n";
  }
  if (r.engine == "box2d")
    s << "    w.use = w.use or {}\n"
      << "    w.use.rigid_body = \"rigid_body.box2d\"\n"
      << "    w.use.collisions = \"collisions.box2d\"\n";
  if (r.box2d_substeps > 0) {
    setting("rigid_body.box2d", "substeps", std::to_string(r.box2d_substeps));
    setting("rigid_body.box2d", "max_substep", "0");
  }
  s << "    return scene_world(w)\n  end\nend\n";
  return s.str();
}

/// Loads `mod`'s scene (e.g. "doorbell") with its rates overridden. The
/// scene text is copied behind the prelude into a scratch file; its
/// `require`s find the mods through the source tree's mods/.
inline lua::LoadedScene load(const std::string& mod, const Rates& rates, PluginRegistry& registry) {
  namespace fs = std::filesystem;
  const fs::path scene = source_dir() / "mods" / mod / "scene.lua";
  std::ifstream in(scene);
  std::stringstream text;
  text << in.rdbuf();
  static int counter = 0;
  const fs::path file = fs::temp_directory_path() / ("alloy_coupled_" + std::to_string(::getpid()) +
                                                     "_" + std::to_string(counter++) + ".lua");
  std::ofstream(file) << rate_prelude(rates) << text.str();
  lua::LoadOptions options;
  options.mod_paths.push_back(source_dir() / "mods");
  try {
    lua::LoadedScene loaded = lua::load_scene(file, registry, options);
    fs::remove(file);
    return loaded;
  } catch (...) {
    fs::remove(file);
    throw;
  }
}

/// The scene's own rates, every one resolved (a setting the scene leaves out
/// is the plugin's default): what the benchmarks mark as "default".
inline Rates scene_rates(const std::string& mod) {
  PluginRegistry registry;
  register_native_plugins(registry);
  const lua::LoadedScene loaded = load(mod, {}, registry);
  const WorldDef& def = loaded.def;
  auto settings = [&](const char* plugin) {
    auto it = def.settings.find(plugin);
    return it == def.settings.end() ? PluginSettings{} : it->second;
  };
  const rigid::RigidBodyConfig rigid_config = rigid::RigidBodyConfig::from(settings("rigid_body"));
  const electricity::ElectricityConfig elec =
      electricity::ElectricityConfig::from(settings("electricity"));
  Rates r;
  r.dt = def.dt;
  r.solver = rigid_config.solver == rigid::RigidBodyConfig::Solver::Step ? "step" : "quick";
  r.iterations = rigid_config.iterations;
  r.rigid_substeps = rigid_config.substeps;
  r.electricity_substeps = elec.substeps;
  for (const auto& [stage, n] : def.every) r.every[stage] = n;
  return r;
}

/// `base` with every rate that `over` sets taken from `over`.
inline Rates with(Rates base, const Rates& over) {
  if (over.dt > 0) base.dt = over.dt;
  if (!over.solver.empty()) base.solver = over.solver;
  if (over.iterations > 0) base.iterations = over.iterations;
  if (over.electricity_substeps > 0) base.electricity_substeps = over.electricity_substeps;
  if (over.rigid_substeps > 0) base.rigid_substeps = over.rigid_substeps;
  for (const auto& [stage, n] : over.every) base.every[stage] = n;
  base.load_rates = base.load_rates || over.load_rates;
  base.current_rates = base.current_rates || over.current_rates;
  if (!over.substep_contacts.empty()) base.substep_contacts = over.substep_contacts;
  if (!over.engine.empty()) base.engine = over.engine;
  if (over.box2d_substeps > 0) base.box2d_substeps = over.box2d_substeps;
  if (over.contacts_ahead) base.contacts_ahead = true;
  return base;
}

/// "1/240" for a step that is 1/n s, else the number.
inline std::string step_name(double dt) {
  const double n = 1 / dt;
  if (std::abs(n - std::round(n)) < 1e-6) return "1/" + std::to_string(std::llround(n));
  std::ostringstream s;
  s << dt;
  return s.str();
}

/// What a run measured.
struct Measure {
  double value = NAN;    ///< the figure (strike period, s; steady speed, rad/s); NaN: fails
  int count = 0;         ///< strikes / whole turns it is made of
  double cpu = 0;        ///< CPU seconds spent stepping
  double simulated = 0;  ///< simulated seconds
  std::uint64_t steps = 0;
  std::vector<StageTiming> stages;                 ///< the world's per-stage timing (wall clock)
  double cost() const { return cpu / simulated; }  ///< CPU s per simulated s
  bool ok() const { return std::isfinite(value); }
};

/// CPU time of this process (the same clock as bench::cpu_seconds, kept here
/// so that tests can use this header without the bench library).
inline double process_cpu() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// The doorbell's strike period: the mean interval between the bell's strikes
/// (its `sound` events) whose times fall in [from, to]. Runs the scene to `to`.
/// Fails (NaN) with fewer than 3 strikes in the window: it does not ring.
inline Measure doorbell_period(const Rates& rates, double from = 1.0, double to = 5.0);
inline Measure motor_speed(const Rates& rates, double from = 1.0, double to = 8.0,
                           const std::string& mod = "motor");

/// The two scenes by name, for the sweeps: "doorbell" or "motor".
struct Scene {
  std::string mod;       ///< mods/<mod>
  std::string quantity;  ///< what is measured, with its unit
  double from, to;       ///< the measuring window, s
  Measure (*run)(const Rates&, double, double);
  /// Runs it; a run that throws (a resolver refusing a state) fails like one
  /// that does not work: NaN.
  Measure measure(const Rates& r) const {
    try {
      return run(r, from, to);
    } catch (const std::exception&) {
      Measure m;
      m.simulated = to;
      return m;
    }
  }
};

inline Scene doorbell_scene() {
  return {"doorbell", "strike period (s)", 1.0, 5.0, &doorbell_period};
}
inline Scene motor_scene() {
  return {"motor", "steady speed (rad/s)", 1.0, 8.0,
          [](const Rates& r, double from, double to) { return motor_speed(r, from, to); }};
}

inline Measure doorbell_period(const Rates& rates, double from, double to) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene loaded = load("doorbell", rates, registry);
  World& world = *loaded.world;
  world.set_timing(true);  // the stages' times are part of the measure
  const ObjectId bell = world.find("bell");
  std::vector<double> strikes;
  world.add_observer([&](const Event& e) {
    if (e.type == "sound" && e.a == bell) strikes.push_back(e.time);
  });
  Measure m;
  m.steps = std::uint64_t(std::llround(to / world.dt()));
  m.simulated = double(m.steps) * world.dt();
  const double t0 = process_cpu();
  world.run(m.steps);
  m.cpu = process_cpu() - t0;
  m.stages = world.profile().stages;
  std::vector<double> in;
  for (double t : strikes)
    if (t >= from - 1e-9 && t <= to + 1e-9) in.push_back(t);
  m.count = int(in.size());
  if (in.size() >= 3) m.value = (in.back() - in.front()) / double(in.size() - 1);
  return m;
}

/// The motor's steady speed: the mean angular speed of the axle (rad/s,
/// anticlockwise positive) over the whole turns from `from` on that end by
/// `to`, each turn's end found by linear interpolation between steps (so the
/// figure does not carry a step's worth of quantisation). Runs the scene to
/// `to`. Fails (NaN) if the rotor does not make one whole anticlockwise turn.
inline Measure motor_speed(const Rates& rates, double from, double to, const std::string& mod) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene loaded = load(mod, rates, registry);
  World& world = *loaded.world;
  world.set_timing(true);  // the stages' times are part of the measure
  const ObjectId axle = world.find("axle");
  Measure m;
  m.steps = std::uint64_t(std::llround(to / world.dt()));
  m.simulated = double(m.steps) * world.dt();
  std::vector<double> time, angle;
  time.reserve(m.steps + 1), angle.reserve(m.steps + 1);
  auto sample = [&] {
    const double a = angle_z(std::get<Quat>(world.get(axle, "orientation")));
    angle.push_back(
        angle.empty() ? a : angle.back() + std::remainder(a - angle.back(), 2 * std::numbers::pi));
    time.push_back(world.time());
  };
  double cpu = 0;
  sample();
  for (std::uint64_t i = 0; i < m.steps; ++i) {
    const double t0 = process_cpu();
    world.step();
    cpu += process_cpu() - t0;
    sample();
  }
  m.cpu = cpu;
  m.stages = world.profile().stages;
  const auto i0 =
      std::size_t(std::lower_bound(time.begin(), time.end(), from - 1e-9) - time.begin());
  if (i0 >= time.size()) return m;
  const double start = angle[i0], turn = 2 * std::numbers::pi;
  int turns = 0;
  double t_end = time[i0];
  for (std::size_t i = i0 + 1; i < time.size(); ++i) {
    const double level = start + turn * (turns + 1);
    if (angle[i] >= level && angle[i - 1] < level) {
      const double f = (level - angle[i - 1]) / (angle[i] - angle[i - 1]);
      t_end = time[i - 1] + f * (time[i] - time[i - 1]);
      ++turns;
    }
  }
  m.count = turns;
  if (turns >= 1) m.value = turn * turns / (t_end - time[i0]);
  return m;
}

/// |value - reference| / |reference|, or NaN when the run failed.
inline double relative_error(const Measure& m, double reference) {
  return m.ok() ? std::abs(m.value - reference) / std::abs(reference) : NAN;
}

}  // namespace alloy::bench::coupled
