// motor_study: how the motor's steady speed depends on the battery's emf, the
// bearing's friction and drag, and the time step (docs/motor.md, "Tolerance").
// Each point is one 10 s run of mods/motor with one thing changed; the speed
// is the mean of the per-revolution mean angular velocities between frames
// 200 and 2000 (0.833 s to 8.333 s), the bars their least and greatest.
//
//   motor_study OUT_DIR      writes OUT_DIR/motor_tolerance.csv and .svg,
//                            motor_dc_model.csv (the DC-motor model's fit), and
//                            hoist.csv and .svg (mods/hoist's lifting speed)
//   motor_study --torque-constant OUT_DIR [COIL_H]
//                            k(theta) of the scene's coils and of session 18's
//                            coreless ones (OUT_DIR/motor_torque_constant.csv),
//                            and the coreless motor's DC fit and mean electrical
//                            torque at three steps (docs/motor.md, "Session 19");
//                            COIL_H: the coreless coils' inductance set to it
//   motor_study --live-cores [LAYOUT [LUA]]
//                            session 20's two-phase motor with live cores
//                            (motor.layout's live_cores = true), or the
//                            motor.layout options LAYOUT (Lua), LUA appended
//                            to the scene (e.g. at(...) lines): speed against
//                            the battery and the load at 1/240 and 1/960 s,
//                            the DC fit, <k>, starts from put-downs
//
// The SVG is written here, by hand: four panels of points with bars, no
// plotting package needed.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tests/motor/motor_support.hpp"

