// The cost of a Lua stage against its C++ twin, as ratios measured in one run.
//
//   Lua / C++         the same interaction, a force field over every body
//                     (F = -k m p: a spring towards the origin, queued on the
//                     rigid body), written once in C++ as a native plugin and
//                     in Lua as a mod's stage, in two forms:
//                       per body   add_force(i, f) in a loop over a column
//                       bulk       the loop fills a vec3 buffer, one
//                                  add_force_each queues it (docs/modding.md)
//                     Goal (issue 6): Lua at most 2x the C++ time.
//   budget ticks      the per-body Lua stage with the sandbox's budget ticks
//                     against the same stage without them
//                     (ModBudget::ticks = false): what the time budget costs.
//
// For 100, 1,000 and 10,000 bodies: one world per variant with the same
// bodies, stepped in turn (rounds of steps, after a warm-up so that LuaJIT
// has compiled its traces). A stage's time is CPU time: at each step the
// world calls the stage `repeat` times in a row (k divided by as much, so
// the forces are those of one call) and the batch is timed with
// cpu_seconds(), since a CPU clock read costs about a microsecond here,
// as much as a whole C++ call on 100 bodies. The rigid body's advance, the
// same for all variants, is not counted. Ratios are medians over rounds of
// the round's ratio.
//
//   build/bench/alloy_bench_lua_stage [--quick] [--out DIR] [--docs FILE]
//   build/bench/alloy_bench_lua_stage --profile VARIANT   (one variant at
//     10,000 bodies for 400 steps, to run under perf; VARIANT: cpp, lua,
//     lua_raw, lua_bulk)
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench/common/bench_common.hpp"
#include "lua/mod_runtime.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"

namespace {

using namespace alloy;
namespace fs = std::filesystem;

constexpr double kK = 2.0;  // N/(m kg): the field's stiffness per unit mass

class FieldCpp final : public Interaction {
 public:
  FieldCpp(rigid::RigidBodyResolver& rigid, double k) : rigid_(rigid), k_(k) {}
  void apply(const WorldView& w) override {
    if (pos_ == kNoProperty) pos_ = w.property("position"), mass_ = w.property("mass");
    const auto pos = w.column<Vec3>(pos_);
    const auto mass = w.column<double>(mass_);
    for (std::uint32_t s : mass.members()) rigid_.add_force(s, pos[s] * (-k_ * mass[s]));
  }

 private:
  rigid::RigidBodyResolver& rigid_;
  double k_;
  PropertyId pos_ = kNoProperty, mass_ = kNoProperty;
};

PluginDef field_cpp() {
  PluginDef def;
  def.info = {.name = "bench.field_cpp",
              .kind = StageKind::Interaction,
              .reads = {"position", "mass"},
              .target = "rigid_body",
              .doc = "F = -k m p on every body (C++)"};
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    return std::make_unique<FieldCpp>(ctx.target<rigid::RigidBodyResolver>(),
                                      ctx.settings().number("k", kK));
  };
  return def;
}

// The mod's stage as a mod would write it: one add_force per body.
std::string field_lua(const std::string& name) {
  return R"LUA(
mod.interaction {
  name = ")LUA" +
         name + R"LUA(", reads = { "position", "mass" }, target = "rigid_body",
  settings = { k = 2 },
  apply = function(w)
    local pos, mass = w:read("position"), w:read("mass")
    local k, add_force = w.settings.k, w.target.add_force
    for i in mass:each() do
      add_force(i, pos[i] * (-k * mass[i]))
    end
  end,
}
)LUA";
}

// The same with the bulk form: a force per member into a buffer, queued at once.
std::string field_lua_bulk(const std::string& name) {
  return R"LUA(
mod.interaction {
  name = ")LUA" +
         name + R"LUA(", reads = { "position", "mass" }, target = "rigid_body",
  settings = { k = 2 },
  apply = function(w)
    local pos, mass = w:read("position"), w:read("mass")
    local k = w.settings.k
    local force = w.target.add_force_each(mass)
    for i in mass:each() do
      force[i] = pos[i] * (-k * mass[i])
    end
  end,
}
)LUA";
}

void write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

/// CPU time of a stage's calls, summed over batches.
struct Clock {
  double overhead = 0;  // of reading the clock, subtracted
  double seconds = 0;
  std::uint64_t calls = 0;
};

/// Calls the stage it wraps `repeat` times per step, timing the batch.
class Timed final : public Interaction {
 public:
  Timed(std::unique_ptr<Stage> inner, int repeat, Clock& clock)
      : inner_(std::move(inner)), repeat_(repeat), clock_(clock) {}
  void on_structure_changed(const WorldView& w) override { inner_->on_structure_changed(w); }
  void apply(const WorldView& w) override {
    auto& inner = static_cast<Interaction&>(*inner_);
    const double t0 = bench::cpu_seconds();
    for (int r = 0; r < repeat_; ++r) inner.apply(w);
    clock_.seconds += bench::cpu_seconds() - t0 - clock_.overhead;
    clock_.calls += std::uint64_t(repeat_);
  }

