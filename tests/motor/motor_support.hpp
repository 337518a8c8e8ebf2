// Running the motor (mods/motor) headless and measuring it: its events as
// plain records, the rotor's angle at every step, and the speed of each whole
// revolution. Shared by the tests and by motor_study (the tolerance study of
// docs/motor.md).
//
// A *frame* is one step at the scene's time step (1/240 s in mods/motor): the
// paper counts frames, the world counts steps, and they are the same thing.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/electricity/electricity_from_magnetism.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy::motor::test {

using alloy::test::EventRecords;
using alloy::test::Record;
using alloy::test::source;

constexpr const char* kScene = "mods/motor";
constexpr const char* kBatteryOff = "mods/motor/battery_off.lua";
constexpr double kSceneDt = 1.0 / 240;
/// The paper's "steady from frame 200", and the window the tests measure in:
/// frames 200 to 2000 at the scene's step, 0.833 s to 8.333 s.
constexpr double kSteadyFrom = 200 * kSceneDt, kSteadyTo = 2000 * kSceneDt;

struct RunOptions {
  std::optional<double> dt;        ///< overrides the scene's step (World::set_dt)
  std::optional<double> seconds;   ///< default: the scene's
  double emf_scale = 1;            ///< the battery's emf times this, before the first step
  double friction_scale = 1;       ///< the bearing's dry friction times this
  std::optional<double> emf;       ///< the battery's emf, V (instead of a scale)
  std::optional<double> friction;  ///< the bearing's dry friction, N m
  double drag_scale = 1;           ///< the bearing's viscous drag times this
};

struct RunResult : EventRecords {
  double dt = 0;
  std::vector<double> time;  ///< at the end of each step, and 0 first
  std::vector<double>
      angle;  ///< the rotor's angle (the axle's), unwrapped, rad; anticlockwise positive
  std::vector<double> spin;  ///< its angular velocity about +z, rad/s
  /// The two coils' currents added, A, positive the way the battery drives
  /// them (the coils' `current` property counts it negative); 0 before the
  /// electricity gives them one.
  std::vector<double> coil_current;

  /// The index of the first sample at or after time t.
  std::size_t at(double t) const {
    return std::size_t(std::lower_bound(time.begin(), time.end(), t - 1e-9) - time.begin());
  }
};

inline double get_number(World& w, const char* object, const char* property) {
  return std::get<double>(w.get(w.find(object), property));
}

/// Loads the scene at `path` (with the source tree's mods) and returns
/// f(loaded) while its registry lives.
template <class F>
decltype(auto) with_scene(const std::string& path, F&& f) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(path, registry, load);
  return f(loaded);
}

inline RunResult run_motor(const std::string& scene, const RunOptions& options = {}) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(source(scene), registry, load);
  World& world = *loaded.world;
  if (options.dt) world.set_dt(*options.dt);
  const ObjectId battery = world.find("battery"), bearing = world.find("bearing"),
                 axle = world.find("axle");
  // The coils of both phases (the second, coil_b1 and coil_b2, when the
  // layout has a second commutator: docs/motor.md, "Session 20").
  std::vector<ObjectId> coils;
  for (const char* name : {"upper_coil", "lower_coil", "coil_b1", "coil_b2"})
    if (const ObjectId c = world.find(name); !c.is_null()) coils.push_back(c);
  if (options.emf) world.set(battery, "emf", *options.emf);
  if (options.emf_scale != 1)
    world.set(battery, "emf", get_number(world, "battery", "emf") * options.emf_scale);
  if (options.friction) world.set(bearing, "joint_friction", *options.friction);
  if (options.friction_scale != 1)
    world.set(bearing, "joint_friction",
              get_number(world, "bearing", "joint_friction") * options.friction_scale);
  if (options.drag_scale != 1)
    world.set(axle, "angular_damping",
              get_number(world, "axle", "angular_damping") * options.drag_scale);
  RunResult r;
  r.record(world);
  r.dt = world.dt();
  const double seconds = options.seconds ? *options.seconds : loaded.seconds;
  const auto steps = std::uint64_t(std::llround(seconds / r.dt));
  r.time.reserve(steps + 1), r.angle.reserve(steps + 1), r.spin.reserve(steps + 1);
  r.coil_current.reserve(steps + 1);
  auto sample = [&] {
    const double a = angle_z(std::get<Quat>(world.get(axle, "orientation")));
    // Less than half a turn a step: the nearest branch is the right one.
    const double unwrapped =
        r.angle.empty() ? a
                        : r.angle.back() + std::remainder(a - r.angle.back(), 2 * std::numbers::pi);
    r.time.push_back(world.time());
    r.angle.push_back(unwrapped);
    // The rigid body gives the axle its velocities in its first advance.
    const bool moving = world.store().has(axle, world.properties().id("angular_velocity"));
    r.spin.push_back(moving ? std::get<Vec3>(world.get(axle, "angular_velocity")).z : 0.0);
    double current = 0;
    for (ObjectId c : coils)
      if (world.store().has(c, world.properties().id("current")))
        current -= std::get<double>(world.get(c, "current"));
    r.coil_current.push_back(current);
  };
  sample();
  for (std::uint64_t i = 0; i < steps; ++i) {
    world.step();
    sample();
  }
  return r;
}

