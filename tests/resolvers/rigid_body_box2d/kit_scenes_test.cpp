// The kit's scenes on Box2D (issue 15): the doorbell (mods/doorbell) and the
// motor (mods/motor) loaded as bundled, run on ODE, on Box2D from the start,
// and swapped from ODE to Box2D (and back) in the middle of a run. Only
// `rigid_body` is swapped: the engine's contact set must come with it
// (World::swap), or nothing would ring and nothing would turn. Each test
// prints its figures (docs/box2d.md, "The kit's scenes").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <tuple>
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
  double dt = 0;  ///< the world's step; 0: the scene's
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

/// A bundled scene (or a test's), loaded as `alloy run` loads it.
lua::LoadedScene load_kit_scene(const std::string& scene, PluginRegistry& registry) {
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  return lua::load_scene(source(scene), registry, load);
}

KitRun run_kit(const std::string& scene, double seconds, const Engines& e,
               const char* axle = nullptr) {
  PluginRegistry registry;
  lua::LoadedScene loaded = load_kit_scene(scene, registry);
  World& world = *loaded.world;
  if (e.dt > 0) world.set_dt(e.dt);
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
/// The strike times in [t0, t1).
std::vector<double> strikes_in(const KitRun& r, double t0, double t1) {
  std::vector<double> t;
  for (double s : r.strikes())
    if (s >= t0 && s < t1) t.push_back(s);
  return t;
}

Ringing ringing(const KitRun& r, double t0, double t1) {
  const std::vector<double> t = strikes_in(r, t0, t1);
  Ringing out{int(t.size()), 0};
  if (t.size() > 1) out.period = (t.back() - t.front()) / double(t.size() - 1);
  return out;
}

/// The intervals between strikes in [t0, t1), in steps, and their spread
/// (longest less shortest) and how many are of the most common length.
struct Steadiness {
  std::vector<long> steps;
  long spread = 0;
  int at_mode = 0;
  long mode = 0;
};
Steadiness steadiness(const KitRun& r, double t0, double t1) {
  const std::vector<double> t = strikes_in(r, t0, t1);
  Steadiness out;
  for (std::size_t i = 1; i < t.size(); ++i)
    out.steps.push_back(std::lround((t[i] - t[i - 1]) / r.dt));
  if (out.steps.empty()) return out;
  const auto [lo, hi] = std::minmax_element(out.steps.begin(), out.steps.end());
  out.spread = *hi - *lo;
  for (long v : out.steps) {
    const int n = int(std::count(out.steps.begin(), out.steps.end(), v));
    if (n > out.at_mode) out.at_mode = n, out.mode = v;
  }
  return out;
}

/// The mean of the intervals within three steps of the most common one, s:
/// the period of the strikes heard in turn, a missed strike (an interval of
/// two or three periods) left out.
double steady_period(const Steadiness& s, double dt) {
  double sum = 0;
  int n = 0;
  for (long v : s.steps)
    if (std::abs(v - s.mode) <= 3) sum += double(v), ++n;
  return n > 0 ? dt * sum / n : 0.0;
}

void print_steadiness(const char* what, const Steadiness& s) {
  std::printf("doorbell %s: %zu intervals, %d of %ld steps, spread %ld steps:", what,
              s.steps.size(), s.at_mode, s.mode, s.spread);
  for (long v : s.steps) std::printf(" %ld", v);
  std::printf("\n");
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
  // ODE's. (Session 15: 33 strikes at 0.0712 s.) Session 17: Box2D's
  // time-of-impact sub-step is off (box2d_engine.cpp, build): 36 at 0.0661 s
  // with order-1 induction; with second-order induction the default and the
  // doorbell's pack 0.6 ohm (the same session), ODE 36 at 0.0667 s (its 37th
  // falls at 3.0000 s) and Box2D 33 at 0.0708 s. Session 18: Box2D's
  // rebuilds (4 in 3 s) make its hinges from their defining points
  // (hinge_anchors.hpp), not the present stretch: 33 at 0.0707 s.
  // Session 20 (the coil pulls with the circuit's current of the kick's
  // instant): ODE 34 at 0.0708 s (17 steps; its converged period is 0.0694
  // s), Box2D 34 at 0.0687 s. Session 21 (the coil's EMF carries the
  // change of the armature's and the core's moments, docs/magnetism.md
  // "Induction through soft iron"): ODE's strikes to the step as before,
  // Box2D 34 at 0.0688 s.
  EXPECT_EQ(a.count, 34);
  EXPECT_NEAR(a.period, 0.0708, 1e-4);
  EXPECT_EQ(b.count, 34);
  EXPECT_NEAR(b.period, 0.0688, 1e-4);
  // One steady period. ODE: every interval 16 steps. Box2D: 30 of 32 at 17
  // steps, the others 16 and 18 (a landing's contact found a step late
  // leaves the lever 0.7 mm deeper in its felt rest: docs/box2d.md). Until
  // session 17 Box2D's intervals ran from 14 to 23 steps, 15 of 33 at 16:
  // its time-of-impact sub-step moved the struck lever without the finger
  // hinged to it, and the hinge's next solve threw the lever back.
  const Steadiness sa = steadiness(ode, 0, kDoorbellSeconds),
                   sb = steadiness(b2, 0, kDoorbellSeconds);
  print_steadiness("on ODE", sa);
  print_steadiness("on Box2D", sb);
  EXPECT_EQ(sa.mode, 17);  // 16 before session 20
  EXPECT_EQ(sa.spread, 0);
  EXPECT_EQ(sb.mode, 16);  // 17 in session 20
  // Session 17: 30 (hinges rebuilt at their stretch); session 18: 25; session
  // 19, contacts kept across Box2D's one-step drops (box2d_engine.cpp,
  // kept_contacts): 27 of 32, spread 2. Session 20: 17 of 33, from 15 to 18
  // steps: the hammer's blow ends with the coil's current now, and Box2D's
  // lever lands a step early or late more often (ODE's stays at 17).
  // Session 21 (the iron's moments in the EMF): 19 of 33 at 16 steps, from
  // 16 to 18.
  EXPECT_EQ(sb.at_mode, 19);
  EXPECT_EQ(sb.spread, 2);
  EXPECT_GT(b2.strikes().front(), 0.5) << "nothing rings before the switch bar is let go";
}

TEST(KitOnBox2D, DoorbellRingsSteadilyAtTheCoarseStep) {
  // At 1/120 s with one Box2D step a step the doorbell buzzed (352 circuit
  // closings in 5 s, no strike): the brass switch bar, dropped on its
  // contacts, bounced for ever. Gravity gives 0.082 m/s a step of 1/120 s, so
  // a flight of two steps lands at 0.16 m/s, above the 0.1 m/s below which
  // nothing bounces (bounce_velocity), and the bar rebounded every 3 or 4
  // steps, closing the switch for one. With Box2D steps of at most
  // max_substep = 1/240 s (two at 1/120 s) it lands at 0.08 m/s and stays.
  // The strike period is held against ODE's at the same step, and its
  // lengthening from 1/240 to 1/120 s against ODE's (the coarse step
  // lengthens the cycle on both engines: the interrupter's timing is whole
  // steps), each run here.
  const double seconds = 5;
  const KitRun coarse = run_kit("mods/doorbell", seconds, {.start = kBox2D, .dt = 1.0 / 120});
  const KitRun fine = run_kit("mods/doorbell", seconds, {.start = kBox2D});
  const KitRun ode = run_kit("mods/doorbell", seconds, {.dt = 1.0 / 120});
  const KitRun ode_fine = run_kit("mods/doorbell", seconds, {});
  const Ringing c = ringing(coarse, 1, seconds), f = ringing(fine, 1, seconds),
                o = ringing(ode, 1, seconds), of = ringing(ode_fine, 1, seconds);
  const Steadiness sc = steadiness(coarse, 1, seconds);
  const double pc = steady_period(sc, 1.0 / 120),
               pf = steady_period(steadiness(fine, 1, seconds), 1.0 / 240);
  const std::size_t closings = coarse.of("circuit_closed", "battery").size();
  std::printf(
      "doorbell 1-5 s: Box2D at 1/120 s %d strikes, period %.4f s; at 1/240 s %d, %.4f s; ODE "
      "at 1/120 s %d, %.4f s; at 1/240 s %d, %.4f s; Box2D at 1/120 s: %zu closings of the "
      "battery's circuit in 5 s\n",
      c.count, c.period, f.count, f.period, o.count, o.period, of.count, of.period, closings);
  print_steadiness("on Box2D at 1/120 s", sc);
  std::printf("Box2D's period of the strikes heard in turn: %.4f s at 1/120 s, %.4f s at 1/240 s\n",
              pc, pf);
  ASSERT_GT(c.count, 20) << "it rings";
  // Since session 20's coupling (the coil's pull ends with its current) the
  // hammer's blow is shorter, and at 1/120 s Box2D's bell misses one in ten
  // (a blow within one of its two steps): the periods compared are of the
  // strikes heard in turn. Measured: 0.0822 s against ODE's 0.0792 s at 1/120
  // s; from 1/240 s Box2D's lengthens 1.21 times, ODE's 1.12 (before: 1.23
  // and 1.28, with ODE's bell 16 steps at 1/240 s).
  EXPECT_NEAR(pc / o.period, 1, 0.05) << "ODE's period at the same step";
  EXPECT_NEAR((pc / pf) / (o.period / of.period), 1, 0.10) << "lengthened from 1/240 s as ODE's is";
  // Steadily, over 20 s: every interval between strikes heard is either the
  // bell's own period (within three steps of the most common interval) or a
  // whole number of them: strikes missed, a blow that begins and ends
  // between the two Box2D steps of a world step is not in the contact set at
  // its end and the bell does not hear it (publishing such contacts steadied
  // it, spread 1 step, but stalled the motor; docs/box2d.md, "Box2D's step
  // and the world's"). About one interval in five is such a miss: 38 of 181
  // over 1-20 s before session 21's iron EMF, 37 of 180 after (docs/energy.md
  // "Session 21"). A 5 s window's share swings with where the misses fall
  // (the base build's later 4 s windows: 0.66 to 0.69 heard), so the count is
  // over 20 s. Buzzing (intervals of a step or two) or a bell whose own
  // period wanders fails the first check, more misses the second.
  const KitRun long_run = run_kit("mods/doorbell", 20, {.start = kBox2D, .dt = 1.0 / 120});
  const Steadiness sl = steadiness(long_run, 1, 20);
  print_steadiness("on Box2D at 1/120 s, 1-20 s", sl);
  std::size_t heard = 0, missed = 0;
  for (long n : sl.steps) {
    const long periods = std::lround(double(n) / double(sl.mode));
    if (std::abs(n - sl.mode) <= 3)
      ++heard;
    else if (periods >= 2 && std::abs(n - periods * sl.mode) <= 3 * periods)
      ++missed;
  }
  EXPECT_GE(sl.steps.size(), 150u) << "it rings for 20 s";
  EXPECT_EQ(heard + missed, sl.steps.size()) << "every interval is a period or a strike missed";
  EXPECT_LE(double(missed), 0.25 * double(sl.steps.size())) << "about one in five missed";
  // Two closings a cycle (the switch bar once, the interrupter each strike),
  // not one every few steps.
  EXPECT_LE(closings, std::size_t(3 * (coarse.strikes().size() + 1)));
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
  // Session 17: the motor's scene names induction_order = 2 (was 4.1775 and
  // 3.9544 with order 1; the ratio 0.947 then, 0.943 now). Session 18:
  // hinges rebuilt from their defining points (3.9765, ratio 0.943, before).
  // Session 20 (the coil's pull from the circuit's current of the kick's
  // instant): 4.2112 (4.2157 before).
  EXPECT_NEAR(w_ode, 4.2112, 1e-3);
  // Session 19: 4.1253 (ratio 0.979), from 3.9997: the slider's one-step
  // openings on the spokes were Box2D dropping a contact at zero overlap for
  // a step (adv F5), which the engine now keeps (kept_contacts).
  // Session 20: 4.1213 (ratio 0.979).
  EXPECT_NEAR(w_b2, 4.1213, 1e-3);
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
  // Session 17, with Box2D's time-of-impact sub-step off, second-order
  // induction, the 0.6 ohm pack and the contact pairs handed over at a swap:
  // 14 then 21 at 0.0708 s to Box2D (its own period from the start), 12 then
  // 21 at 0.0708 s back to ODE. The last is 17 steps where ODE from the start
  // rings every 16: the interrupter's timing is whole steps at 1/240 s, and
  // the state the swap leaves locks it on 17 (the pre-session figures: 13
  // then 22 at 0.0667 s).
  // Session 20 (the coil's pull from the circuit's current of the kick's
  // instant; ODE's own period is 17 steps now): 13 then 22 at 0.0681 s to
  // Box2D, 12 then 22 at 0.0706 s back to ODE. Session 21 (the iron's
  // moments in the EMF): 13 then 22 at 0.0675 s to Box2D, 12 then 22 at
  // 0.0706 s back to ODE.
  EXPECT_EQ(ringing(to_b2, 0, at).count, 13);
  EXPECT_EQ(ringing(to_b2, at, kDoorbellSeconds).count, 22);
  EXPECT_NEAR(ringing(to_b2, at, kDoorbellSeconds).period, 0.0675, 1e-4);
  EXPECT_EQ(ringing(to_ode, 0, at).count, 12);
  // Session 19, contacts kept across Box2D's one-step drops: back to ODE it
  // rang at ODE's own 16 steps (23 strikes at 0.0667 s); session 20: at ODE's
  // own 17 (the first interval 16).
  EXPECT_EQ(ringing(to_ode, at, kDoorbellSeconds).count, 22);
  EXPECT_NEAR(ringing(to_ode, at, kDoorbellSeconds).period, 0.0706, 1e-4);
  // The spread of the intervals after the swap, in steps (from the first
  // strike after it): ODE's own 0; Box2D's as from its start.
  const Steadiness after_b2 = steadiness(to_b2, at, kDoorbellSeconds),
                   after_ode = steadiness(to_ode, at, kDoorbellSeconds);
  print_steadiness("after the swap to Box2D", after_b2);
  print_steadiness("after the swap to ODE", after_ode);
  // Session 20: ODE's 16 then 17 steps; Box2D's 13 of 21 at 16 steps, from
  // 15 to 18 (session 19: 20 of 20 at 17; session 16: 16 to 19 steps).
  // Session 21: ODE's as in session 20; Box2D's 15 of 21 at 16, from 15 to
  // 17.
  EXPECT_EQ(after_ode.spread, 1);
  EXPECT_EQ(after_b2.mode, 16);
  EXPECT_EQ(after_b2.at_mode, 15);
  EXPECT_EQ(after_b2.spread, 2);
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
    // (the slider's blows on the spokes): -0.014 and +0.055 rad/s against
    // 0.18 and 0.19. Each engine's own speed follows (4.20 -> 4.04 rad/s,
    // 3.89 -> 4.27; before session 16's fix 4.21 -> 2.32 and 1.83 -> 4.11).
    EXPECT_LT(std::abs(jump), usual);
    // With induction_order = 2 (session 17; order 1: 4.2124 -> 4.1111 and
    // 3.9481 -> 4.2659) and the contact pairs handed over at the swap (4.1149
    // to Box2D without). Session 18, hinges rebuilt from their defining
    // points: Box2D -> ODE 3.8728 -> 4.2994 (3.8941 -> 4.2668 before).
    // Session 19, contacts kept across Box2D's one-step drops (kept_contacts):
    // ODE -> Box2D 4.2001 -> 4.2018, Box2D -> ODE 4.0573 -> 4.3160.
    // Session 20 (the coil's pull from the circuit's current of the kick's
    // instant): 4.2616 -> 4.2167 and 4.0761 -> 4.3131 (were 4.2001 -> 4.2018
    // and 4.0573 -> 4.3160).
    EXPECT_NEAR(before, to_b2 ? 4.2616 : 4.0761, 1e-3);
    EXPECT_NEAR(after, to_b2 ? 4.2167 : 4.3131, 1e-3);
    EXPECT_TRUE(has(r.stages, to_b2 ? "collisions.box2d" : "collisions"));
  }
}

