// The generator (mods/generator): the motor's rotor turned by a hand on a
// crank lights a lamp through its coils, by induction alone; and the kit's
// lamp and photocell as parts. docs/light.md has the figures these print.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "lua/scene_loader.hpp"
#include "resolvers/light/light_resolver.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy::generator::test {
namespace {

using alloy::test::source;

double number(const World& w, const char* object, const char* property) {
  return std::get<double>(w.get(w.find(object), property));
}

struct Steady {
  double speed = 0;        ///< mean angular velocity of the rotor, rad/s (anticlockwise +)
  double lamp_power = 0;   ///< mean radiant power of the lamp, W
  double lamp_energy = 0;  ///< what the light resolver reports radiated in the window, J
};

/// Runs the crank scene with the hand's torque `torque` (N m) from the start
/// for `seconds`, and measures the means over the last `window` seconds.
/// `open`: the loop is cut (the wire between the coils removed) before the start.
Steady crank(double torque, bool open = false, double seconds = 10, double window = 2,
             double dt = 0) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene scene =
      lua::load_scene(source("tests/generator/scenes/crank.lua"), registry, load);
  World& w = *scene.world;
  if (dt > 0) w.set_dt(dt);
  w.set(w.find("crank"), "drive_torque", Vec3{0, 0, torque});
  if (open) w.destroy(w.find("between_coils"));
  const int steps = int(std::lround(seconds / w.dt())),
            from = steps - int(std::lround(window / w.dt()));
  Steady s;
  for (int i = 0; i < steps; ++i) {
    w.step();
    if (i < from) continue;
    s.speed += std::get<Vec3>(w.get(w.find("axle"), "angular_velocity")).z;
    s.lamp_power += number(w, "lamp", "radiant_power");
    if (auto* light = dynamic_cast<light::LightResolver*>(w.stage("light")))
      s.lamp_energy += light->emitted_energy();
  }
  s.speed /= steps - from;
  s.lamp_power /= steps - from;
  return s;
}

// Turned at three torques, the lamp lights, and its power grows as the
// square of the speed (a resistive load on an EMF proportional to the
// speed) while the coils' reactance is small against the loop's 814 ohm:
// the log-log slope of power against speed is 2 within 10 % from 3.4 to 4.9
// rad/s (2.08). Faster, it falls below 2 (1.70 from 4.9 to 6.6 rad/s, the
// same at 1/240 and 1/960 s): the coils' L/R is 9.7 ms and the flat coils'
// EMF is peaked (docs/motor.md, k(theta)), so its harmonics, at 4, 12, 20
// times the speed, meet a reactance near the resistance. (Before session
// 20's coupling the slopes read 1.94 and 1.90 at 1/240 s, with the rotor
// 5.5 % slow at the highest torque: the step's error hid the inductance.)
TEST(Generator, LampPowerGrowsAsTheSquareOfTheCrankSpeed) {
  const double torques[] = {0.015, 0.02, 0.025};
  Steady s[3];
  for (int k = 0; k < 3; ++k) {
    s[k] = crank(torques[k]);
    std::printf("torque %.3f N m: %.2f rad/s, lamp %.5f W\n", torques[k], s[k].speed,
                s[k].lamp_power);
    EXPECT_GT(s[k].speed, 1.0);
    EXPECT_GT(s[k].lamp_power, 0.0);
    EXPECT_NEAR(s[k].lamp_energy, s[k].lamp_power * 2.0, 1e-9 + 1e-6 * s[k].lamp_power);
  }
  for (int k = 1; k < 3; ++k) {
    EXPECT_GT(s[k].speed, s[k - 1].speed);
    EXPECT_GT(s[k].lamp_power, s[k - 1].lamp_power);
    const double slope =
        std::log(s[k].lamp_power / s[k - 1].lamp_power) / std::log(s[k].speed / s[k - 1].speed);
    std::printf("log-log slope %.3f\n", slope);
    if (k == 1) {
      EXPECT_NEAR(slope, 2.0, 0.2);
    } else {
      EXPECT_LT(slope, 1.9) << "the coils' reactance takes a share at speed";
      EXPECT_GT(slope, 1.5);
    }
  }
}

// The same hand on the same crank: with the lamp's loop cut the rotor turns
// almost three times faster. The loop takes power (lamp and coils' copper)
// and the rotor pays for it: the induced current's field brakes the spokes
// (Lenz), through the same pole model that gives the EMF.
TEST(Generator, TheLampsLoadSlowsTheRotor) {
  const double torque = 0.02;
  const Steady loaded = crank(torque), open = crank(torque, true);
  std::printf("open %.2f rad/s, loaded %.2f rad/s, lamp %.5f W\n", open.speed, loaded.speed,
              loaded.lamp_power);
  EXPECT_EQ(open.lamp_power, 0.0);
  EXPECT_GT(loaded.lamp_power, 0.005);
  EXPECT_LT(loaded.speed, 0.5 * open.speed);
}

