// alloy_bench_coupled: work-precision of the coupled scenes. The doorbell's
// strike period and the motor's steady speed (bench/coupled_scenes.hpp),
// against a reference run at a very small step, over the world's step (the
// coupling window, 1/60 to 1/1920 s), the rigid-body solver (ODE's dWorldStep,
// dWorldQuickStep at several iteration counts) and the substeps of the
// electricity and the rigid body. Writes docs/bench/coupled.csv,
// coupled_doorbell.svg, coupled_motor.svg and the "coupled" section of
// docs/performance.md.
//
//   alloy_bench_coupled [--quick] [--out DIR] [--docs FILE] [--no-progress]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "bench/common/bench_common.hpp"
#include "bench/coupled_scenes.hpp"

namespace {

using namespace alloy::bench;
using namespace alloy::bench::coupled;

struct Method {
  std::string name;
  Rates over;  ///< what differs from the scene
  bool is_default = false;
};

std::string describe(const Rates& r) {
  std::string s = r.solver == "step" ? "step" : "quick " + std::to_string(r.iterations) + " it";
  s += ", elec " + std::to_string(r.electricity_substeps);
  if (r.rigid_substeps > 1) s += ", rigid " + std::to_string(r.rigid_substeps);
  for (const auto& [stage, n] : r.every) s += ", " + stage + " every " + std::to_string(n);
  return s;
}

/// The scene's own rates, then one change at a time: each other solver, the
/// electricity's substeps down to 1 and up to 16, the rigid body's to 2.
std::vector<Method> methods(const Rates& scene, bool quick) {
  std::vector<Method> out;
  out.push_back({describe(scene) + " (scene)", {}, true});
  auto add = [&](Rates over) {
    const Rates r = with(scene, over);
    const std::string name = describe(r);
    for (const Method& m : out)
      if (describe(with(scene, m.over)) == name) return;  // the scene's own, already there
    out.push_back({name, over, false});
  };
  add({.solver = scene.solver == "step" ? "quick" : "step"});
  if (quick) return out;
  for (int it : {10, 20, 40}) add({.solver = "quick", .iterations = it});
  add({.electricity_substeps = 1});
  add({.electricity_substeps = 16});
  add({.rigid_substeps = 2});
  return out;
}

struct Point {
  double dt;
  Measure m;
  double error;
};

std::string percent(double e) { return std::isfinite(e) ? fmt(100 * e, 2) + " %" : "fails"; }

}  // namespace

