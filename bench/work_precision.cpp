// Work-precision of the analytic scenes: error against CPU run time per
// simulated second, for every step from 1/60 s to 1/1920 s and every solver
// setting, through the real World and plugins (tests/scenes/analytic_scenes).
//
//   free fall          exact y0 - g t^2 / 2
//   pendulum 0.05 rad  fine RK4 of theta'' = -(m g d / I) sin theta
//   pendulum 2.5 rad   the same, far from the small-angle regime
//   tumbling box       fine RK4 of Euler's equations + quaternion (Dzhanibekov flip)
//   two-body orbit     Kepler's circular orbit under gravity.nbody
//   RL circuit         I(t) = E/R (1 - e^(-t/tau))
//   RC, LC, RLC        issue 13: q(t) = C E (1 - e^(-t/RC)); the LC period
//                      2 pi sqrt(LC); q(t) = q0 e^(-at)(cos wt + a/w sin wt)
//   magnets            fine RK4 of the pole model's force law
//   induction          fine RK4 of a magnet flown through a closed coil: its
//                      motion and the coil's current, coupled by Faraday,
//                      the coil's flux the current sheet's (its near field,
//                      on by default) from closed forms on the axis
//   elastic pairs, Newton's cradle, bounce, lever and bar pendulums at large
//   swings, a 1000:1 chain, the tumbling box over 10 s: the closed-form
//   cases of issue 12 (energy drift in the table where the scene measures it)
//
// Methods: the rigid body's solver (dWorldStep; dWorldQuickStep at 10, 20,
// 40, 80 iterations; only where there are constraints to solve, else step
// and quick 40), the rigid body's substeps (when the resolver has them), and
// electricity's substeps (1, 2, 4, 8). The default (1/240 s, quick 40, rigid
// substeps 1, electricity substeps 4) is marked on every plot.
//
// Writes docs/bench/work_precision.csv, docs/bench/wp_<scene>.svg and the
// table between <!-- bench:work_precision --> markers in docs/performance.md.
//
//   build/bench/alloy_bench_work_precision [--quick] [--circuits | --induction] [--out DIR]
//                                          [--docs FILE] [--no-progress]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench/common/bench_common.hpp"
#include "tests/scenes/analytic_scenes.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace {

using namespace alloy::bench;
using alloy::scenes::analytic::Method;
using alloy::scenes::analytic::Result;
namespace an = alloy::scenes::analytic;

constexpr int kDefaultRate = 240;
constexpr double kPi = 3.14159265358979323846;

struct NamedMethod {
  std::string name;
  Method method;
  bool is_default = false;
};

struct Scene {
  std::string key;  // file names: wp_<key>.svg
  std::string title;
  std::string error_label;  // y axis, with units
  std::function<Result(double, const Method&)> run;
  std::vector<NamedMethod> methods;
};

struct Run {
  const Scene* scene;
  const NamedMethod* method;
  int rate;  // steps per second: dt = 1 / rate
  Result result;
  double cost = 0;  // CPU s per simulated s (best of the repeats)
};

std::vector<NamedMethod> rigid_methods(bool constrained) {
  std::vector<NamedMethod> m;
  m.push_back({"step", {.solver = "step"}});
  if (constrained)
    for (int it : {10, 20}) m.push_back({"quick " + std::to_string(it), {.iterations = it}});
  m.push_back({"quick 40", {}, true});
  if (constrained) m.push_back({"quick 80", {.iterations = 80}});
  // ODE's hinges alone, without the position projection (joint_projection.hpp).
  if (constrained) m.push_back({"quick 40, no projection", {.joint_projection = false}});
  if (an::rigid_substeps_supported())
    for (int sub : {2, 4})
      m.push_back({"quick 40, " + std::to_string(sub) + " substeps", {.rigid_substeps = sub}});
  return m;
}

// --- issue 13: circuits with capacitors against their closed forms -------------
// Built here rather than in tests/scenes so that the numbers are the same as
// tests/resolvers/electricity's (RcCharge..., LcPeriod..., RlcDecay...).

enum class Circuit { Rc, Lc, Rlc };

void join(alloy::World& w, const char* name, alloy::ObjectId from, int ft, alloy::ObjectId to,
          int tt) {
  const alloy::ObjectId id = w.create(name);
  w.set(id, "wire_from", from);
  w.set(id, "wire_from_terminal", std::int64_t(ft));
  w.set(id, "wire_to", to);
  w.set(id, "wire_to_terminal", std::int64_t(tt));
  w.set(id, "resistance", 0.0);  // 1 micro-ohm, the floor
}