/// The falling-weight scene (mods/generator/weight.lua) for `seconds`: the
/// weight's downward speed and the lamp's energy over the run.
struct Fall {
  double speed = 0;        ///< m/s, downward, the mean over the last 2 s
  double rotor = 0;        ///< rad/s, the mean over the last 2 s
  double lamp_energy = 0;  ///< J radiated over the run
  double drop = 0;         ///< m fallen
};
Fall fall(bool open, double seconds = 6) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene scene = lua::load_scene(source("mods/generator/weight.lua"), registry, load);
  World& w = *scene.world;
  if (open) w.destroy(w.find("between_coils"));
  const ObjectId weight = w.find("weight");
  const double y0 = std::get<Vec3>(w.get(weight, "position")).y;
  Fall f;
  // Means over the last 2 s: the rotor's speed ripples within a turn (the
  // coils brake it hardest where a spoke's flux changes fastest) and the
  // elastic string lets the weight lag it, so single samples differ.
  const int n = int(std::lround(seconds / w.dt())), from = n - int(std::lround(2.0 / w.dt()));
  for (int i = 0; i < n; ++i) {
    w.step();
    if (auto* light = dynamic_cast<light::LightResolver*>(w.stage("light")))
      f.lamp_energy += light->emitted_energy();
    if (i < from) continue;
    f.speed -= std::get<Vec3>(w.get(weight, "velocity")).y / (n - from);
    f.rotor += std::get<Vec3>(w.get(w.find("axle"), "angular_velocity")).z / (n - from);
  }
  f.drop = y0 - std::get<Vec3>(w.get(weight, "position")).y;
  return f;
}

// A falling weight on a string wound on the hub turns the rotor and lights
// the lamp; the lamp's load holds the weight back: with the loop cut it
// falls faster. The string pays out what the drum turns (v = omega r).
TEST(Generator, AFallingWeightLightsTheLampAndIsHeldBackByIt) {
  const Fall loaded = fall(false), open = fall(true);
  std::printf(
      "falling weight, 6 s: loaded %.3f m/s (%.2f rad/s, %.3f m, lamp %.4f J), open %.3f m/s (%.3f "
      "m)\n",
      loaded.speed, loaded.rotor, loaded.drop, loaded.lamp_energy, open.speed, open.drop);
  EXPECT_GT(loaded.lamp_energy, 0.05);
  EXPECT_EQ(open.lamp_energy, 0.0);
  EXPECT_LT(loaded.speed, 0.8 * open.speed);
  EXPECT_LT(loaded.drop, open.drop);
  EXPECT_NEAR(loaded.speed, loaded.rotor * 0.022, 0.05 * loaded.speed);
}

// Not a test: the figures of docs/light.md ("The generator"), at three steps.
// Run with --gtest_also_run_disabled_tests --gtest_filter=*Study*.
TEST(Generator, DISABLED_Study) {
  for (double dt : {1.0 / 240, 1.0 / 480, 1.0 / 960}) {
    const Steady loaded = crank(0.02, false, 10, 2, dt), open = crank(0.02, true, 10, 2, dt);
    std::printf("dt 1/%.0f: open %.3f rad/s, loaded %.3f rad/s, lamp %.5f W\n", 1 / dt, open.speed,
                loaded.speed, loaded.lamp_power);
  }
}

// The kit's lamp lights and its photocell's resistance falls with the light.
TEST(KitLightParts, LampLightsAndPhotocellResponds) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene scene =
      lua::load_scene(source("tests/generator/scenes/lamp_photocell.lua"), registry);
  World& w = *scene.world;
  EXPECT_DOUBLE_EQ(number(w, "lamp", "resistance"), 12);
  EXPECT_DOUBLE_EQ(number(w, "lamp", "luminous_efficacy"), 10);
  EXPECT_DOUBLE_EQ(number(w, "cell", "resistance"), 1e6);
  EXPECT_TRUE(std::get<bool>(w.get(w.find("cell"), "light_receiver")));
  w.run(4);
  const double p = number(w, "lamp", "radiant_power");
  EXPECT_GT(p, 2.0);
  const double flux = number(w, "lamp", "luminous_flux");
  EXPECT_NEAR(flux, 10 * p, 1e-9 * flux);
  // 10 cm below the lamp, face up: E = flux / (4 pi 0.01 m^2).
  const double e = flux / (4 * std::numbers::pi * 0.01);
  const double r = std::max(100.0, 1e6 * std::pow(e / 0.0139, -0.7));
  const double wires = number(w, "w3", "resistance") + number(w, "w4", "resistance") + 0.5;
  EXPECT_NEAR(number(w, "cell", "current"), 5 / (r + wires), 1e-6 * 5 / r);
  std::printf("lamp %.3f W, %.2f lm; %.1f lux on the cell, %.1f Ohm\n", p, flux, e, r);
}

}  // namespace
}  // namespace alloy::generator::test