namespace {

using namespace alloy::motor::test;

struct Point {
  std::string sweep;
  double x = 0;  ///< the swept value, in the sweep's unit
  Steadiness s;
  std::size_t coil_switches = 0;  ///< electromagnet_on events in the window
  double turned = 0;              ///< turns in the window
  /// Coil switch-ons per turn: 8 when each spoke hands over cleanly, more
  /// when the slider bounces at hand-overs and a coil comes on twice.
  double switches_per_turn() const { return turned > 0.5 ? coil_switches / turned : NAN; }
};

struct Sweep {
  std::string name, label, unit;
  double scene_value;  ///< the scene's own value, marked on the plot
  std::vector<double> values;
  std::function<RunOptions(double)> options;
  bool log_x = false;
};

Point measure(const Sweep& sweep, double x) {
  RunOptions o = sweep.options(x);
  o.seconds = kSteadyTo + 0.1;
  const RunResult r = run_motor(kScene, o);
  Point p{sweep.name, x, steadiness(revolutions(r, kSteadyFrom, kSteadyTo)), 0, 0};
  for (const Record* e : r.of("electromagnet_on"))
    if (e->time >= kSteadyFrom && e->time < kSteadyTo && std::abs(e->value("current")) > 1e-3)
      ++p.coil_switches;
  p.turned = (r.angle[r.at(kSteadyTo)] - r.angle[r.at(kSteadyFrom)]) / (2 * std::numbers::pi);
  return p;
}

// --- a small SVG plotter -------------------------------------------------------------

std::string num(double v, int digits = 4) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

/// Round ticks over [lo, hi]: 1, 2 or 5 times a power of ten apart.
std::vector<double> ticks(double lo, double hi, int want = 6) {
  const double raw = (hi - lo) / want, mag = std::pow(10, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step)
    t.push_back(std::abs(v) < 1e-12 ? 0 : v);
  return t;
}

void panel(std::ostream& svg, const Sweep& sweep, const std::vector<Point>& points, double x0,
           double y0, double w, double h, double y_max,
           const std::function<double(double)>& model = {},
           const std::string& y_label = "steady speed, rad/s") {
  const double left = x0 + 58, right = x0 + w - 14, top = y0 + 30, bottom = y0 + h - 46;
  double lo = 1e300, hi = -1e300;
  for (double v : sweep.values) lo = std::min(lo, v), hi = std::max(hi, v);
  auto fx = [&](double v) {
    if (sweep.log_x)
      return left + (std::log(v) - std::log(lo)) / (std::log(hi) - std::log(lo)) * (right - left);
    const double pad = 0.04 * (hi - lo);
    return left + (v - (lo - pad)) / (hi - lo + 2 * pad) * (right - left);
  };
  auto fy = [&](double v) { return bottom - v / y_max * (bottom - top); };
  svg << "<text x='" << (left + right) / 2 << "' y='" << y0 + 18
      << "' text-anchor='middle' font-size='14' font-weight='bold'>" << sweep.label << "</text>\n";
  // Grid and axes.
  for (double t : ticks(0, y_max)) {
    svg << "<line x1='" << left << "' x2='" << right << "' y1='" << fy(t) << "' y2='" << fy(t)
        << "' stroke='#ddd'/>\n<text x='" << left - 6 << "' y='" << fy(t) + 4
        << "' text-anchor='end' font-size='11'>" << num(t) << "</text>\n";
  }
  std::vector<double> xt;
  if (sweep.log_x) {  // powers of two times the largest value
    for (double v = hi; v >= lo * (1 - 1e-9); v /= 2) xt.push_back(v);
  } else {
    xt = ticks(lo, hi);
  }
  for (double t : xt) {
    const std::string label = sweep.name == "dt" ? "1/" + num(std::round(1 / t)) : num(t, 2);
    svg << "<line x1='" << fx(t) << "' x2='" << fx(t) << "' y1='" << bottom << "' y2='"
        << bottom + 4 << "' stroke='#333'/>\n<text x='" << fx(t) << "' y='" << bottom + 17
        << "' text-anchor='middle' font-size='11'>" << label << "</text>\n";
  }
  svg << "<rect x='" << left << "' y='" << top << "' width='" << right - left << "' height='"
      << bottom - top << "' fill='none' stroke='#333'/>\n";
  svg << "<text x='" << (left + right) / 2 << "' y='" << bottom + 36
      << "' text-anchor='middle' font-size='12'>" << sweep.unit << "</text>\n";
  svg << "<text x='" << x0 + 16 << "' y='" << (top + bottom) / 2
      << "' text-anchor='middle' font-size='12' transform='rotate(-90 " << x0 + 16 << " "
      << (top + bottom) / 2 << ")'>" << y_label << "</text>\n";
  // The DC-motor model fitted to the emf and load sweeps (docs/motor.md).
  if (model) {
    std::string d;
    for (int i = 0; i <= 60; ++i) {
      const double v = sweep.values.front() + (sweep.values.back() - sweep.values.front()) * i / 60;
      const double y = model(v);
      if (y < 0 || y > y_max) continue;
      d += (d.empty() ? "M" : " L") + num(fx(v), 6) + " " + num(fy(y), 6);
    }
    svg << "<path d='" << d << "' fill='none' stroke='#2a2' stroke-width='1.5' "
        << "stroke-dasharray='6 3'/>\n";
  }
  // The scene's value.
  svg << "<line x1='" << fx(sweep.scene_value) << "' x2='" << fx(sweep.scene_value) << "' y1='"
      << top << "' y2='" << bottom << "' stroke='#c33' stroke-dasharray='4 3'/>\n";
  // The points: mean with the range of the per-revolution means; x where it did not run.
  std::string line;
  for (const Point& p : points) {
    if (p.sweep != sweep.name) continue;
    const double x = fx(p.x);
    if (p.s.turns < 2 || p.s.mean <= 0) {
      svg << "<path d='M" << x - 4 << " " << fy(0) - 4
          << " l8 8 m0 -8 l-8 8' stroke='#c33' stroke-width='2'/>\n";
      continue;
    }
    line += (line.empty() ? "M" : " L") + num(x, 6) + " " + num(fy(p.s.mean), 6);
    svg << "<line x1='" << x << "' x2='" << x << "' y1='" << fy(p.s.min) << "' y2='" << fy(p.s.max)
        << "' stroke='#247' stroke-width='1.5'/>\n<circle cx='" << x << "' cy='" << fy(p.s.mean)
        << "' r='3.5' "
        << (p.switches_per_turn() > 8.5 ? "fill='white' stroke='#247' stroke-width='1.5'"
                                        : "fill='#247'")
        << "/>\n";
  }
  if (!line.empty())
    svg << "<path d='" << line << "' fill='none' stroke='#247' stroke-opacity='0.5'/>\n";
}

}  // namespace