/// RC: battery 6 V, 0.5 Ohm + resistor 99.5 Ohm + 1 mF (RC = 0.1 s), 0.5 s;
/// error: largest |q - q(t)| / C E. LC: 0.06 H, 20 mF charged to 0.12 C, six
/// periods (1.31 s); error: relative period error from the zero crossings.
/// RLC: the same with the coil's 1 Ohm, 0.45 s; error: largest |q - q(t)| / q0.
Result run_circuit(double dt, const Method& m, Circuit kind) {
  alloy::scenes::Sim sim(an::world_def(dt, m, /*gravity=*/false));
  alloy::World& w = *sim;
  Result r;
  const double e = 6.0, l = 0.06;
  const double c = kind == Circuit::Rc ? 1e-3 : 0.02, q0 = kind == Circuit::Rc ? 0.0 : 0.12;
  const alloy::ObjectId cap = w.create("cap");
  w.set(cap, "capacitance", c);
  w.set(cap, "plate_charge", q0);
  double r_loop = 0, seconds = 0;
  if (kind == Circuit::Rc) {
    const alloy::ObjectId b = w.create("battery");
    w.set(b, "emf", e);
    w.set(b, "internal_resistance", 0.5);
    const alloy::ObjectId res = w.create("resistor");
    w.set(res, "conductive", true);
    w.set(res, "resistance", 99.5);
    join(w, "w1", b, 1, res, 0);
    join(w, "w2", res, 1, cap, 0);
    join(w, "w3", cap, 1, b, 0);
    r_loop = 100 + 3e-6, seconds = 0.5;
  } else {
    const double rc = kind == Circuit::Rlc ? 1.0 : 0.0;
    const alloy::ObjectId coil = w.create("coil");
    w.set(coil, "inductance", l);
    w.set(coil, "resistance", rc);
    join(w, "w1", cap, 0, coil, 0);
    join(w, "w2", coil, 1, cap, 1);
    r_loop = rc + 2e-6, seconds = kind == Circuit::Rlc ? 0.45 : 6 * 2 * kPi * std::sqrt(l * c);
  }
  const double a = r_loop / (2 * l), om = std::sqrt(1 / (l * c) - a * a);
  const auto steps = std::uint64_t(std::llround(seconds / dt));
  bool non_finite = false;
  w.add_observer([&](const alloy::Event& ev) { non_finite |= ev.type == "non_finite"; });
  w.start();
  double q_prev = q0, first = -1, last = -1;
  int crossings = 0;
  const double t0 = cpu_seconds();
  for (std::uint64_t i = 1; i <= steps; ++i) {
    w.step();
    const double t = double(i) * dt, q = std::get<double>(w.get(cap, "plate_charge"));
    if (kind == Circuit::Rc) {
      r.error =
          std::max(r.error, std::abs(q - c * e * (1 - std::exp(-t / (r_loop * c)))) / (c * e));
    } else if (kind == Circuit::Rlc) {
      const double exact = q0 * std::exp(-a * t) * (std::cos(om * t) + a / om * std::sin(om * t));
      r.error = std::max(r.error, std::abs(q - exact) / q0);
    } else if ((q_prev > 0) != (q > 0)) {
      const double tc = t - dt + dt * q_prev / (q_prev - q);
      if (first < 0) first = tc;
      last = tc, ++crossings;
    }
    q_prev = q;
  }
  r.cpu_seconds = cpu_seconds() - t0;
  r.steps = steps;
  r.sim_seconds = double(steps) * dt;
  if (kind == Circuit::Lc) {
    r.exact = 2 * kPi / om;
    r.measured = crossings > 1 ? 2 * (last - first) / (crossings - 1) : 0;
    r.error = std::abs(r.measured - r.exact) / r.exact;
  }
  r.finite = !non_finite && std::isfinite(r.error);
  return r;
}

void add_circuit_scenes(std::vector<Scene>& s, const std::vector<NamedMethod>& elec) {
  s.push_back({"rc_circuit", "RC charge, RC = 0.1 s (0.5 s)",
               "largest charge error (relative to C E)",
               [](double dt, const Method& m) { return run_circuit(dt, m, Circuit::Rc); }, elec});
  s.push_back({"lc_circuit", "LC oscillation, period 0.218 s (6 periods)", "relative period error",
               [](double dt, const Method& m) { return run_circuit(dt, m, Circuit::Lc); }, elec});
  s.push_back({"rlc_circuit", "RLC decay, 1 Ohm, 0.06 H, 20 mF (0.45 s)",
               "largest charge error (relative to q0)",
               [](double dt, const Method& m) { return run_circuit(dt, m, Circuit::Rlc); }, elec});
}

