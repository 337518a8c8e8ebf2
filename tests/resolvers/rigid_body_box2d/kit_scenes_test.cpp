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
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
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
  std::uint64_t rebuilds = 0;             ///< Box2D's full builds, if it ran at the end
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
                                      : r.angle.back() + std::remainder(a - r.angle.back(),
                                                                        2 * std::numbers::pi));
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
  if (auto* b = dynamic_cast<box2d::Box2DEngine*>(world.stage(kBox2D)))
    r.rebuilds = b->rebuild_count();
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
  std::printf("doorbell on Box2D: %llu builds of the Box2D world in %g s\n",
              (unsigned long long)b2.rebuilds, kDoorbellSeconds);
  EXPECT_TRUE(has(b2.stages, "rigid_body.box2d"));
  EXPECT_TRUE(has(b2.stages, "collisions.box2d"));  // came with the engine
  EXPECT_FALSE(has(b2.stages, "rigid_body"));
  EXPECT_FALSE(has(b2.stages, "collisions"));
  const Ringing a = ringing(ode, 0, kDoorbellSeconds), b = ringing(b2, 0, kDoorbellSeconds);
  std::printf("doorbell to 3 s: ODE %d strikes, period %.4f s; Box2D %d strikes, period %.4f s\n",
              a.count, a.period, b.count, b.period);
  // Step-exact on this build (the runs are deterministic; golden hashes
  // hold the same). One strike a cycle on both. Session 16: a part's force
  // acts at the part on Box2D too (35 strikes at 0.0665 s with that alone),
  // and soft iron's poles sit on its faces with the coil 6 mm up (35 at
  // 0.0680 s with that alone); with both, 34 at 0.0697 s, 4.5 % longer than
  // ODE's. (Session 15: 33 strikes at 0.0712 s.) Session 17 (induction
  // order 2 the default, the pack 0.6 ohm): ODE 36 at 0.0667 s, Box2D 31 at
  // 0.0765 s, its intervals uneven (0.0625 to 0.0958 s).
  EXPECT_EQ(a.count, 36);
  EXPECT_NEAR(a.period, 0.0667, 1e-4);
  EXPECT_EQ(b.count, 31);
  EXPECT_NEAR(b.period, 0.0765, 1e-4);
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
  // Anticlockwise on both, Box2D 5.3 % slower (docs/box2d.md, "The motor on
  // both engines": the slider leaves the spokes 5 % of the time there). Until
  // session 16 it was 44 % slower (2.3367 rad/s): Box2D applied the magnets'
  // pull on each spoke at the rotor's centre, where it has no torque.
  // Session 17, induction order 2 the default: 4.2157 and 3.9765 rad/s
  // (were 4.1775 and 3.9544).
  EXPECT_NEAR(w_ode, 4.2157, 1e-3);
  EXPECT_NEAR(w_b2, 3.9765, 1e-3);
  EXPECT_NEAR(w_b2 / w_ode, 1, 0.10) << "the goal of issue 15: within 10 %";
}