int main(int argc, char** argv) {
  const Options o = Options::parse(argc, argv, "alloy_bench_coupled");
  const std::vector<int> rates_per_s =
      o.quick ? std::vector<int>{60, 240, 960} : std::vector<int>{60, 120, 240, 480, 960, 1920};
  // The reference and the next coarser step, to show how far it has converged.
  const int ref_n = o.quick ? 3840 : 30720, check_n = ref_n / 2;
  const int repeats = o.quick ? 1 : 2;  // timing: the least CPU time of these

  const std::vector<Scene> scenes = {doorbell_scene(), motor_scene()};
  std::vector<Rates> defaults;
  std::vector<std::vector<Method>> all_methods;
  std::size_t total = 0;
  for (const Scene& s : scenes) {
    defaults.push_back(scene_rates(s.mod));
    all_methods.push_back(methods(defaults.back(), o.quick));
    total += 2 + all_methods.back().size() * rates_per_s.size() * repeats;
  }

  Csv csv(o.file("coupled.csv"),
          {"scene", "method", "default", "dt", "solver", "iterations", "electricity_substeps",
           "rigid_substeps", "value", "count", "relative_error", "cpu_per_simulated_s",
           "status"});
  std::ostringstream md;
  md << "\nCommand: `build/bench/alloy_bench_coupled` (or `make bench`); raw data "
        "`docs/bench/coupled.csv`.\n";
  Progress progress("coupled", total, o.progress);
  int exit_code = 0;

  for (std::size_t si = 0; si < scenes.size(); ++si) {
    const Scene& scene = scenes[si];
    const Rates& def = defaults[si];
    const Measure ref = scene.measure(with(def, {.dt = 1.0 / ref_n}));
    progress.tick();
    const Measure check = scene.measure(with(def, {.dt = 1.0 / check_n}));
    progress.tick();
    const double reference = ref.value;
    if (!ref.ok()) {
      std::fprintf(stderr, "%s: the reference run fails\n", scene.mod.c_str());
      exit_code = 1;
    }
    auto row = [&](const std::string& method, bool is_default, const Rates& r, const Measure& m,
                   double err) {
      csv.row({scene.mod, method, Csv::cell(int(is_default)), Csv::cell(r.dt), r.solver,
               Csv::cell(r.iterations), Csv::cell(r.electricity_substeps),
               Csv::cell(r.rigid_substeps), Csv::cell(m.value), Csv::cell(m.count),
               Csv::cell(err), Csv::cell(m.cost()), m.ok() ? "ok" : "fails"});
    };
    row("reference", false, with(def, {.dt = 1.0 / ref_n}), ref, 0);
    row("reference check", false, with(def, {.dt = 1.0 / check_n}), check,
        relative_error(check, reference));

    Plot plot;
    plot.title = "The " + scene.mod + ": " + scene.quantity + " against run time";
    plot.x_label = "CPU time per simulated second (s)";
    plot.y_label = "relative error of the " + scene.quantity.substr(0, scene.quantity.find(" (")) +
                   " (vs the 1/" + std::to_string(ref_n) + " s reference)";
    std::vector<double> all_cost, all_err;
    std::vector<std::string> all_name;
    Table table([&] {
      std::vector<std::string> h = {"method"};
      for (int n : rates_per_s) h.push_back("dt 1/" + std::to_string(n));
      h.push_back("order");
      return h;
    }());
    for (const Method& method : all_methods[si]) {
      Series series{method.name, {}, {}};
      std::vector<double> dts, errs;
      std::vector<std::string> cells = {method.is_default ? "**" + method.name + "**"
                                                          : method.name};
      for (int n : rates_per_s) {
        const Rates r = with(def, with(method.over, {.dt = 1.0 / n}));
        Measure m = scene.measure(r);
        progress.tick();
        for (int k = 1; k < repeats; ++k) {
          const Measure again = scene.measure(r);
          progress.tick();
          if (again.ok() && again.cpu < m.cpu) m.cpu = again.cpu;
        }
        const double err = relative_error(m, reference);
        row(method.name, method.is_default && std::abs(r.dt - def.dt) < 1e-12, r, m, err);
        cells.push_back(m.ok() ? percent(err) + " · " + fmt(m.cost(), 2) + " s" : "fails");
        if (!m.ok()) continue;
        series.x.push_back(m.cost()), series.y.push_back(err);
        dts.push_back(r.dt), errs.push_back(err);
        all_cost.push_back(m.cost()), all_err.push_back(err);
        all_name.push_back(method.name + " at " + step_name(r.dt));
        if (method.is_default && std::abs(r.dt - def.dt) < 1e-12)
          plot.markers.push_back({m.cost(), err, "default (" + step_name(r.dt) + ")"});
      }
      const double order = loglog_slope(dts, errs);
      cells.push_back(std::isfinite(order) ? fmt(order, 2) : "-");
      table.row(cells);
      plot.series.push_back(std::move(series));
    }
    write_svg(plot, o.file("coupled_" + scene.mod + ".svg"));

    md << "\n### The " << scene.mod << "\n\n"
       << "Quantity: " << scene.quantity << " over " << fmt(scene.from, 2) << " to "
       << fmt(scene.to, 2) << " s. Scene's rates: dt " << step_name(def.dt) << ", "
       << describe(def) << ". Reference: dt 1/" << ref_n << ", " << fmt(reference, 6)
       << "; at 1/" << check_n << " " << fmt(check.value, 6) << " ("
       << percent(relative_error(check, reference))
       << " away: errors below that are within the reference's own).\n\n"
       << "Each cell: relative error · CPU seconds per simulated second. Order: slope of "
          "log error against log dt. Plot: `docs/bench/coupled_"
       << scene.mod << ".svg`.\n\n"
       << table.str() << "\nPareto front (cost, error):";
    for (std::size_t i : pareto_front(all_cost, all_err))
      md << " " << all_name[i] << " (" << fmt(all_cost[i], 2) << " s, " << percent(all_err[i])
         << ");";
    md << "\n";
  }
  const std::string text = md.str();
  std::printf("%s", text.c_str());
  splice(o.docs, "coupled", text);
  return exit_code;
}