std::vector<Scene> scenes() {
  std::vector<Scene> s;
  s.push_back({"free_fall", "Free fall (1 s from rest)", "largest height error (m)",
               [](double dt, const Method& m) { return an::run_free_fall(dt, m); },
               rigid_methods(false)});
  s.push_back({"pendulum_small", "Bar pendulum, 0.05 rad (5 s)", "largest angle error (rad)",
               [](double dt, const Method& m) { return an::run_pendulum(dt, m, 0.05); },
               rigid_methods(true)});
  s.push_back({"pendulum_large", "Bar pendulum, 2.5 rad (5 s)", "largest angle error (rad)",
               [](double dt, const Method& m) { return an::run_pendulum(dt, m, 2.5); },
               rigid_methods(true)});
  s.push_back({"tumbling_box", "Torque-free box near its intermediate axis (3 s)",
               "largest orientation error (rad)",
               [](double dt, const Method& m) { return an::run_tumbling_box(dt, m); },
               rigid_methods(false)});
  s.push_back({"orbit", "Two-body circular orbit, gravity.nbody (2 orbits)",
               "separation error after 2 orbits (relative)",
               [](double dt, const Method& m) { return an::run_orbit(dt, m); },
               rigid_methods(false)});
  // The closed-form cases of issue 12 (tests/resolvers/rigid_body/closed_form_test.cpp).
  s.push_back({"elastic_pair", "Head-on elastic pair, 1:1 (closed form v' = (0, 1))",
               "largest velocity error (m/s)",
               [](double dt, const Method& m) { return an::run_elastic_pair(dt, m, 1.0); },
               rigid_methods(false)});
  s.push_back({"elastic_pair_3to1", "Head-on elastic pair, 3:1 (closed form v' = (0.5, 1.5))",
               "largest velocity error (m/s)",
               [](double dt, const Method& m) { return an::run_elastic_pair(dt, m, 3.0); },
               rigid_methods(false)});
  s.push_back({"cradle", "Newton's cradle, 5 touching steel balls (closed form (0, 0, 0, 0, 1))",
               "largest velocity error (m/s)",
               [](double dt, const Method& m) { return an::run_cradle(dt, m); },
               rigid_methods(false)});
  s.push_back({"bounce", "Ball dropped 1 m, restitution 0.5 (rebound e^2 of the drop)",
               "relative error of the rebound height",
               [](double dt, const Method& m) { return an::run_bounce(dt, m, 0.5); },
               rigid_methods(false)});
  s.push_back({"lever_90", "2 cm ball hinged 1 m from its anchor, 90 degrees (2 periods)",
               "relative period error",
               [](double dt, const Method& m) { return an::run_swing(dt, m, true, kPi / 2); },
               rigid_methods(true)});
  s.push_back(
      {"lever_170", "2 cm ball hinged 1 m from its anchor, 170 degrees (2 periods)",
       "relative period error",
       [](double dt, const Method& m) { return an::run_swing(dt, m, true, 170 * kPi / 180); },
       rigid_methods(true)});
  s.push_back(
      {"bar_170", "Bar pendulum, 170 degrees (2 periods)", "relative period error",
       [](double dt, const Method& m) { return an::run_swing(dt, m, false, 170 * kPi / 180); },
       rigid_methods(true)});
  s.push_back({"lever_90_stretch", "2 cm ball hinged 1 m from its anchor, 90 degrees: the hinge",
               "largest relative stretch",
               [](double dt, const Method& m) {
                 Result r = an::run_swing(dt, m, true, kPi / 2);
                 r.error = r.stretch;
                 return r;
               },
               rigid_methods(true)});
  s.push_back({"bar_170_energy", "Bar pendulum, 170 degrees: energy drift (2 periods)",
               "energy drift per period, of the swing",
               [](double dt, const Method& m) {
                 Result r = an::run_swing(dt, m, false, 170 * kPi / 180);
                 r.error = r.energy_drift;
                 return r;
               },
               rigid_methods(true)});
  s.push_back({"heavy_chain", "Chain of 5 light links holding a ball 1000 times heavier (3 s)",
               "largest relative stretch",
               [](double dt, const Method& m) { return an::run_heavy_chain(dt, m); },
               rigid_methods(true)});
  s.push_back({"tumbling_box_10s", "Torque-free box near its intermediate axis (10 s)",
               "largest orientation error (rad)",
               [](double dt, const Method& m) { return an::run_tumbling_box(dt, m, 10.0); },
               rigid_methods(false)});
  s.push_back({"rolling_disk", "Disk rolling down 20 degrees (closed form a = 2/3 g sin theta)",
               "relative error of the acceleration",
               [](double dt, const Method& m) { return an::run_rolling(dt, m, true); },
               rigid_methods(false)});
  std::vector<NamedMethod> elec;
  for (int sub : {1, 2, 4, 8})
    elec.push_back({std::to_string(sub) + " substep" + (sub > 1 ? "s" : ""),
                    {.electricity_substeps = sub},
                    sub == 4});
  s.push_back({"rl_circuit", "RL circuit, tau = 10 ms (0.5 s)",
               "largest current error (relative to E/R)",
               [](double dt, const Method& m) { return an::run_rl(dt, m); }, elec});
  s.push_back({"magnets", "Two magnets, like poles facing (1 s)", "largest position error (m)",
               [](double dt, const Method& m) { return an::run_magnets(dt, m); },
               rigid_methods(false)});
  add_circuit_scenes(s, elec);  // issue 13
  // The coupling's timing, electricity's induction_order: 1 (the default)
  // and 2 (the EMF's motion at the step's end, the force's current at the
  // rigid body's kick; docs/magnetism.md "The coupling's timing").
  std::vector<NamedMethod> induct = elec;
  for (int sub : {1, 2, 4, 8})
    induct.push_back({std::to_string(sub) + " substep" + (sub > 1 ? "s" : "") + ", order 2",
                      {.electricity_substeps = sub, .induction_order = 2}});
  s.push_back(
      {"induction",
       "Magnet flown through a closed 4000-turn air coil (its sheet's near field) at 0.5 m/s, "
       "L/R = 3.3 ms (1.2 s)",
       "largest current error (relative to the peak)",
       [](double dt, const Method& m) { return an::run_induction(dt, m); }, induct});
  return s;
}