using namespace alloy;
using namespace alloy::motor::test;

/// Session 18's coreless coils (docs/motor.md), as motor.layout options.
constexpr const char* kCoreless =
    "coil_gap = 0.0015, coil_length = 0.02, coil_diameter = 0.058, turns = 5100, "
    "wire_diameter = 0.25e-3, core = \"air\", core_diameter = 0.0174, bias_distance = 0.14, ";

/// The coreless motor at emf V and bearing friction T, 6 s at step dt, from
/// 2 s: its mean speed and coil current, and the mean electrical torque
/// sum_c I_c dPhi_c/dtheta, the coils' currents times their k(theta).
struct TorquePoint {
  double emf, load, speed, current, torque;
};

TorquePoint coreless_point(const std::filesystem::path& scene, double emf, double load, double dt,
                           const std::vector<CoilFluxes>& phi, double step) {
  return with_scene(scene.string(), [&](lua::LoadedScene& loaded) {
    World& w = *loaded.world;
    w.set_dt(dt);
    w.set(w.find("battery"), "emf", emf);
    w.set(w.find("bearing"), "joint_friction", load);
    const ObjectId upper = w.find("upper_coil"), lower = w.find("lower_coil"),
                   axle = w.find("axle");
    const std::size_t n = phi.size() - 1;
    const double h = step * std::numbers::pi / 180;
    // dPhi/dtheta at the cells' midpoints, linearly between them.
    auto slope = [&](double theta, bool up) {
      double deg = std::fmod(theta * 180 / std::numbers::pi + 22.5, 90.0);
      if (deg < 0) deg += 90;
      const double x = deg / step - 0.5, j = std::floor(x), f = x - j;
      auto cell = [&](double m) {
        const auto c = std::size_t(std::fmod(m + double(n), double(n)));
        return up ? (phi[c + 1].upper - phi[c].upper) / h : (phi[c + 1].lower - phi[c].lower) / h;
      };
      return cell(j) * (1 - f) + cell(j + 1) * f;
    };
    double angle = 0, torque = 0, speed = 0, current = 0;
    long count = 0;
    const auto steps = std::llround(6.0 / dt), from = std::llround(2.0 / dt);
    for (long long s = 0; s < steps; ++s) {
      w.step();
      const double a = angle_z(std::get<Quat>(w.get(axle, "orientation")));
      angle = s == 0 ? a : angle + std::remainder(a - angle, 2 * std::numbers::pi);
      if (s < from) continue;
      const double iu = std::get<double>(w.get(upper, "current"));
      const double il = std::get<double>(w.get(lower, "current"));
      torque += iu * slope(angle, true) + il * slope(angle, false);
      speed += std::get<Vec3>(w.get(axle, "angular_velocity")).z;
      current -= iu + il;
      ++count;
    }
    return TorquePoint{emf, load, speed / double(count), current / double(count),
                       torque / double(count)};
  });
}