/// The rotor's mean angular velocity over each whole revolution that starts
/// and ends between t0 and t1, the first starting at t0: 2 pi / its duration,
/// signed (anticlockwise positive). A turn ends at the first sample at which
/// the rotor has turned one more full turn either way.
inline std::vector<double> revolutions(const RunResult& r, double t0, double t1) {
  std::vector<double> out;
  const std::size_t i0 = r.at(t0), i1 = std::min(r.at(t1), r.time.size() - 1);
  if (i0 >= i1) return out;
  std::size_t start = i0;
  for (std::size_t i = i0 + 1; i <= i1; ++i) {
    const double turned = r.angle[i] - r.angle[start];
    if (std::abs(turned) >= 2 * std::numbers::pi) {
      out.push_back(std::copysign(2 * std::numbers::pi, turned) / (r.time[i] - r.time[start]));
      start = i;
    }
  }
  return out;
}

/// The mean of the samples of v between t0 and t1.
inline double mean_between(const RunResult& r, const std::vector<double>& v, double t0, double t1) {
  const std::size_t i0 = r.at(t0), i1 = std::min(r.at(t1), v.size() - 1);
  double sum = 0;
  for (std::size_t i = i0 + 1; i <= i1; ++i) sum += v[i];
  return i1 > i0 ? sum / double(i1 - i0) : NAN;
}

/// The rotor's mean angular velocity between t0 and t1, from its angle.
inline double mean_speed(const RunResult& r, double t0, double t1) {
  const std::size_t i0 = r.at(t0), i1 = std::min(r.at(t1), r.angle.size() - 1);
  return (r.angle[i1] - r.angle[i0]) / (r.time[i1] - r.time[i0]);
}

struct Steadiness {
  std::size_t turns = 0;
  double mean = 0, min = 0, max = 0;  ///< of the per-revolution means, rad/s
  /// (max - min) / |mean| of the per-revolution means.
  double spread() const { return turns ? (max - min) / std::abs(mean) : INFINITY; }
};

inline Steadiness steadiness(const std::vector<double>& per_turn) {
  Steadiness s;
  s.turns = per_turn.size();
  if (per_turn.empty()) return s;
  s.min = *std::min_element(per_turn.begin(), per_turn.end());
  s.max = *std::max_element(per_turn.begin(), per_turn.end());
  for (double w : per_turn) s.mean += w;
  s.mean /= double(per_turn.size());
  return s;
}

// --- the DC-motor model ---------------------------------------------------------------
//
// A DC motor with back-EMF constant k and loop resistance R turns where the
// battery's emf V is the back-EMF plus the drop, V = k w + R I, and gives the
// torque k I, which the load takes: the bearing's dry friction (a brake: the
// load), and what the motor loses in itself (the slider's friction on the
// spokes, the oil's drag), T0. So w = V / k - R (T + T0) / k^2: the no-load
// speed V / k, the stall torque k V / R, a straight line between.

/// One steady point: the battery's emf and the load (the bearing's dry
/// friction), and what the rotor and the coils did from t0 to t1.
struct DcPoint {
  double emf = 0, load = 0;       ///< V; N m
  double speed = 0, current = 0;  ///< mean rad/s; mean coil current, A
};

inline DcPoint dc_point(double emf, double load, double t0 = 2.0, double t1 = 6.0,
                        std::optional<double> dt = {}) {
  const RunResult r = run_motor(kScene, {.dt = dt, .seconds = t1, .emf = emf, .friction = load});
  return {emf, load, mean_speed(r, t0, t1), mean_between(r, r.coil_current, t0, t1)};
}