/// Runs once for the error, then repeats (full mode) until the timed CPU time
/// reaches `min_cpu`, keeping the cheapest: short runs are otherwise at the
/// mercy of the clock's grain and of other work on the machine.
Run measure(const Scene& sc, const NamedMethod& nm, int rate, double min_cpu) {
  Run r{&sc, &nm, rate, sc.run(1.0 / rate, nm.method)};
  r.cost = r.result.cost();
  double total = r.result.cpu_seconds;
  for (int rep = 0; rep < 200 && total < min_cpu; ++rep) {
    const Result again = sc.run(1.0 / rate, nm.method);
    total += again.cpu_seconds;
    r.cost = std::min(r.cost, again.cost());
  }
  return r;
}

std::string rate_label(int rate) {
  return "1/" + std::to_string(rate);
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt =
      Options::parse(argc, argv, "alloy_bench_work_precision", {"--circuits", "--induction"});
  const std::vector<int> rates =
      opt.quick ? std::vector<int>{120, 240} : std::vector<int>{60, 120, 240, 480, 960, 1920};
  std::vector<Scene> all = scenes();
  // --circuits: the RL, RC, LC and RLC scenes alone (a few seconds), written
  // to circuits.csv and the "circuits" section of docs/performance.md.
  const bool circuits = opt.flag("--circuits");
  if (circuits) std::erase_if(all, [](const Scene& s) { return !s.key.ends_with("_circuit"); });
  // --induction: the induced-EMF scene alone, to induction.csv and the
  // "induction" section.
  const bool induction = opt.flag("--induction");
  if (induction) std::erase_if(all, [](const Scene& s) { return s.key != "induction"; });
  const std::string stem = circuits ? "circuits" : induction ? "induction" : "work_precision";
  if (opt.quick)  // one method per scene: the default
    for (Scene& s : all)
      std::erase_if(s.methods, [](const NamedMethod& m) { return !m.is_default; });
  const double min_cpu = opt.quick ? 0.0 : 0.1;

  std::size_t total = 0;
  for (const Scene& s : all) total += s.methods.size() * rates.size();
  std::vector<Run> runs;
  {
    Progress bar("work-precision", total, opt.progress);
    for (const Scene& s : all)
      for (const NamedMethod& m : s.methods)
        for (int rate : rates) {
          runs.push_back(measure(s, m, rate, min_cpu));
          bar.tick();
        }
  }

  Csv csv(opt.file(stem + ".csv"),
          {"scene", "method", "solver", "iterations", "rigid_substeps", "electricity_substeps",
           "dt", "steps", "sim_seconds", "cpu_seconds", "cpu_per_sim_second", "error",
           "energy_drift", "momentum_drift", "finite", "default"});
  for (const Run& r : runs) {
    const Method& m = r.method->method;
    const bool def = r.method->is_default && r.rate == kDefaultRate;
    csv.row({r.scene->key, r.method->name, m.solver, Csv::cell(m.iterations),
             Csv::cell(m.rigid_substeps), Csv::cell(m.electricity_substeps),
             Csv::cell(1.0 / r.rate), Csv::cell((long long)r.result.steps),
             Csv::cell(r.result.sim_seconds), Csv::cell(r.result.cpu_seconds), Csv::cell(r.cost),
             Csv::cell(r.result.error), Csv::cell(r.result.energy_drift),
             Csv::cell(r.result.momentum_drift), r.result.finite ? "1" : "0", def ? "1" : "0"});
  }

  Table table({"scene", "method", "order", "error at 1/240 s", "cost at 1/240 s (ms/s)",
               "energy drift at 1/240 s", "on the Pareto front at"});
  std::string fronts;
  bool all_finite = true;
  for (const Scene& s : all) {
    std::vector<const Run*> mine;
    for (const Run& r : runs)
      if (r.scene == &s) mine.push_back(&r);
    std::vector<double> cost, err;
    for (const Run* r : mine) cost.push_back(r->cost), err.push_back(r->result.error);
    const std::vector<std::size_t> front = pareto_front(cost, err);
    auto on_front = [&](const Run* r) {
      for (std::size_t i : front)
        if (mine[i] == r) return true;
      return false;
    };

    Plot plot;
    plot.title = s.title;
    plot.x_label = "CPU run time per simulated second (s)";
    plot.y_label = s.error_label;
    for (const NamedMethod& m : s.methods) {
      Series series{.name = m.name};
      std::vector<double> dts, errs;
      std::string front_rates;
      const Run* at_default = nullptr;
      for (const Run* r : mine) {
        if (r->method != &m) continue;
        series.x.push_back(r->cost);
        series.y.push_back(r->result.error);
        dts.push_back(1.0 / r->rate);
        errs.push_back(r->result.error);
        all_finite = all_finite && r->result.finite;
        if (on_front(r)) front_rates += (front_rates.empty() ? "" : ", ") + rate_label(r->rate);
        if (r->rate == kDefaultRate) at_default = r;
        if (m.is_default && r->rate == kDefaultRate)
          plot.markers.push_back({r->cost, r->result.error, "default (1/240 s, " + m.name + ")"});
      }
      plot.series.push_back(std::move(series));
      table.row({s.key, m.name, fmt(loglog_slope(dts, errs), 2),
                 at_default ? fmt(at_default->result.error) : "-",
                 at_default ? fmt(1e3 * at_default->cost) : "-",
                 at_default && at_default->result.energy_drift >= 0
                     ? fmt(at_default->result.energy_drift)
                     : "-",
                 front_rates.empty() ? "-" : front_rates});
    }
    write_svg(plot, opt.file("wp_" + s.key + ".svg"));

    fronts += "- **" + s.key + "**: ";
    for (std::size_t k = 0; k < front.size(); ++k) {
      const Run* r = mine[front[k]];
      fronts += (k ? " < " : "") + r->method->name + " @ " + rate_label(r->rate) + " (" +
                fmt(r->result.error, 2) + ", " + fmt(1e3 * r->cost, 2) + " ms/s)";
    }
    fronts += "\n";
  }

  std::printf("%s\nPareto fronts, by increasing cost (error, CPU ms per simulated s):\n%s",
              table.str().c_str(), fronts.c_str());
  if (!opt.docs.empty()) {
    std::string md = "Orders are least-squares slopes of log(error) against log(dt) over " +
                     std::string("dt = 1/60 ... 1/1920 s; cost is CPU time per simulated second ") +
                     "(best of repeats). Generated by `alloy_bench_work_precision" +
                     (circuits ? " --circuits" : "") + "`; data in [bench/" + stem +
                     ".csv](bench/" + stem + ".csv).\n\n" + table.str() +
                     "\nPareto fronts of (cost, error), cheapest first, as method @ dt (error, "
                     "CPU ms per simulated s):\n\n" +
                     fronts + "\n";
    for (const Scene& s : all) md += "![" + s.title + "](bench/wp_" + s.key + ".svg)\n";
    splice(opt.docs, stem, md);
  }
  if (!all_finite) std::fprintf(stderr, "work-precision: a run froze an object (non-finite)\n");
  return all_finite ? 0 : 1;
}