int torque_constant_study(const std::filesystem::path& out, double inductance) {
  const double step = 0.25;
  const TorqueConstant cored = measure_torque_constant(step),
                       coreless = measure_torque_constant(step, kCoreless);
  std::ofstream csv(out / "motor_torque_constant.csv");
  csv << "degrees_from_hand_over,k_cored_V_s,k_coreless_V_s\n";
  for (std::size_t j = 0; j < cored.k.size(); ++j)
    csv << num((double(j) + 0.5) * step, 6) << "," << num(cored.k[j], 6) << ","
        << num(coreless.k[j], 6) << "\n";
  for (const auto& [name, t] : {std::pair{"cored (the scene's)", &cored}, {"coreless", &coreless}})
    std::cout << name << ": <k> " << num(t->mean) << " V s, from "
              << num(*std::min_element(t->k.begin(), t->k.end())) << " to "
              << num(*std::max_element(t->k.begin(), t->k.end())) << ", var(k) / <k>^2 "
              << num(t->dc_resistance_factor() - 1) << ", <k^2> / <k> " << num(t->dc_k())
              << " V s\n";
  // The coreless motor as a scene, at the scene's settings.
  namespace fs = std::filesystem;
  const fs::path scene =
      fs::temp_directory_path() / ("alloy_motor_coreless_" + std::to_string(::getpid()) + ".lua");
  std::ofstream(scene) << "world { dt = 1 / 240, seconds = 6, settings = { [\"gravity.uniform\"] = "
                          "{ g = { 0, -9.81, 0 } }, rigid_body = { solver = \"step\" }, "
                          "electricity = { induction_order = 2 } } }\n"
                          "local m = require \"motor.layout\" { "
                       << kCoreless << "}\nat(m.slider_release, \"slider\", { pinned = false })\n";
  if (inductance > 0)  // the coils rewound to this inductance, H, before the slider lands
    for (const char* coil : {"upper_coil", "lower_coil"})
      std::ofstream(scene, std::ios::app)
          << "at(0.05, \"" << coil << "\", { inductance = " << inductance << " })\n";
  std::vector<CoilFluxes> phi;
  for (std::size_t j = 0; j <= std::size_t(std::llround(90 / step)); ++j)
    phi.push_back(coil_fluxes(-22.5 + double(j) * step, kCoreless));
  const double R = with_scene(
      scene.string(), [](lua::LoadedScene& built) { return loop_resistance(*built.world); });
  const double drag = kBearingDrag;
  std::cout << "coreless loop " << num(R) << " ohm; short-L prediction: k "
            << num((coreless.mean_square / R + drag) / (coreless.mean / R)) << " V s, R "
            << num((coreless.mean_square / R + drag) / std::pow(coreless.mean / R, 2))
            << " ohm; long-L: k " << num(coreless.mean) << ", R " << num(R) << "\n";
  for (double dt : {1.0 / 240, 1.0 / 480, 1.0 / 960}) {
    std::vector<DcPoint> dc;
    std::vector<TorquePoint> tp;
    for (const auto& [v, t] :
         {std::pair{4.5, 0.002}, {6.0, 0.002}, {7.5, 0.002}, {6.0, 0.004}, {6.0, 0.0055}}) {
      tp.push_back(coreless_point(scene, v, t, dt, phi, step));
      dc.push_back({v, t, tp.back().speed, tp.back().current});
    }
    const DcFit f = fit_dc_model(dc);
    std::cout << "dt 1/" << num(1 / dt) << ": DC fit from the speeds k " << num(f.k) << " V s, R "
              << num(f.R) << " ohm, T0 " << num(1e3 * f.T0) << " mN m\n";
    for (const TorquePoint& p : tp)
      std::cout << "  " << num(p.emf) << " V, " << num(1e3 * p.load) << " mN m: " << num(p.speed)
                << " rad/s (model " << num(f.speed(p.emf, p.load)) << "), " << num(1e3 * p.current)
                << " mA, (V - I R) / w " << num((p.emf - p.current * R) / p.speed)
                << " V s, electrical torque " << num(1e3 * p.torque)
                << " mN m, short-L model at this speed "
                << num(1e3 * (coreless.mean * p.emf - coreless.mean_square * p.speed) / R)
                << ", left after the load and the oil "
                << num(1e3 * (p.torque - p.load - drag * p.speed)) << " mN m\n";
  }
  fs::remove(scene);
  std::cout << "wrote " << (out / "motor_torque_constant.csv").string() << "\n";
  return 0;
}