/// The DC model fitted to the rotor's speeds alone (least squares of
/// w = a V - b T - c over the points): k = 1 / a, R = b k^2, T0 = c / b.
struct DcFit {
  double k = 0, R = 0, T0 = 0;  ///< V s; ohm; N m
  double speed(double emf, double load) const { return emf / k - R * (load + T0) / (k * k); }
  double no_load_speed(double emf) const { return emf / k; }
  double stall_torque(double emf) const { return k * emf / R; }
};

inline DcFit fit_dc_model(const std::vector<DcPoint>& points) {
  // Normal equations of the 3 x 3 least-squares problem, by Cramer's rule.
  double A[3][3] = {}, y[3] = {};
  for (const DcPoint& p : points) {
    const double row[3] = {p.emf, -p.load, -1};
    for (int i = 0; i < 3; ++i) {
      y[i] += row[i] * p.speed;
      for (int j = 0; j < 3; ++j) A[i][j] += row[i] * row[j];
    }
  }
  auto det = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double d = det(A);
  double x[3];
  for (int c = 0; c < 3; ++c) {
    double m[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = j == c ? y[i] : A[i][j];
    x[c] = det(m) / d;
  }
  DcFit f;
  f.k = 1 / x[0];
  f.R = x[1] * f.k * f.k;
  f.T0 = x[2] / x[1];
  return f;
}

/// The DC model of the scene's motor, fitted as motor_dc_model_test does:
/// no load but the bearing's 2 mN m at 4.5, 6 and 7.5 V, and 4 and 7 mN m
/// at 6 V (computed once per process).
inline const std::vector<DcPoint>& scene_dc_points() {
  static const std::vector<DcPoint> p = [] {
    std::vector<DcPoint> out;
    for (double v : {4.5, 6.0, 7.5}) out.push_back(dc_point(v, 0.002));
    for (double t : {0.004, 0.007}) out.push_back(dc_point(6.0, t));
    return out;
  }();
  return p;
}

/// The loop's resistance as built: the coil, the battery's inside and the
/// three wires of one circuit (lead, a spoke's wire, a return), ohm. With two
/// phases (a second commutator) one circuit of each is closed at a time, in
/// parallel across the battery: V = k w + R_bat I + R_branch I / 2 for the
/// total current I when the two branches carry alike, so the DC model's R is
/// the battery's inside plus the two branches in parallel.
inline double loop_resistance(World& w) {
  const double a = get_number(w, "upper_coil", "resistance") + get_number(w, "lead", "resistance") +
                   get_number(w, "spoke_N1_wire", "resistance") +
                   get_number(w, "upper_return", "resistance");
  const double battery = get_number(w, "battery", "internal_resistance");
  if (w.find("coil_b1").is_null()) return a + battery;
  const double b = get_number(w, "coil_b1", "resistance") + get_number(w, "lead_b", "resistance") +
                   get_number(w, "segment_n1_wire", "resistance") +
                   get_number(w, "b1_return", "resistance");
  return battery + a * b / (a + b);
}
inline double loop_resistance() {
  return with_scene(source(kScene).string(),
                    [](lua::LoadedScene& loaded) { return loop_resistance(*loaded.world); });
}

/// The bearing's viscous drag, N m s (mods/motor/layout.lua: a light oil).
constexpr double kBearingDrag = 9e-5;

// --- the torque constant against the angle, k(theta) ---------------------------------
//
// A coil's current I puts the torque I dPhi/dtheta on the rotor (Phi the flux
// the spokes link with it, theta the rotor's angle, anticlockwise) and the
// rotor's turning induces -dPhi/dt = -(dPhi/dtheta) w in it
// (flux_linkage.hpp). Counting the current the way the battery drives it
// (i = -I), the torque is k i and the back-EMF k w with
// k(theta) = -dPhi_c/dtheta, c the coil the commutation connects at theta.
// Over a turn the time mean of k w is <k> (over the angle) times the mean
// speed, whatever the ripple, so (V - I R) / w = <k> up to the inductive
// drop at the hand-overs. How the mean torque <k i> depends on V and w
// depends on L / R against the time k takes to change: with L / R short,
// i = (V - k w) / R follows k and the motor is a DC motor with
// k_dc = <k^2> / <k> and R_dc = R <k^2> / <k>^2 = R (1 + var(k) / <k>^2);
// with L / R long, i is nearly constant and k_dc = <k>, R_dc = R. The
// scene's cored coils' fit is the second (k = <k> within 0.6 %, R the
// loop's); session 18's coreless coils lie between the two (docs/motor.md,
// "Session 19").

/// The flux linking each coil, Wb, with the rotor put down turned by
/// `degrees` from where the bias magnet holds it and the slider held up
/// (both circuits open: no current, so no coil field): the flux code's own
/// Phi, read from electricity_from_magnetism after one step of 1 us (the
/// rotor moves by 1e-10 rad in it).
struct CoilFluxes {
  double upper = 0, lower = 0;
  double b1 = NAN, b2 = NAN;  ///< the second phase's coils (NAN: one phase)
};

/// `layout` is more of motor.layout's options, as Lua ("coil_gap = 0.002, ");
/// empty: the scene's.
inline CoilFluxes coil_fluxes(double degrees, const std::string& layout = "") {
  namespace fs = std::filesystem;
  const fs::path f =
      fs::temp_directory_path() / ("alloy_motor_flux_" + std::to_string(::getpid()) + ".lua");
  std::ofstream(f) << "world { dt = 1e-6, seconds = 1e-6 }\n"
                      "require \"motor.layout\" { "
                   << layout << "rotor_angle = " << std::setprecision(17) << degrees
                   << ", slider_release = 1 }\n";
  const CoilFluxes out = with_scene(f.string(), [](lua::LoadedScene& loaded) -> CoilFluxes {
    World& w = *loaded.world;
    w.step();
    const auto& faraday = dynamic_cast<const magnetism::ElectricityFromMagnetism&>(
        *w.stage(magnetism::ElectricityFromMagnetism::kName));
    const auto* upper = faraday.find(w.find("upper_coil"));
    const auto* lower = faraday.find(w.find("lower_coil"));
    if (!upper || !lower) return {NAN, NAN};
    CoilFluxes out{upper->linkage.flux, lower->linkage.flux};
    if (!w.find("coil_b1").is_null()) {
      const auto* b1 = faraday.find(w.find("coil_b1"));
      const auto* b2 = faraday.find(w.find("coil_b2"));
      if (!b1 || !b2) return {NAN, NAN};
      out.b1 = b1->linkage.flux, out.b2 = b2->linkage.flux;
    }
    return out;
  });
  fs::remove(f);
  return out;
}

/// k(theta) over one period of the rotor (90 degrees: the spokes alternate,
/// and the two coils' fluxes repeat every second spoke), at the midpoints of
/// a grid of `step` degrees from -22.5 (a hand-over) on, each the central
/// difference of the connected coil's Phi across its cell. The slider lies on
/// the spokes' ends at 135 degrees and a spoke carries it from 112.5 to 157.5
/// degrees (mods/motor/layout.lua): with the rotor at theta a north spoke, and
/// so the upper coil, is connected while (theta + 22.5) mod 90 < 45, else a
/// south spoke and the lower coil.
struct TorqueConstant {
  double step = 0;         ///< degrees
  std::vector<double> k;   ///< V s (N m / A), at -22.5 + (j + 1/2) step degrees
  double mean = 0;         ///< <k>, V s
  double mean_square = 0;  ///< <k^2>, V^2 s^2
  double dc_k() const { return mean_square / mean; }
  double dc_resistance_factor() const { return mean_square / (mean * mean); }
};

inline TorqueConstant measure_torque_constant(double step, const std::string& layout = "") {
  TorqueConstant t;
  t.step = step;
  const auto n = std::size_t(std::llround(90.0 / step));
  std::vector<CoilFluxes> phi(n + 1);
  for (std::size_t j = 0; j <= n; ++j) phi[j] = coil_fluxes(-22.5 + double(j) * step, layout);
  const double h = step * std::numbers::pi / 180;
  for (std::size_t j = 0; j < n; ++j) {
    const double mid = (double(j) + 0.5) * step;  // from -22.5
    const bool north = std::fmod(mid, 90.0) < 45.0;
    const double dphi = north ? phi[j + 1].upper - phi[j].upper : phi[j + 1].lower - phi[j].lower;
    if (std::isnan(phi[j].b1)) {
      t.k.push_back(-dphi / h);
      continue;
    }
    // Two phases in parallel across the battery (loop_resistance): the DC
    // model's k is the mean of the two circuits' k. The second ring's bars
    // are turned by 22.5 degrees (motor.layout's commutator_offset), so its
    // north bar, and coil_b1, is connected while (theta + 45) mod 90 < 45.
    const bool b_north = std::fmod(mid + 22.5, 90.0) < 45.0;
    const double dphi_b = b_north ? phi[j + 1].b1 - phi[j].b1 : phi[j + 1].b2 - phi[j].b2;
    t.k.push_back(-(dphi + dphi_b) / (2 * h));
  }
  for (double k : t.k) t.mean += k, t.mean_square += k * k;
  t.mean /= double(n), t.mean_square /= double(n);
  return t;
}

// --- the hoist (mods/hoist) ------------------------------------------------------------

constexpr double kDrumRadius = 0.005;  // mods/hoist/layout.lua: the 10 mm axle
constexpr double kBearingFriction = 0.002, kG = 9.81;

struct Lift {
  double speed = 0;   ///< the load's mean upward speed, m/s
  double wound = 0;   ///< the axle's mean angular velocity times the drum's radius, m/s
  double rose = 0;    ///< how far the load rose from 0.1 s to the end, m
  double lowest = 0;  ///< its lowest point below where it started, m (<= 0)
};

/// The hoist with a load of `mass` kg and a battery of `emf` V, run for 8 s;
/// speeds from 2 s to 8 s.
inline Lift run_lift(double mass, double emf) {
  namespace fs = std::filesystem;
  static int n = 0;
  const fs::path f = fs::temp_directory_path() / ("alloy_hoist_" + std::to_string(::getpid()) +
                                                  "_" + std::to_string(n++) + ".lua");
  std::ofstream(f)
      << "world { dt = 1 / 240, seconds = 8, settings = { [\"gravity.uniform\"] = "
         "{ g = { 0, -9.81, 0 } }, rigid_body = { solver = \"step\" }, "
         // as mods/hoist/scene.lua names it (session 17)
         "electricity = { induction_order = 2 } } }\n"
         "local h = require \"hoist.layout\" { load_mass = "
      << mass << ", emf = " << emf
      << " }\nfor _, s in ipairs(h.sliders) do at(h.slider_release, s, { pinned = false }) end\n";
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(f.string(), registry, load);
  fs::remove(f);
  World& w = *loaded.world;
  const ObjectId body = w.find("load"), axle = w.find("axle");
  std::vector<double> t, y, angle;
  auto sample = [&] {
    const double a = angle_z(std::get<Quat>(w.get(axle, "orientation")));
    angle.push_back(
        angle.empty() ? a : angle.back() + std::remainder(a - angle.back(), 2 * std::numbers::pi));
    t.push_back(w.time());
    y.push_back(std::get<Vec3>(w.get(body, "position")).y);
  };
  sample();
  const auto steps = std::llround(8.0 / w.dt());
  for (long long i = 0; i < steps; ++i) w.step(), sample();
  auto at = [&](double when) {
    return std::size_t(std::lower_bound(t.begin(), t.end(), when - 1e-9) - t.begin());
  };
  const std::size_t a = at(2.0), b = t.size() - 1;
  Lift l;
  l.speed = (y[b] - y[a]) / (t[b] - t[a]);
  l.wound = kDrumRadius * (angle[b] - angle[a]) / (t[b] - t[a]);
  l.rose = y[b] - y[at(0.1)];
  l.lowest = *std::min_element(y.begin(), y.end()) - y[0];
  return l;
}

/// run_lift, each load and battery once per process.
inline Lift lift(double mass, double emf) {
  static std::map<std::pair<double, double>, Lift> done;
  const auto key = std::make_pair(mass, emf);
  if (auto i = done.find(key); i != done.end()) return i->second;
  return done[key] = run_lift(mass, emf);
}

/// The hoist's lifting speed by the DC model of the scene's motor, with the
/// load's torque m g r added to the bearing's friction, m/s.
inline double hoist_model_speed(double mass, double emf) {
  const DcFit f = fit_dc_model(scene_dc_points());
  return kDrumRadius * f.speed(emf, mass * kG * kDrumRadius + kBearingFriction);
}

}  // namespace alloy::motor::test