 private:
  std::unique_ptr<Stage> inner_;
  int repeat_;
  Clock& clock_;
};

struct Variant {
  const char* key;    // CSV and --profile name
  const char* label;  // table heading
  const char* stage;  // the plugin it times
};

const Variant kVariants[] = {
    {"cpp", "C++", "bench.field_cpp"},
    {"lua", "Lua per body", "bench.field_lua"},
    {"lua_raw", "Lua per body, no ticks", "bench.field_lua_raw"},
    {"lua_bulk", "Lua bulk", "bench.field_lua_bulk"},
};
constexpr int kCpp = 0, kLua = 1, kLuaRaw = 2, kLuaBulk = 3;

struct Result {
  int bodies = 0;
  double per_call[std::size(kVariants)] = {};  // median CPU seconds per call
  double ratio[std::size(kVariants)] = {};     // median over rounds of variant / C++
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The mods of the Lua variants, written to a temporary directory.
struct Mods {
  fs::path dir;
  PluginRegistry registry;
  std::unique_ptr<lua::ModRuntime> sandboxed, trusted;

  Mods() {
    dir = fs::temp_directory_path() / ("alloy_bench_lua_" + std::to_string(::getpid()));
    auto mod = [&](const std::string& name, const std::string& code) {
      write(dir / name / "mod.lua",
            "return { name = '" + name + "', version = '1', runtime = 'runtime.lua' }");
      write(dir / name / "runtime.lua", code);
    };
    // One mod (one Lua state) per variant: LuaJIT specialises traces of the
    // prelude's code to the stage instance that first ran them.
    mod("field", field_lua("bench.field_lua"));
    mod("field_bulk", field_lua_bulk("bench.field_lua_bulk"));
    mod("field_raw", field_lua("bench.field_lua_raw"));
    register_native_plugins(registry);
    registry.add(field_cpp());
    sandboxed =
        std::make_unique<lua::ModRuntime>(registry, lua::ModRuntimeOptions{.mod_paths = {dir}});
    sandboxed->load("field");
    sandboxed->load("field_bulk");
    lua::ModBudget no_ticks;
    no_ticks.ticks = false;
    trusted = std::make_unique<lua::ModRuntime>(
        registry, lua::ModRuntimeOptions{.mod_paths = {dir}, .budget = no_ticks});
    trusted->load("field_raw");
  }
  ~Mods() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }

  /// A world of `bodies` spheres with `stage` wrapped in a Timed calling it
  /// `repeat` times per step.
  std::unique_ptr<World> world(const char* stage, int bodies, int repeat, Clock& clock) {
    const std::string timed = std::string("timed.") + stage + "." + std::to_string(bodies);
    if (!registry.find(timed)) {
      PluginDef def = *registry.find(stage);
      def.info.name = timed;
      def.create = [inner = def.create, repeat,
                    &clock](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<Timed>(inner(ctx), repeat, clock);
      };
      registry.add(std::move(def));
    }
    WorldDef def;
    def.plugins = {"rigid_body", "gravity.uniform", "rigid_body_from_gravity", timed};
    PluginSettings k;
    k.set("k", kK / repeat);  // the forces of one call, whatever the repeat
    def.settings[timed] = k;
    auto w = std::make_unique<World>(registry, def);
    const int side = int(std::ceil(std::sqrt(double(bodies))));
    for (int i = 0; i < bodies; ++i) {
      const ObjectId o = w->create();
      w->set(o, "shape", std::string("sphere"));
      w->set(o, "radius", 0.01);
      w->set(o, "mass", 1.0 + 0.001 * (i % 7));
      w->set(o, "position", Vec3{0.5 * (i % side), 0.5 * (i / side), 0});
    }
    return w;
  }
};