/// A motor.layout variant as a scene file (the scene's settings, every slider
/// let go at slider_release), written to the temp folder; `layout` is Lua.
std::filesystem::path variant_scene(const std::string& layout, const std::string& tag,
                                    const std::string& extra = "") {
  namespace fs = std::filesystem;
  const fs::path f = fs::temp_directory_path() /
                     ("alloy_motor_variant_" + std::to_string(::getpid()) + "_" + tag + ".lua");
  std::ofstream(f) << "world { dt = 1 / 240, seconds = 10, settings = { [\"gravity.uniform\"] = "
                      "{ g = { 0, -9.81, 0 } }, rigid_body = { solver = \"step\" }, "
                      "electricity = { induction_order = 2 } } }\n"
                      "local m = require \"motor.layout\" { "
                   << layout
                   << " }\nfor _, s in ipairs(m.sliders) do at(m.slider_release, s, { pinned = "
                      "false }) end\n"
                   << extra << "\n";
  return f;
}

/// One steady point of a variant: mean speed and current from t0 to t1, and
/// coil switch-ons per turn (8 with clean hand-overs of one commutator, 16
/// with two).
struct VariantPoint {
  DcPoint dc;
  double switches_per_turn = NAN;
};

VariantPoint variant_point(const std::filesystem::path& scene, double emf, double load, double dt,
                           double t0 = 2.0, double t1 = 6.0) {
  const RunResult r =
      run_motor(scene.string(), {.dt = dt, .seconds = t1, .emf = emf, .friction = load});
  VariantPoint p{{emf, load, mean_speed(r, t0, t1), mean_between(r, r.coil_current, t0, t1)}};
  std::size_t on = 0;
  for (const Record* e : r.of("electromagnet_on"))
    if (e->time >= t0 && e->time < t1 && std::abs(e->value("current")) > 1e-3) ++on;
  const double turns = (r.angle[r.at(t1)] - r.angle[r.at(t0)]) / (2 * std::numbers::pi);
  if (turns > 0.5) p.switches_per_turn = double(on) / turns;
  return p;
}

