// The cost of a Lua stage against its C++ twin, as ratios measured in one run.
//
//   Lua / C++         the same interaction, a force field over every body
//                     (F = -k m p: a spring towards the origin, queued on the
//                     rigid body with add_force), written once in C++ as a
//                     native plugin and once in Lua as a mod's stage (the
//                     FFI fast path behind checked column proxies).
//                     Goal: Lua at most 2x the C++ time.
//   budget ticks      the Lua stage with the sandbox's budget ticks against
//                     the same stage without them (ModBudget::ticks = false):
//                     what the time budget costs under the JIT.
//
// For 1,000 and 10,000 bodies: three worlds with the same bodies, one per
// variant, stepped in turn (rounds of 20 steps, after 100 steps of warm-up
// so that LuaJIT has compiled its traces); each variant's time is the
// profile's time of its stage alone (the rigid body's advance, the same for
// all, is not counted). Ratios are of the median time per call over rounds.
//
//   build-mods/bench/alloy_bench_lua_stage
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "lua/mod_runtime.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"

namespace {

using namespace alloy;
namespace fs = std::filesystem;

constexpr double kK = 2.0;

class FieldCpp final : public Interaction {
 public:
  explicit FieldCpp(rigid::RigidBodyResolver& rigid) : rigid_(rigid) {}
  void apply(const WorldView& w) override {
    if (pos_ == kNoProperty) pos_ = w.property("position"), mass_ = w.property("mass");
    const auto pos = w.column<Vec3>(pos_);
    const auto mass = w.column<double>(mass_);
    for (std::uint32_t s : mass.members()) rigid_.add_force(s, pos[s] * (-kK * mass[s]));
  }

 private:
  rigid::RigidBodyResolver& rigid_;
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
    return std::make_unique<FieldCpp>(ctx.target<rigid::RigidBodyResolver>());
  };
  return def;
}

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

void write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

struct Variant {
  std::string stage;
  std::unique_ptr<World> world;
  double seconds = 0;  // stage time at the start of the round
  std::vector<double> per_call;
};

double stage_seconds(const World& w, const std::string& stage, std::uint64_t* runs = nullptr) {
  for (const auto& t : w.profile().stages)
    if (t.name == stage) {
      if (runs) *runs = t.runs;
      return t.seconds;
    }
  return 0;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void measure(int bodies) {
  const fs::path dir =
      fs::temp_directory_path() / ("alloy_bench_lua_" + std::to_string(::getpid()));
  write(dir / "field/mod.lua", "return { name = 'field', version = '1', runtime = 'runtime.lua' }");
  write(dir / "field/runtime.lua", field_lua("bench.field_lua"));
  write(dir / "field_raw/mod.lua",
        "return { name = 'field_raw', version = '1', runtime = 'runtime.lua' }");
  write(dir / "field_raw/runtime.lua", field_lua("bench.field_lua_raw"));

  PluginRegistry registry;
  register_native_plugins(registry);
  registry.add(field_cpp());
  lua::ModRuntime sandboxed(registry, {.mod_paths = {dir}});
  sandboxed.load("field");
  lua::ModBudget trusted;
  trusted.ticks = false;
  lua::ModRuntime raw(registry, {.mod_paths = {dir}, .budget = trusted});
  raw.load("field_raw");

  std::vector<Variant> variants;
  for (const char* stage : {"bench.field_cpp", "bench.field_lua", "bench.field_lua_raw"}) {
    WorldDef def;
    def.plugins = {"rigid_body", "gravity.uniform", "rigid_body_from_gravity", stage};
    Variant v{stage, std::make_unique<World>(registry, def)};
    const int side = int(std::ceil(std::sqrt(double(bodies))));
    for (int i = 0; i < bodies; ++i) {
      const ObjectId o = v.world->create();
      v.world->set(o, "shape", std::string("sphere"));
      v.world->set(o, "radius", 0.01);
      v.world->set(o, "mass", 1.0 + 0.001 * (i % 7));
      v.world->set(o, "position", Vec3{0.5 * (i % side), 0.5 * (i / side), 0});
    }
    v.world->run(100);  // warm-up: traces compiled, caches filled
    variants.push_back(std::move(v));
  }
  for (int round = 0; round < 15; ++round)
    for (Variant& v : variants) {
      std::uint64_t runs0 = 0, runs1 = 0;
      const double s0 = stage_seconds(*v.world, v.stage, &runs0);
      v.world->run(20);
      const double s1 = stage_seconds(*v.world, v.stage, &runs1);
      v.per_call.push_back((s1 - s0) / double(runs1 - runs0));
    }
  const double cpp = median(variants[0].per_call), lua = median(variants[1].per_call),
               lua_raw = median(variants[2].per_call);
  std::printf(
      "%6d bodies   C++ %8.1f us   Lua %8.1f us   Lua without ticks %8.1f us   (per call; %.1f / "
      "%.1f / %.1f ns per body)\n",
      bodies, cpp * 1e6, lua * 1e6, lua_raw * 1e6, cpp * 1e9 / bodies, lua * 1e9 / bodies,
      lua_raw * 1e9 / bodies);
  std::printf(
      "%6d bodies   Lua / C++ = %.2f (goal <= 2)   budget ticks: Lua / Lua without = %.3f\n",
      bodies, lua / cpp, lua / lua_raw);
  variants.clear();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace

int main() {
  std::printf(
      "A force field over every body, as an interaction queueing add_force on the rigid body\n");
  for (int n : {1000, 10000}) measure(n);
  return 0;
}