/// Calls per step: enough that a batch takes well over the CPU clock's cost,
/// few enough that the rigid body's queue stays as long as one call's on
/// 10,000 bodies (a longer one would time memory traffic, not the stage).
int repeat_for(int bodies) {
  return std::max(1, 10'000 / bodies);
}

/// What one cpu_seconds() pair costs, measured (the median of many), to
/// subtract from each batch.
double clock_cost() {
  std::vector<double> v;
  for (int i = 0; i < 201; ++i) {
    const double t0 = bench::cpu_seconds();
    v.push_back(bench::cpu_seconds() - t0);
  }
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

Result measure(Mods& mods, int bodies, int rounds, int steps, bench::Progress& progress) {
  const int repeat = repeat_for(bodies);
  std::vector<Clock> clocks(std::size(kVariants));
  for (Clock& c : clocks) c.overhead = clock_cost();
  std::vector<std::unique_ptr<World>> worlds;
  for (std::size_t v = 0; v < std::size(kVariants); ++v) {
    worlds.push_back(mods.world(kVariants[v].stage, bodies, repeat, clocks[v]));
    worlds.back()->run(30);  // warm-up: traces compiled, buffers grown
  }
  std::vector<std::vector<double>> per_call(std::size(kVariants));
  for (int round = 0; round < rounds; ++round) {
    for (std::size_t v = 0; v < std::size(kVariants); ++v) {
      const Clock before = clocks[v];
      worlds[v]->run(steps);
      per_call[v].push_back((clocks[v].seconds - before.seconds) /
                            double(clocks[v].calls - before.calls));
    }
    progress.tick();
  }
  Result r;
  r.bodies = bodies;
  for (std::size_t v = 0; v < std::size(kVariants); ++v) {
    r.per_call[v] = median(per_call[v]);
    std::vector<double> ratios;
    for (int round = 0; round < rounds; ++round)
      ratios.push_back(per_call[v][std::size_t(round)] / per_call[kCpp][std::size_t(round)]);
    r.ratio[v] = median(ratios);
  }
  return r;
}

std::string with_commas(int n) {
  std::string s = std::to_string(n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

std::string us(double seconds) {
  return bench::fmt(seconds * 1e6) + " us";
}

int profile(Mods& mods, const std::string& key) {
  for (const Variant& v : kVariants)
    if (key == v.key) {
      Clock clock;
      auto w = mods.world(v.stage, 10'000, 1, clock);
      w->run(400);
      std::printf("%s: %.1f us per call at 10,000 bodies (400 steps)\n", v.key,
                  clock.seconds / double(clock.calls) * 1e6);
      return 0;
    }
  std::fprintf(stderr, "--profile takes cpp, lua, lua_raw or lua_bulk\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  // --profile VARIANT: outside Options, which knows flags without values.
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--profile") == 0) {
      Mods mods;
      return profile(mods, argv[i + 1]);
    }
  const bench::Options opt = bench::Options::parse(argc, argv, "alloy_bench_lua_stage");
  const std::vector<int> sizes = {100, 1'000, 10'000};
  const int rounds = opt.quick ? 3 : 31;
  const int steps = opt.quick ? 4 : 20;

  std::vector<Result> results;
  {
    bench::Progress progress("lua stage", sizes.size() * std::size_t(rounds), opt.progress);
    // Fresh mods (Lua states) per size: LuaJIT's traces are specialised to
    // the first stage instance that ran them, as in a scene with one world.
    for (int n : sizes) {
      Mods mods;
      results.push_back(measure(mods, n, rounds, steps, progress));
    }
  }

  bench::Csv csv(opt.file("lua_stage.csv"),
                 {"bodies", "variant", "us_per_call", "ns_per_body", "ratio_to_cpp"});
  bench::Table table({"bodies", "C++", "Lua per body", "Lua / C++", "Lua bulk", "bulk / C++",
                      "cost of budget ticks"});
  bool met = true;
  for (const Result& r : results) {
    for (std::size_t v = 0; v < std::size(kVariants); ++v)
      csv.row({bench::Csv::cell(r.bodies), kVariants[v].key, bench::Csv::cell(r.per_call[v] * 1e6),
               bench::Csv::cell(r.per_call[v] * 1e9 / r.bodies), bench::Csv::cell(r.ratio[v])});
    const double ticks = r.per_call[kLua] / r.per_call[kLuaRaw] - 1;
    table.row({with_commas(r.bodies), us(r.per_call[kCpp]), us(r.per_call[kLua]),
               bench::fmt(r.ratio[kLua]), us(r.per_call[kLuaBulk]), bench::fmt(r.ratio[kLuaBulk]),
               bench::fmt(100 * ticks, 2) + " %"});
    std::printf(
        "%6d bodies  per call: C++ %8.2f us  Lua %8.2f us  Lua no ticks %8.2f us  Lua bulk %8.2f "
        "us\n              Lua / C++ = %.2f  bulk / C++ = %.2f (goal <= 2)  budget ticks: %+.1f "
        "%%\n",
        r.bodies, r.per_call[kCpp] * 1e6, r.per_call[kLua] * 1e6, r.per_call[kLuaRaw] * 1e6,
        r.per_call[kLuaBulk] * 1e6, r.ratio[kLua], r.ratio[kLuaBulk], 100 * ticks);
    if (r.bodies >= 1'000 && !(r.ratio[kLua] <= 2 && r.ratio[kLuaBulk] <= 2)) met = false;
  }
  if (!opt.quick) bench::splice(opt.docs, "lua_stage", table.str());
  std::printf("goal (Lua at most 2x C++ at 1,000 and 10,000 bodies): %s\n", met ? "met" : "missed");
  // --quick is a smoke run (a few rounds, noisy ratios): it does not judge the goal.
  return met || opt.quick ? 0 : 1;
}
