// multirate_diag: one run of a coupled scene (bench/coupled_scenes.hpp) at
// chosen rates, printing its figure, its cost, the events after 1 s by type
// (a contact that chatters shows as more contact_began than commutations)
// and the per-stage times. The diagnosis of docs/performance.md "Multi-rate
// coupling" is made of such runs; not a benchmark (make bench skips it).
//   multirate_diag motor|doorbell N [elec=k] [rigid=k] [rates=1] [crates=1] [found=1]
//   [solver=step|quick] [iter=k] [every:stage=n] [from=s] ...
// N: the window is 1/N s; every:stage=n runs that stage every n-th window,
// e.g. every:magnetic_forces=32 at N = 7680 holds the magnetic loads for
// 1/240 s while everything else runs at 1/7680 s. from=s: the motor's speed
// is measured from s seconds (default 1, as the benchmarks do; from 3 s,
// past the start-up, the errors are the same to 0.05 %: session 17).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/coupled_scenes.hpp"

using namespace alloy;
using namespace alloy::bench::coupled;

int main(int argc, char** argv) {
  const std::string mod = argv[1];
  Rates over{.dt = 1.0 / std::atof(argv[2])};
  double from = 1.0;
  for (int i = 3; i < argc; ++i) {
    std::string a = argv[i];
    const auto eq = a.find('=');
    const std::string k = a.substr(0, eq);
    const int v = std::atoi(a.c_str() + eq + 1);
    if (k == "elec")
      over.electricity_substeps = v;
    else if (k == "rigid")
      over.rigid_substeps = v;
    else if (k == "rates")
      over.load_rates = v != 0;
    else if (k == "crates")
      over.current_rates = v != 0;
    else if (k == "engine")
      over.engine = a.substr(eq + 1);
    else if (k == "ahead")
      over.contacts_ahead = v != 0;
    else if (k == "found")
      over.substep_contacts = v ? "found" : "kept";
    else if (k == "solver")
      over.solver = a.substr(eq + 1);
    else if (k == "iter")
      over.iterations = v;
    else if (k == "from")
      from = std::atof(a.c_str() + eq + 1);
    else if (k.rfind("every:", 0) == 0)
      over.every[k.substr(6)] = v;
  }
  const Rates r = with(scene_rates(mod == "doorbell" ? mod : "motor"), over);
  const Measure m = mod == "doorbell" ? doorbell_period(r, 1, 5) : motor_speed(r, from, 8, mod);
  std::printf("%s 1/%s value %.6f count %d cost %.5f\n", mod.c_str(), argv[2], m.value, m.count,
              m.cost());
  {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::LoadedScene loaded = load(mod, r, registry);
    std::map<std::string, int> counts;
    loaded.world->add_observer([&](const Event& e) {
      if (e.time >= 1.0) ++counts[e.type];
    });
    loaded.world->run(std::uint64_t(std::llround(8.0 / loaded.world->dt())));
    for (const auto& [k, v] : counts) std::printf("  event %-30s %d\n", k.c_str(), v);
  }
  double total = 0;
  for (const auto& st : m.stages) total += st.seconds;
  for (const auto& st : m.stages)
    std::printf("  %-34s runs %8llu  %.4f s  %5.1f %%\n", st.name.c_str(),
                (unsigned long long)st.runs, st.seconds, 100 * st.seconds / total);
  std::printf("  stages total %.4f s of cpu %.4f s\n", total, m.cpu);
}
