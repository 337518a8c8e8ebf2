// The electric motor (mods/motor, docs/motor.md): built from kit parts only,
// turned by nothing but the physics. These tests run its scenes headless and
// check what the paper (4.2) says the motor does: it starts by itself, turns
// anticlockwise at a steady speed from frame 200, its two electromagnets take
// turns, and it stops when the battery is taken away; then the same with the
// step halved, the battery 10 % weaker and stronger and the bearing stiffer,
// and from rotors put down out of place.
//
// Frames are steps at the scene's time step, 1/240 s (motor_support.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <numbers>
#include <sstream>

#include "apps/alloy/commands.hpp"
#include "tests/motor/motor_support.hpp"

namespace alloy::motor::test {
namespace {

constexpr double kRelease = 0.1;  // mods/motor/scene.lua: at(0.1, "slider", { pinned = false })
constexpr double kBatteryOffAt =
    5.0;  // mods/motor/battery_off.lua: at(5.0, "battery", { emf = 0 })
constexpr double kPitch = std::numbers::pi / 4;  // one spoke
/// The scene's steady speed, rad/s (docs/motor.md: 4.19 at 1/240 s, 4.24 at
/// 1/480 s and 4.26 at 1/960 s since the energy-consistent coupling; 4.44
/// and 4.36 before, from above: the limit is near 4.28), set by the
/// back-EMF, and how far a variant may stray from it.
constexpr double kSpeed = 4.25, kSpeedTolerance = 0.3;

std::string describe(const Steadiness& s) {
  std::ostringstream o;
  o << s.turns << " turns, mean " << s.mean << " rad/s, from " << s.min << " to " << s.max;
  return o.str();
}

/// What every running motor must show between frames 200 and 2000: it turns
/// anticlockwise, at least `min_turns` whole turns, each turn's mean speed
/// within `max_spread` (max - min over mean) of the others.
Steadiness expect_turns_steadily(const RunResult& r, std::size_t min_turns = 4,
                                 double max_spread = 0.10) {
  const Steadiness s = steadiness(revolutions(r, kSteadyFrom, kSteadyTo));
  EXPECT_GE(s.turns, min_turns) << describe(s);
  EXPECT_GT(s.min, 0) << "every turn anticlockwise: " << describe(s);
  EXPECT_LT(s.spread(), max_spread) << describe(s);
  return s;
}

/// The coils switched on, in order, within [t0, t1); `current` above the
/// electricity resolver's powered threshold (1 mA), so that the exponential
/// tail of a coil's current through a dead battery does not count.
std::vector<const Record*> switched_on(const RunResult& r, double t0, double t1) {
  std::vector<const Record*> out;
  for (const Record* e : r.of("electromagnet_on"))
    if (e->time >= t0 && e->time < t1 && std::abs(e->value("current")) > 1e-3) out.push_back(e);
  return out;
}

/// The two coils take turns: each on is the other coil's, and each coil is
/// switched off before it comes on again.
void expect_alternation(const RunResult& r, double t0, double t1) {
  const auto on = switched_on(r, t0, t1);
  ASSERT_GE(on.size(), 8u);
  for (std::size_t i = 1; i < on.size(); ++i)
    ASSERT_NE(on[i]->a, on[i - 1]->a)
        << "step " << on[i]->step << ": " << on[i]->a << " came on twice in a row";
  for (const char* coil : {"upper_coil", "lower_coil"}) {
    std::vector<std::pair<std::uint64_t, bool>> switches;
    for (const Record& e : r.events)
      if (e.a == coil && e.time >= t0 && e.time < t1 &&
          (e.type == "electromagnet_on" || e.type == "electromagnet_off"))
        switches.push_back({e.step, e.type == "electromagnet_on"});
    for (std::size_t i = 1; i < switches.size(); ++i)
      ASSERT_NE(switches[i].second, switches[i - 1].second)
          << coil << " at step " << switches[i].first;
  }
}

// --- the scene: start-up, steady running, alternation ------------------------------

TEST(Motor, StartsUpAsThePaperTellsIt) {
  const RunResult r = run_motor(kScene, {.seconds = 1.0});
  EXPECT_DOUBLE_EQ(r.dt, kSceneDt);
  // 4.2.1: the sliding contact falls onto the top spoke; the circuit closes
  // and the upper electromagnet comes on.
  const auto released = r.of("input", "slider");
  ASSERT_EQ(released.size(), 1u);
  EXPECT_NEAR(released[0]->time, kRelease, 1.5 * r.dt);
  const auto touched = r.of("contact_began");
  const auto first_touch = std::find_if(touched.begin(), touched.end(),
                                        [](const Record* e) { return e->b == "slider"; });
  ASSERT_NE(first_touch, touched.end());
  const Record& touch = **first_touch;
  EXPECT_EQ(touch.a, "spoke_N3")
      << "the north spoke under the slider, where the bias magnet put it";
  EXPECT_GT(touch.time, kRelease);
  EXPECT_LT(touch.time, kRelease + 0.25) << "it falls for a few tenths of a second at most";
  const auto on = switched_on(r, 0, 1);
  ASSERT_FALSE(on.empty());
  EXPECT_EQ(on[0]->a, "upper_coil") << "a north spoke powers the upper coil";
  // One step for the contact to close the circuit, one for the magnet.
  const auto closed = r.of("circuit_closed", "upper_coil");
  ASSERT_FALSE(closed.empty());
  EXPECT_EQ(closed[0]->step, touch.step + 1);
  EXPECT_EQ(on[0]->step, touch.step + 2);
  // Until then the rotor was held by the bias magnet; then it turns, anticlockwise.
  EXPECT_NEAR(r.angle[r.at(touch.time)], 0, 0.01) << "at rest until the first contact";
  const std::size_t i = r.at(touch.time);
  std::size_t begun = i;
  while (begun < r.angle.size() && r.angle[begun] - r.angle[i] < kPitch) ++begun;
  ASSERT_LT(begun, r.angle.size()) << "it never turned by one spoke";
  EXPECT_LT(r.time[begun], kSteadyFrom) << "rotation begins well before frame 200";
  // 4.2.3: the next spoke reaches the slider, a south one, and the other coil takes over.
  ASSERT_GE(on.size(), 2u);
  EXPECT_EQ(on[1]->a, "lower_coil");
}

TEST(Motor, TurnsAnticlockwiseAtASteadySpeedFromFrame200) {
  const RunResult r = run_motor(kScene, {.seconds = kSteadyTo + 0.1});
  // 4.19 rad/s over the 7.5 s window is 5.0 turns, 4 of them whole.
  const Steadiness s = expect_turns_steadily(r, 4, 0.10);
  // Measured (docs/motor.md): 4.19 rad/s, set by the back-EMF.
  EXPECT_NEAR(s.mean, kSpeed, kSpeedTolerance);
  // With induction_order = 2 (the scene names it since session 17) the rotor
  // still gains its last 1.2 % in the first turn from frame 200: per turn
  // 4.185, 4.236, 4.235, 4.237, 4.236 rad/s (spread 1.21 %; 0.04 % from the
  // second turn on). With order 1 it was 4.186 to 4.189 (0.09 %). Was 1 %.
  EXPECT_LT(s.spread(), 0.015);
}

TEST(Motor, TheTwoElectromagnetsTakeTurns) {
  const RunResult r = run_motor(kScene, {.seconds = kSteadyTo + 0.1});
  expect_alternation(r, kSteadyFrom, kSteadyTo);
  // Eight spokes: each turn switches each coil on four times.
  const double turns =
      (r.angle[r.at(kSteadyTo)] - r.angle[r.at(kSteadyFrom)]) / (2 * std::numbers::pi);
  const auto on = switched_on(r, kSteadyFrom, kSteadyTo);
  EXPECT_NEAR(double(on.size()), 8 * turns, 1.5);
  // And only the coil of the spoke touched: never both for more than the
  // step of a hand-over.
  for (const Record* e : r.of("circuit_closed")) {
    if (e->time >= kSteadyFrom && e->time < kSteadyTo && e->a != "battery") {
      EXPECT_TRUE(e->a == "upper_coil" || e->a == "lower_coil") << e->a;
    }
  }
}

TEST(Motor, RemovingTheBatteryStopsIt) {
  const RunResult r = run_motor(kBatteryOff);
  const auto cut = r.of("input", "battery");
  ASSERT_EQ(cut.size(), 1u);
  EXPECT_NEAR(cut[0]->time, kBatteryOffAt, 1.5 * r.dt);  // stamped at the end of its step
  const Steadiness before = steadiness(revolutions(r, kSteadyFrom, kBatteryOffAt));
  EXPECT_GE(before.turns, 2u) << "it ran until then";
  // No coil is powered by the battery once it is gone (a step for the
  // resolvers to see it). While the rotor still turns it induces a current
  // in the coil whose spoke the slider touches (a generator, short-circuited
  // through the battery's 0.5 ohm): it flows against the way the battery
  // drove it, and brakes the rotor. At a hand-over the collapse of one
  // coil's generated current induces a forward kick in the other through
  // their mutual inductance (1.04 mA for two steps at 5.07 s since the
  // energy-consistent coupling, just above the 1 mA powered threshold): 2 mA
  // is still far below the 4.5 mA the battery drove.
  double generated = 0;
  for (std::size_t i = r.at(kBatteryOffAt + 2 * r.dt); i < r.time.size(); ++i) {
    if (r.spin[i] < 0.1) continue;
    EXPECT_LT(r.coil_current[i], 2e-3) << "driven forward at " << r.time[i] << " s";
    generated = std::min(generated, r.coil_current[i]);
  }
  EXPECT_LT(generated, -5e-3) << "the turning rotor drives a current back";
  // It runs down and stops: measured 0.9 s (docs/motor.md).
  std::size_t last_moving = 0;
  for (std::size_t i = 0; i < r.spin.size(); ++i)
    if (std::abs(r.spin[i]) > 1e-3) last_moving = i;
  EXPECT_GT(r.time[last_moving], kBatteryOffAt);
  EXPECT_LT(r.time[last_moving], kBatteryOffAt + 2.0)
      << "still turning " << r.time[last_moving] - kBatteryOffAt << " s after the battery went";
  EXPECT_LT(std::abs(r.angle.back() - r.angle[r.at(kBatteryOffAt + 2.5)]), 1e-3)
      << "and stays stopped";
}

// --- the same with small changes: robust, not at a knife edge ----------------------

TEST(MotorRobustness, HalfTheStep) {
  const RunResult r = run_motor(kScene, {.dt = kSceneDt / 2, .seconds = kSteadyTo + 0.1});
  const Steadiness s = expect_turns_steadily(r);
  EXPECT_NEAR(s.mean, kSpeed, kSpeedTolerance) << "the speed hardly depends on the step";
  expect_alternation(r, kSteadyFrom, kSteadyTo);
}

TEST(MotorRobustness, TenPercentLessEmf) {
  const RunResult r = run_motor(kScene, {.seconds = kSteadyTo + 0.1, .emf_scale = 0.9});
  expect_turns_steadily(r);
  expect_alternation(r, kSteadyFrom, kSteadyTo);
}

TEST(MotorRobustness, TenPercentMoreEmf) {
  const RunResult r = run_motor(kScene, {.seconds = kSteadyTo + 0.1, .emf_scale = 1.1});
  expect_turns_steadily(r);
  expect_alternation(r, kSteadyFrom, kSteadyTo);
}

TEST(MotorRobustness, TwiceTheBearingFriction) {
  const RunResult r = run_motor(kScene, {.seconds = kSteadyTo + 0.1, .friction_scale = 2});
  expect_turns_steadily(r);
  expect_alternation(r, kSteadyFrom, kSteadyTo);
}

TEST(MotorRobustness, HalfTheStepAndTenPercentLessEmf) {
  const RunResult r =
      run_motor(kScene, {.dt = kSceneDt / 2, .seconds = kSteadyTo + 0.1, .emf_scale = 0.9});
  expect_turns_steadily(r);
}

/// The bias magnet's job (paper 4.2): wherever the rotor is put down, it
/// settles where it can start. Here it is put down turned by up to 40
/// degrees, the slider is let go at 3 s, and it must run as the scene does.
/// In its oiled bearing the rotor rocks on the bias magnet for over two
/// seconds (the dry friction takes about 6 degrees off each swing) and stops
/// within the dry friction's band about the detent: 2 mN m against the
/// detent's 0.039 N m/rad, 2.9 degrees.
class MotorPutDownOutOfPlace : public ::testing::TestWithParam<int> {};

TEST_P(MotorPutDownOutOfPlace, SettlesOnTheBiasMagnetAndStarts) {
  namespace fs = std::filesystem;
  const int degrees = GetParam();
  const fs::path f =
      fs::temp_directory_path() / ("alloy_motor_put_down_" + std::to_string(::getpid()) + "_" +
                                   std::to_string(degrees + 90) + ".lua");
  std::ofstream(f) << "world { dt = 1 / 240, seconds = 6, settings = { [\"gravity.uniform\"] = { g "
                      "= { 0, -9.81, 0 } } } }\n"
                      "local m = require \"motor.layout\" { rotor_angle = "
                   << degrees
                   << ", slider_release = 3 }\n"
                      "for _, s in ipairs(m.sliders) do at(3, s, { pinned = false }) end\n";
  const RunResult r = run_motor(f.string());
  fs::remove(f);
  // Settled by 3 s, within the friction band of where the bias holds it
  // (the axle's own angle counts from where it was put down). A rotor put
  // down more than 22.5 degrees off goes to the next such place, 90 degrees on.
  const double settled = r.angle[r.at(3.0)] * 180 / std::numbers::pi;
  const double off = std::remainder(settled + degrees, 90.0);
  EXPECT_LT(std::abs(off), 3.5) << "settled at " << settled << " degrees";
  EXPECT_LT(std::abs(r.spin[r.at(3.0)]), 1e-3);
  // Then it starts, anticlockwise, and runs steadily.
  const Steadiness s = steadiness(revolutions(r, 4.0, 6.0));
  EXPECT_GE(s.turns, 1u) << describe(s);
  EXPECT_GT(s.min, 0) << describe(s);
  EXPECT_NEAR(s.mean, kSpeed, kSpeedTolerance) << describe(s);
}

INSTANTIATE_TEST_SUITE_P(Degrees, MotorPutDownOutOfPlace,
                         ::testing::Values(-40, -20, -10, 10, 20, 40));

// --- the command: `alloy run mods/motor` tells the start-up -------------------------

TEST(MotorCommand, TheRunNarratesTheStartUp) {
  const std::string scene = source(kScene).string();
  const char* argv[] = {"alloy", "run", scene.c_str(), "--seconds", "1"};
  std::ostringstream out, err;
  ASSERT_EQ(app::run_cli(int(std::size(argv)), argv, out, err), app::kExitOk) << err.str();
  // Each in its order, on a line of its own or shared with others of its type
  // and step ("circuit closed: upper_coil, battery").
  std::istringstream lines(out.str());
  const std::vector<std::pair<std::string, std::string>> told = {
      {"input", "slider"},
      {"contact began", "spoke_N3 - slider"},
      {"circuit closed", "upper_coil"},
      {"electromagnet on", "upper_coil"},
      {"contact began", "spoke_S3 - slider"},
      {"electromagnet on", "lower_coil"}};
  std::size_t next = 0;
  for (std::string line; next < told.size() && std::getline(lines, line);)
    if (line.find(told[next].first + ": ") != std::string::npos &&
        line.find(told[next].second) != std::string::npos)
      ++next;
  EXPECT_EQ(next, told.size()) << "'"
                               << (next < told.size() ? told[next].first + ": " + told[next].second
                                                      : "")
                               << "' is not told, in its order:\n"
                               << out.str();
}

// --- the kit's part the motor needed -------------------------------------------------

TEST(MotorKit, NeodymiumMagnetsConductFerriteOnesDoNot) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(source(kScene), registry, load);
  World& w = *loaded.world;
  for (const char* spoke : {"spoke_N1", "spoke_N2", "spoke_N3", "spoke_N4", "spoke_S1", "spoke_S2",
                            "spoke_S3", "spoke_S4"})
    EXPECT_TRUE(std::get<bool>(w.get(w.find(spoke), "conductive"))) << spoke;
  EXPECT_FALSE(w.store().has(w.find("bias"), w.properties().id("conductive")))
      << "the ferrite bias magnet";
  // North out and south out in turn: the pole at the spoke's outer end.
  for (const char* spoke : {"spoke_N1", "spoke_N3"})
    EXPECT_GT(std::get<double>(w.get(w.find(spoke), "pole_strength")), 100) << spoke;
  for (const char* spoke : {"spoke_S1", "spoke_S3"})
    EXPECT_LT(std::get<double>(w.get(w.find(spoke), "pole_strength")), -100) << spoke;
}

}  // namespace
}  // namespace alloy::motor::test
