// The commutation chain's rates (electricity `rates`, magnetism `rates`): a
// coil's current reaches the magnetism with its dI/dt, and the pole strength
// is set for the end of the window instead of a window late. A 6 V battery on
// a 60 mH, 5.9 Ohm coil (tau = 10 ms) switched on at t = 0: the analytic
// current is I(t) = I_inf (1 - exp(-t / tau)).
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "magnet_scene.hpp"
#include "resolvers/electricity/electricity.hpp"
#include "resolvers/magnetism/magnetism_from_electricity.hpp"

namespace alloy::magnetism {
namespace {

using namespace testing;

struct Circuit {
  PluginRegistry registry;
  std::unique_ptr<World> world;
  ObjectId coil;
  /// `force_rates`: magnetic_forces publishes its rates too.
  explicit Circuit(bool rates, double dt = 1.0 / 240, bool force_rates = false) {
    electricity::register_electricity_resolver(registry);
    register_magnetism_resolver(registry);
    WorldDef def;
    def.dt = dt;
    if (force_rates) def.settings["magnetic_forces"].set("rates", true);
    // Electricity publishes its rates by default (for the coupling's timing,
    // docs/magnetism.md); "without rates" turns them off.
    def.settings["electricity"].set("rates", rates);
    if (rates) def.settings["magnetism"].set("rates", true);
    world = std::make_unique<World>(registry, def);
    World& w = *world;
    const ObjectId battery = w.create("battery");
    w.set(battery, "emf", 6.0);
    w.set(battery, "internal_resistance", 0.1);
    coil = add_coil(w, "coil", {0, 0, 0}, 0, 200);
    w.set(coil, "inductance", 0.06);
    w.set(coil, "resistance", 5.9);
    for (auto [name, from, ft, to, tt] :
         {std::tuple{"w1", battery, 1, coil, 0}, std::tuple{"w2", coil, 1, battery, 0}}) {
      const ObjectId id = w.create(name);
      w.set(id, "wire_from", from);
      w.set(id, "wire_from_terminal", std::int64_t(ft));
      w.set(id, "wire_to", to);
      w.set(id, "wire_to_terminal", std::int64_t(tt));
      w.set(id, "resistance", 0.0);
    }
  }
  /// Pole strength per ampere of the test coil (magnet_scene.hpp's bar, 200 turns).
  static double per_ampere() {
    return kBarSize.y * kBarSize.z / (kMagneticLengthRatio * kBarSize.x) * 200;
  }
};

constexpr double kTau = 0.06 / 6.0, kInf = 6.0 / 6.0;  // L / R_total, s; V / R_total, A

double analytic(double t) {
  return kInf * -std::expm1(-t / kTau);
}

TEST(CurrentRates, TheCoilPublishesItsRateOnlyWithTheSetting) {
  Circuit off(false);
  off.world->run(3);
  // With the settings off the columns stay empty.
  EXPECT_ANY_THROW(off.world->get(off.coil, electricity::prop::kCurrentRate));
  EXPECT_ANY_THROW(off.world->get(off.coil, prop::kPoleStrengthRate));

  Circuit on(true);
  on.world->run(3);
  World& w = *on.world;
  // Backward Euler's last substep: L dI/dt = V - R I at the step's end.
  const double i = number(w, on.coil, electricity::prop::kCurrent);
  EXPECT_NEAR(number(w, on.coil, electricity::prop::kCurrentRate), (kInf - i) / kTau,
              1e-6 * kInf / kTau);
}

TEST(CurrentRates, PoleStrengthNoLongerLagsTheCurrentByAWindow) {
  // Without rates the pole strength at time t is the current of t - dt; with
  // them, the current moved on by its rate: the error against the analytic
  // current at t is a fraction of the one-window lag's.
  double lag_error = 0, rate_error = 0;
  for (bool rates : {false, true}) {
    Circuit c(rates);
    World& w = *c.world;
    double worst = 0;
    w.step();  // the first current reaches the magnetism a step late either way
    for (int n = 0; n < 12; ++n) {  // five time constants
      w.step();
      const double q = number(w, c.coil, prop::kPoleStrength) / Circuit::per_ampere();
      worst = std::max(worst, std::abs(q - analytic(w.time())));
    }
    (rates ? rate_error : lag_error) = worst;
  }
  std::printf("largest |q / (k N) - I(t)|: %.4f A held, %.4f A with rates\n", lag_error,
              rate_error);
  EXPECT_LT(rate_error, 0.5 * lag_error);
}

TEST(CurrentRates, TheForcesFollowThePoleStrengthRate) {
  // A permanent magnet beside the rising coil: with rates, magnetic_forces'
  // force rate on it is d/dt of the force through the coil's pole strength
  // (nothing moves), so value + rate * dt predicts the next window's force
  // far better than the held value.
  for (bool rates : {false, true}) {
    // A tenth of the coil's tau: the rate is a window stale.
    Circuit c(rates, 1.0 / 960, /*force_rates=*/true);
    World& w = *c.world;
    const ObjectId magnet = add_permanent(w, "magnet", {0.1, 0, 0}, 0, 10.0);
    w.run(4);
    ASSERT_NE(forces_of(w).find(magnet), nullptr);
    const MagneticBody b = *forces_of(w).find(magnet);  // a copy: the set is rewritten
    const Vec3 predicted = b.force + b.force_rate * w.dt();
    w.step();
    const Vec3 next = forces_of(w).find(magnet)->force;
    ASSERT_GT(length(next - b.force), 0.0);  // the coil's current is still rising
    if (rates) {
      // The rate is the current's at the command's time, a window before the
      // forces' (the exponential's slope then was e^(dt/tau) = 1.1x larger).
      EXPECT_LT(length(next - predicted), 0.3 * length(next - b.force));
    } else {
      EXPECT_EQ(b.force_rate, Vec3{});  // nothing moves: no rate without the chain's
    }
  }
}

}  // namespace
}  // namespace alloy::magnetism