// --- swaps and the contact set -------------------------------------------------------

/// Loads `scene`, schedules the swaps (time, from, to) and runs `seconds`.
test::EventRecords run_swapped(
    const std::string& scene, double seconds,
    const std::vector<std::tuple<double, const char*, const char*>>& swaps) {
  PluginRegistry registry;
  lua::LoadedScene loaded = load_kit_scene(scene, registry);
  World& world = *loaded.world;
  for (const auto& [at, from, to] : swaps) world.schedule_swap(at, "", from, to);
  test::EventRecords r;
  r.record(world);
  world.run(std::uint64_t(std::llround(seconds / world.dt())));
  return r;
}

TEST(KitOnBox2D, ASwapBeginsAndEndsNoContact) {
  // A box resting on a floor throughout, its engine swapped three times: one
  // contact, begun at the first step and never ended. Before the contact sets
  // handed their pairs over, each swap re-announced it as begun (4 in all) and
  // none was ever ended.
  const auto r = run_swapped("tests/resolvers/rigid_body_box2d/rest_on_floor.lua", 0.5,
                             {{0.1, kOde, kBox2D}, {0.2, kBox2D, kOde}, {0.3, kOde, kBox2D}});
  EXPECT_EQ(r.of("resolver_swapped").size(), 3u);
  EXPECT_EQ(r.of("contact_began").size(), 1u);
  EXPECT_EQ(r.of("contact_ended").size(), 0u);
}

TEST(KitOnBox2D, DoorbellRingsOnAfterASwapThereAndBackAtOnce) {
  // ODE -> Box2D at 0.7 s and back three steps later (an adversary's case):
  // Box2D's set saw the finger touching the interrupter, and when ODE came
  // back its set neither listed nor ended that pair, so the circuit stayed
  // closed through it for good: the coil held at 1.71 A, no strike after
  // 0.74 s. With the pairs handed over, the swap back ends it and the bell
  // rings on (ODE alone: 15 strikes a second from 1 s).
  const auto r = run_swapped("mods/doorbell", 2.0, {{0.7, kOde, kBox2D}, {0.7125, kBox2D, kOde}});
  int late = 0;
  for (const test::Record* e : r.of("sound", "bell")) late += e->time >= 1.0;
  std::printf("doorbell swapped to Box2D at 0.7 s and back at 0.7125 s: %d strikes in 1-2 s\n",
              late);
  EXPECT_GE(late, 12);
}

}  // namespace
}  // namespace alloy