/// Session 20 (docs/motor.md, "Session 20: live cores"): a motor.layout
/// variant (default: live_cores = true) measured as the tests measure the
/// scene: speed against the battery and the load at the scene's step and at
/// 1/960 s, the DC model fitted from the speeds (k, R against the loop's R as
/// built, T0), (V - I R) / w against <k> from k(theta), and the start from
/// rotors put down out of place.
int variant_study(const std::string& layout, const std::string& extra) {
  namespace fs = std::filesystem;
  const fs::path scene = variant_scene(layout, "study", extra);
  const double R = with_scene(
      scene.string(), [](lua::LoadedScene& built) { return loop_resistance(*built.world); });
  const std::string more = layout.empty() ? "" : layout + ", ";
  const TorqueConstant t = measure_torque_constant(0.5, more);
  std::cout << "layout { " << layout << " }: loop " << num(R) << " ohm; k(theta): <k> "
            << num(t.mean) << " V s, from " << num(*std::min_element(t.k.begin(), t.k.end()))
            << " to " << num(*std::max_element(t.k.begin(), t.k.end())) << ", var(k)/<k>^2 "
            << num(t.dc_resistance_factor() - 1) << "\n";
  for (double dt : {1.0 / 240, 1.0 / 960}) {
    std::cout << "dt 1/" << num(1 / dt) << ":\n";
    std::vector<DcPoint> fit_points;
    for (const auto& [v, load] : {std::pair{4.5, 0.002},
                                  {5.0, 0.002},
                                  {6.0, 0.002},
                                  {7.0, 0.002},
                                  {7.5, 0.002},
                                  {6.0, 0.003},
                                  {6.0, 0.004},
                                  {6.0, 0.005},
                                  {6.0, 0.007}}) {
      const VariantPoint p = variant_point(scene, v, load, dt);
      const bool turns = p.dc.speed > 0.5;
      // The test's five points, where the motor turns.
      const bool test_point = (load == 0.002 && (v == 4.5 || v == 6.0 || v == 7.5)) ||
                              (v == 6.0 && (load == 0.004 || load == 0.007));
      if (turns && test_point) fit_points.push_back(p.dc);
      std::cout << "  " << num(v) << " V, " << num(1e3 * load) << " mN m: " << num(p.dc.speed)
                << " rad/s, " << num(1e3 * p.dc.current) << " mA, switch-ons a turn "
                << num(p.switches_per_turn, 3);
      if (turns) std::cout << ", (V - I R) / w " << num((v - p.dc.current * R) / p.dc.speed);
      std::cout << (test_point ? " [fit]" : "") << "\n";
    }
    if (fit_points.size() >= 3) {
      const DcFit f = fit_dc_model(fit_points);
      double worst = 0;
      for (const DcPoint& p : fit_points)
        worst = std::max(worst, std::abs(p.speed - f.speed(p.emf, p.load)) / p.speed);
      std::cout << "  DC fit (" << fit_points.size() << " points): k " << num(f.k) << " V s (<k> "
                << num(t.mean) << "), R " << num(f.R) << " ohm (loop " << num(R) << ": "
                << num(100 * (f.R / R - 1), 3) << " %), T0 " << num(1e3 * f.T0)
                << " mN m; worst point " << num(100 * worst, 3) << " % off\n";
    }
  }
  std::cout << "put down out of place (slider let go at 3 s; mean speed 5 s to 8 s):\n";
  for (int degrees : {-40, -20, -10, 10, 20, 40}) {
    const fs::path f = variant_scene(
        more + "rotor_angle = " + std::to_string(degrees) + ", slider_release = 3", "put", extra);
    const RunResult r = run_motor(f.string(), {.seconds = 8.0});
    fs::remove(f);
    std::cout << "  " << degrees << " deg: " << num(mean_speed(r, 5.0, 8.0)) << " rad/s\n";
  }
  fs::remove(scene);
  return 0;
}