TEST(KitOnBox2D, DoorbellSwappedMidRunBothWays) {
  // Swapped at 1.5 s, when it has rung for a second: only `rigid_body` is
  // named, and the contact set must follow, or the finger's contact with the
  // interrupter would never be seen again and the bell would fall silent.
  const double at = 1.5;
  const KitRun to_b2 = run_kit("mods/doorbell", kDoorbellSeconds, {.to = kBox2D, .at = at});
  const KitRun to_ode =
      run_kit("mods/doorbell", kDoorbellSeconds, {.start = kBox2D, .to = kOde, .at = at});
  print_strikes("ODE, then Box2D from 1.5 s", to_b2);
  print_strikes("Box2D, then ODE from 1.5 s", to_ode);
  EXPECT_TRUE(has(to_b2.stages, "collisions.box2d"));
  EXPECT_FALSE(has(to_b2.stages, "rigid_body_from_collisions"));
  EXPECT_TRUE(has(to_ode.stages, "collisions"));
  EXPECT_TRUE(has(to_ode.stages, "rigid_body_from_collisions"));
  for (const KitRun* r : {&to_b2, &to_ode}) {
    const Ringing before = ringing(*r, 0, at), after = ringing(*r, at, kDoorbellSeconds);
    std::printf("doorbell %s at 1.5 s: %d strikes before (period %.4f s), %d after (%.4f s)\n",
                r == &to_b2 ? "ODE -> Box2D" : "Box2D -> ODE", before.count, before.period,
                after.count, after.period);
    EXPECT_GT(after.count, 10) << "it rings on after the swap";
  }
  // Step-exact: the strikes before the swap are the first engine's, after it
  // the second's period is within a few per cent of its own from the start
  // (ODE 0.0667 s, Box2D 0.0697 s; both 0.0663 s after the swap, the rebuilt
  // contacts' transient). Before session 16's fix of forces on glued parts
  // and its iron on the faces: 14 then 20 strikes at 0.0761 s to Box2D, 12
  // then 22 at 0.0667 s back to ODE.
  // Session 17 (induction order 2, the pack 0.6 ohm): 14 then 20 at 0.0770 s
  // to Box2D, 11 then 23 at 0.0667 s back to ODE.
  EXPECT_EQ(ringing(to_b2, 0, at).count, 14);
  EXPECT_EQ(ringing(to_b2, at, kDoorbellSeconds).count, 20);
  EXPECT_NEAR(ringing(to_b2, at, kDoorbellSeconds).period, 0.0770, 1e-4);
  EXPECT_EQ(ringing(to_ode, 0, at).count, 11);
  EXPECT_EQ(ringing(to_ode, at, kDoorbellSeconds).count, 23);
  EXPECT_NEAR(ringing(to_ode, at, kDoorbellSeconds).period, 0.0667, 1e-4);
}

TEST(KitOnBox2D, MotorSwappedMidRunBothWays) {
  // Swapped at 2 s, turning steadily. The rotor's spin carries over through
  // its properties; what does not (the slider's contact memory, the warm
  // start) shows as a jump of its speed at the swap step, measured against
  // the largest step-to-step change of the second before.
  const double at = 2.0;
  for (const bool to_b2 : {true, false}) {
    const KitRun r = run_kit(
        "mods/motor", kMotorSeconds,
        to_b2 ? Engines{.to = kBox2D, .at = at} : Engines{.start = kBox2D, .to = kOde, .at = at},
        "axle");
    const std::size_t k = r.at(at);  // the sample at the end of the last step before the swap
    double usual = 0;
    for (std::size_t i = r.at(at - 1) + 1; i <= k; ++i)
      usual = std::max(usual, std::abs(r.spin[i] - r.spin[i - 1]));
    const double jump = r.spin[k + 1] - r.spin[k];
    const double before = r.mean_speed(1, 2), after = r.mean_speed(3, 4);
    std::printf(
        "motor %s at 2 s: %.4f rad/s over 1-2 s, %.4f over 3-4 s; speed change at the "
        "swap step %+.4f rad/s (largest in the second before %.4f)\n",
        to_b2 ? "ODE -> Box2D" : "Box2D -> ODE", before, after, jump, usual);
    EXPECT_GT(after, 0) << "still anticlockwise";
    // The swap's transient is smaller than a usual step's change of speed
    // (the slider's blows on the spokes): -0.020 and +0.007 rad/s against
    // 0.18 and 0.17. Each engine's own speed follows (4.21 -> 4.11 rad/s,
    // 3.95 -> 4.27; before session 16's fix 4.21 -> 2.32 and 1.83 -> 4.11).
    EXPECT_LT(std::abs(jump), usual);
    // Session 17, induction order 2: 4.2001 -> 4.1149 and 3.8941 -> 4.2668
    // (were 4.2124 -> 4.1111 and 3.9481 -> 4.2659).
    EXPECT_NEAR(before, to_b2 ? 4.2001 : 3.8941, 1e-3);
    EXPECT_NEAR(after, to_b2 ? 4.1149 : 4.2668, 1e-3);
    EXPECT_TRUE(has(r.stages, to_b2 ? "collisions.box2d" : "collisions"));
  }
}

}  // namespace
}  // namespace alloy
