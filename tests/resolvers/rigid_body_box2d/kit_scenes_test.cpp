// The kit's scenes on Box2D (issue 15): the doorbell (mods/doorbell) and the
// motor (mods/motor) loaded as bundled, run on ODE, on Box2D from the start,
// and swapped from ODE to Box2D (and back) in the middle of a run. Only
// `rigid_body` is swapped: the engine's contact set must come with it
// (World::swap), or nothing would ring and nothing would turn. Each test
// prints its figures (docs/box2d.md, "The kit's scenes").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy {
namespace {

using test::source;

constexpr const char* kOde = "rigid_body";
constexpr const char* kBox2D = "rigid_body.box2d";

/// How a run chooses its engine: `start` before the first step (nullptr: the
/// scene's, ODE), then `to` from time `at` on (nullptr: no swap).
struct Engines {
  const char* start = nullptr;
  const char* to = nullptr;
  double at = 0;
};

struct KitRun : test::EventRecords {
  double dt = 0;
  std::vector<double> time, angle, spin;  ///< of `axle`, if asked for
  std::vector<std::string> stages;        ///< at the end
  std::vector<double> strikes() const {
    std::vector<double> t;
    for (const test::Record* e : of("sound", "bell")) t.push_back(e->time);
    return t;
  }
  std::size_t at(double t) const {
    return std::size_t(std::lower_bound(time.begin(), time.end(), t - 1e-9) - time.begin());
  }
  /// The axle's mean angular velocity between t0 and t1, from its angle.
  double mean_speed(double t0, double t1) const {
    const std::size_t i0 = at(t0), i1 = std::min(at(t1), angle.size() - 1);
    return (angle[i1] - angle[i0]) / (time[i1] - time[i0]);
  }
};

KitRun run_kit(const std::string& scene, double seconds, const Engines& e,
               const char* axle = nullptr) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(source(scene), registry, load);
  World& world = *loaded.world;
  if (e.start) world.swap("", kOde, e.start);
  if (e.to) world.schedule_swap(e.at, "", e.start ? e.start : kOde, e.to);
  KitRun r;
  r.record(world);
  r.dt = world.dt();
  ObjectId id{};
  if (axle) id = world.find(axle);
  auto sample = [&] {
    if (!axle) return;
    const double a = angle_z(std::get<Quat>(world.get(id, "orientation")));
    r.angle.push_back(r.angle.empty() ? a
                                      : r.angle.back() +
                                            std::remainder(a - r.angle.back(), 2 * std::numbers::pi));
    r.time.push_back(world.time());
    const bool moving = world.store().has(id, world.properties().id("angular_velocity"));
    r.spin.push_back(moving ? std::get<Vec3>(world.get(id, "angular_velocity")).z : 0.0);
  };
  sample();
  const auto steps = std::uint64_t(std::llround(seconds / r.dt));
  for (std::uint64_t i = 0; i < steps; ++i) {
    world.step();
    sample();
  }
  r.stages = world.active_stages();
  return r;
}

bool has(const std::vector<std::string>& v, const char* s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

/// Strike times' count and mean period between t0 and t1.
struct Ringing {
  int count = 0;
  double period = 0;
};
Ringing ringing(const KitRun& r, double t0, double t1) {
  std::vector<double> t;
  for (double s : r.strikes())
    if (s >= t0 && s < t1) t.push_back(s);
  Ringing out{int(t.size()), 0};
  if (t.size() > 1) out.period = (t.back() - t.front()) / double(t.size() - 1);
  return out;
}

void print_strikes(const char* what, const KitRun& r) {
  std::printf("doorbell %s: %zu strikes, at", what, r.strikes().size());
  for (double t : r.strikes()) std::printf(" %.4f", t);
  std::printf("\n");
}

// --- the doorbell ----------------------------------------------------------------

constexpr double kDoorbellSeconds = 3.0;

TEST(KitOnBox2D, DoorbellRingsOnBothEngines) {
  const KitRun ode = run_kit("mods/doorbell", kDoorbellSeconds, {});
  const KitRun b2 = run_kit("mods/doorbell", kDoorbellSeconds, {.start = kBox2D});
  print_strikes("on ODE", ode);
  print_strikes("on Box2D", b2);
  EXPECT_TRUE(has(b2.stages, "rigid_body.box2d"));
  EXPECT_TRUE(has(b2.stages, "collisions.box2d"));  // came with the engine
  EXPECT_FALSE(has(b2.stages, "rigid_body"));
  EXPECT_FALSE(has(b2.stages, "collisions"));
  const Ringing a = ringing(ode, 0, kDoorbellSeconds), b = ringing(b2, 0, kDoorbellSeconds);
  std::printf("doorbell to 3 s: ODE %d strikes, period %.4f s; Box2D %d strikes, period %.4f s\n",
              a.count, a.period, b.count, b.period);
  for (const auto& e : b2.events)
    if (e.time > 0.55 && e.time < 0.9 && e.type != "input")
      std::printf("DBG %.4f %s %s %s\n", e.time, e.type.c_str(), e.a.c_str(), e.b.c_str());
  EXPECT_GT(b.count, 20);
  EXPECT_GT(b2.strikes().front(), 0.5) << "nothing rings before the switch bar is let go";
}

// --- the motor -------------------------------------------------------------------

constexpr double kMotorSeconds = 4.0;

TEST(KitOnBox2D, MotorTurnsOnBothEngines) {
  const KitRun ode = run_kit("mods/motor", kMotorSeconds, {}, "axle");
  const KitRun b2 = run_kit("mods/motor", kMotorSeconds, {.start = kBox2D}, "axle");
  const double w_ode = ode.mean_speed(2, 4), w_b2 = b2.mean_speed(2, 4);
  std::printf("motor 2-4 s: ODE %.4f rad/s, Box2D %.4f rad/s\n", w_ode, w_b2);
  EXPECT_TRUE(has(b2.stages, "collisions.box2d"));
  EXPECT_GT(w_b2, 0) << "anticlockwise";
}

}  // namespace
}  // namespace alloy