int main(int argc, char** argv) {
  if ((argc == 3 || argc == 4) && std::string(argv[1]) == "--torque-constant")
    return torque_constant_study(argv[2], argc == 4 ? std::stod(argv[3]) : 0.0);
  if (argc >= 2 && argc <= 4 && std::string(argv[1]) == "--live-cores")
    return variant_study(argc >= 3 ? argv[2] : "live_cores = true", argc == 4 ? argv[3] : "");
  if (argc != 2) {
    std::cerr
        << "usage: motor_study OUT_DIR   (writes OUT_DIR/motor_tolerance.csv and .svg)\n"
           "       motor_study --torque-constant OUT_DIR [COIL_H]   (k(theta), docs/motor.md)\n"
           "       motor_study --live-cores [LAYOUT [LUA]]   (session 20's two-phase motor, or "
           "LAYOUT;\n"
           "                                                  LUA: more of the scene, e.g. "
           "at(...))\n";
    return 2;
  }
  const std::filesystem::path out = argv[1];
  const std::vector<Sweep> sweeps = {
      {"emf",
       "Battery emf",
       "emf, V (the scene: 6 V)",
       6.0,
       {2, 2.5, 3, 3.5, 4, 4.5, 5, 5.4, 6, 6.6, 7, 7.5, 8, 9},
       [](double v) { return RunOptions{.emf = v}; }},
      {"friction",
       "Bearing dry friction",
       "friction torque, N m (the scene: 0.002)",
       0.002,
       {0, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.007, 0.008, 0.009, 0.010, 0.012, 0.014},
       [](double v) { return RunOptions{.friction = v}; }},
      {"dt",
       "Time step",
       "dt, s (the scene: 1/240)",
       1.0 / 240,
       {1.0 / 120, 1.0 / 160, 1.0 / 240, 1.0 / 320, 1.0 / 480, 1.0 / 720, 1.0 / 960, 1.0 / 1440,
        1.0 / 1920},
       [](double v) { return RunOptions{.dt = v}; },
       true},
      {"drag",
       "Bearing viscous drag",
       "drag, N m s (the scene: 9e-5)",
       9e-5,
       {1e-5, 3e-5, 9e-5, 3e-4, 1e-3, 3e-3, 9e-3},
       [](double v) { return RunOptions{.drag_scale = v / 9e-5}; },
       true},
  };
  std::vector<Point> points;
  std::ofstream csv(out / "motor_tolerance.csv");
  csv << "sweep,value,turns,mean_rad_s,min_rad_s,max_rad_s,spread,coil_switches_per_turn\n";
  for (const Sweep& sw : sweeps)
    for (double v : sw.values) {
      const Point p = measure(sw, v);
      points.push_back(p);
      csv << sw.name << "," << num(v, 8) << "," << p.s.turns << "," << num(p.s.mean, 6) << ","
          << num(p.s.min, 6) << "," << num(p.s.max, 6) << ","
          << num(p.s.turns ? p.s.spread() : NAN, 4) << "," << num(p.switches_per_turn(), 3) << "\n";
      std::cout << sw.name << " " << num(v, 6) << ": " << p.s.turns << " turns, "
                << num(p.s.mean, 4) << " rad/s, spread "
                << num(p.s.turns ? 100 * p.s.spread() : NAN, 3) << " %, "
                << num(p.switches_per_turn(), 3) << " coil switch-ons a turn\n";
    }
  // The DC-motor model, w = V / k - R (T + T0) / k^2, fitted to the points
  // of the emf and the load (dry friction) sweeps where it turns cleanly.
  std::vector<DcPoint> dc;
  for (const Point& p : points)
    if (p.s.turns >= 2 && p.s.mean > 0 && p.s.max < 6.5 && p.switches_per_turn() < 8.5) {
      if (p.sweep == "emf") dc.push_back({p.x, 0.002, p.s.mean, 0});
      if (p.sweep == "friction") dc.push_back({6.0, p.x, p.s.mean, 0});
    }
  const DcFit fit = fit_dc_model(dc);
  std::cout << "DC model fitted to " << dc.size() << " points: k " << num(fit.k) << " V s, R "
            << num(fit.R) << " ohm (the loop as built: " << num(loop_resistance()) << "), T0 "
            << num(1e3 * fit.T0) << " mN m; no-load speed at 6 V " << num(fit.no_load_speed(6))
            << " rad/s, stall torque at 6 V " << num(1e3 * fit.stall_torque(6)) << " mN m\n";
  double worst = 0;
  for (const DcPoint& p : dc)
    worst = std::max(worst, std::abs(p.speed - fit.speed(p.emf, p.load)) / p.speed);
  std::cout << "  worst point off the model: " << num(100 * worst, 3) << " %\n";
  std::ofstream dcsv(out / "motor_dc_model.csv");
  dcsv << "emf_V,load_N_m,speed_rad_s,model_rad_s\n";
  for (const DcPoint& p : dc)
    dcsv << num(p.emf, 6) << "," << num(p.load, 6) << "," << num(p.speed, 6) << ","
         << num(fit.speed(p.emf, p.load), 6) << "\n";
  const std::function<double(double)> models[4] = {[&](double v) { return fit.speed(v, 0.002); },
                                                   [&](double t) { return fit.speed(6, t); },
                                                   {},
                                                   {}};
  double y_max = 0;
  for (const Point& p : points) y_max = std::max(y_max, p.s.max);
  y_max = std::ceil(y_max / 2) * 2;
  const double w = 460, h = 300;
  std::ofstream svg(out / "motor_tolerance.svg");
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << 2 * w << "' height='" << 2 * h + 66
      << "' font-family='sans-serif'>\n<rect width='100%' height='100%' fill='white'/>\n";
  svg << "<text x='" << w
      << "' y='20' text-anchor='middle' font-size='15' font-weight='bold'>mods/motor: the "
         "steady speed, one thing changed at a time</text>\n<text x='"
      << w
      << "' y='38' text-anchor='middle' font-size='12'>dot: mean of the per-revolution mean "
         "angular velocities, "
         "frames 200-2000; bar: least to greatest; x: did not turn; dashed: the scene's "
         "value</text>\n<text x='"
      << w
      << "' y='54' text-anchor='middle' font-size='12'>filled: 8 coil switch-ons a turn, one per "
         "spoke; hollow: "
         "more (the slider bounces at hand-overs); green dashes: the DC-motor model</text>\n";
  for (std::size_t i = 0; i < sweeps.size(); ++i)
    panel(svg, sweeps[i], points, (i % 2) * w, 66 + (i / 2) * h, w, h, y_max, models[i]);
  svg << "</svg>\n";
  std::cout << "wrote " << (out / "motor_tolerance.csv").string() << " and "
            << (out / "motor_tolerance.svg").string() << "\n";

  // The hoist (mods/hoist): the lifting speed against the load at 6 V and
  // against the battery with 100 g, each 8 s, and the DC model's line.
  const Sweep hoist_sweeps[2] = {{"mass",
                                  "The hoist: lifting speed against the load",
                                  "load, g (the scene: 100 g)",
                                  100,
                                  {20, 50, 100, 150, 190, 200, 250},
                                  {}},
                                 {"hoist_emf",
                                  "The hoist: lifting speed against the battery",
                                  "emf, V (100 g)",
                                  6.0,
                                  {4.5, 5, 6, 7, 7.5, 8, 9},
                                  {}}};
  std::vector<Point> lifts;
  std::ofstream hcsv(out / "hoist.csv");
  hcsv << "load_kg,emf_V,lift_mm_s,axle_times_r_mm_s,model_mm_s\n";
  for (const Sweep& sw : hoist_sweeps)
    for (double v : sw.values) {
      const double mass = sw.name == "mass" ? v / 1e3 : 0.1, emf = sw.name == "mass" ? 6.0 : v;
      const Lift l = lift(mass, emf);
      const bool lifted = l.rose > 0.01;
      Point p{sw.name, v, {}, 8, 1};
      p.s.turns = lifted ? 5 : 0;
      p.s.mean = p.s.min = p.s.max = lifted ? 1e3 * l.speed : 0;
      lifts.push_back(p);
      hcsv << mass << "," << emf << "," << num(1e3 * l.speed, 5) << "," << num(1e3 * l.wound, 5)
           << "," << num(1e3 * hoist_model_speed(mass, emf), 5) << "\n";
      std::cout << "hoist " << 1e3 * mass << " g, " << emf
                << " V: " << (lifted ? num(1e3 * l.speed, 4) + " mm/s" : std::string("not lifted"))
                << ", the model " << num(1e3 * hoist_model_speed(mass, emf), 4) << " mm/s\n";
    }
  std::ofstream hsvg(out / "hoist.svg");
  hsvg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << 2 * w << "' height='" << h + 50
       << "' font-family='sans-serif'>\n<rect width='100%' height='100%' fill='white'/>\n"
       << "<text x='" << w
       << "' y='20' text-anchor='middle' font-size='12'>dot: the load's mean upward speed, "
          "2 s to 8 s; x: not lifted; green dashes: the DC-motor model of the motor, "
          "fitted without the string</text>\n";
  const std::function<double(double)> hoist_models[2] = {
      [](double g) { return 1e3 * hoist_model_speed(g / 1e3, 6); },
      [](double v) { return 1e3 * hoist_model_speed(0.1, v); }};
  for (int i = 0; i < 2; ++i)
    panel(hsvg, hoist_sweeps[i], lifts, i * w, 30, w, h, 40, hoist_models[i],
          "lifting speed, mm/s");
  hsvg << "</svg>\n";
  std::cout << "wrote " << (out / "hoist.csv").string() << " and " << (out / "hoist.svg").string()
            << "\n";
  return 0;
}
