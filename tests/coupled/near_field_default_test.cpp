// The coil's near field is on by default (issue 13, adv13 F10): a magnet
// flown along the axis of an air-cored coil, in a scene that does not name
// magnetic_forces' near_field, induces the current of the coil as a current
// sheet, two lobes of opposite sign; a scene that names near_field false
// still gets the pole pair's, whose flux changes sign inside the coil (four
// to six lobes). Each against a fine RK4 of the coupled equations with the
// flux written out from closed forms (analytic_scenes.hpp induction_flux).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/analytic_scenes.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy {
namespace {

namespace an = scenes::analytic;

// 100 turns: weakly braked either way (the magnet passes through at about
// 0.5 m/s, from x = -0.4 to 0.4 m in 1.6 s), so the lobes are the flux
// gradient's along the axis.
constexpr double kTurns = 100, kDt = 1.0 / 960, kSeconds = 1.6;

/// The changes of sign of the current, ignoring samples under 2 % of its
/// peak (rounding, not lobes).
int sign_changes(const std::vector<double>& current) {
  double peak = 0;
  for (double i : current) peak = std::max(peak, std::abs(i));
  int changes = 0, last = 0;
  for (double i : current) {
    if (std::abs(i) < 0.02 * peak) continue;
    const int sign = i > 0 ? 1 : -1;
    if (last != 0 && sign != last) ++changes;
    last = sign;
  }
  return changes;
}

/// The reference's sign changes: -dPhi/dx v / R at constant speed, on the
/// run's path (x from -0.4 to 0.4 m), from the closed form alone.
int reference_sign_changes(bool near_field) {
  std::vector<double> quasi_steady;
  for (double x = -0.4; x <= 0.4; x += 1e-4)
    quasi_steady.push_back(-an::induction_gradient(x, kTurns, near_field));
  return sign_changes(quasi_steady);
}

TEST(NearField, IsOnByDefaultAMagnetFlownThroughAnAirCoilInducesTwoLobes) {
  ASSERT_EQ(reference_sign_changes(true), 1);
  std::vector<double> current;
  const an::Method unnamed{.induction_order = 2};  // near_field not named
  ASSERT_EQ(unnamed.near_field, -1);
  const an::Result r = an::run_induction(kDt, unnamed, kSeconds, kTurns, &current);
  ASSERT_TRUE(r.finite);
  std::printf(
      "default: current error %.5f of the peak against the sheet's flux; %d change(s) "
      "of sign; end speed %.5f m/s (reference %.5f)\n",
      r.error, sign_changes(current), r.measured, r.exact);
  EXPECT_LT(r.error, 0.01);
  EXPECT_EQ(sign_changes(current), 1);
}

TEST(NearField, NamedFalseKeepsThePolePair) {
  const int pair_changes = reference_sign_changes(false);
  ASSERT_GE(pair_changes, 3);  // its flux changes sign inside the coil
  std::vector<double> current;
  const an::Result r =
      an::run_induction(kDt, {.induction_order = 2, .near_field = 0}, kSeconds, kTurns, &current);
  ASSERT_TRUE(r.finite);
  std::printf(
      "near_field false: current error %.5f of the peak against the pole pair's flux; "
      "%d changes of sign (the pair's closed form: %d)\n",
      r.error, sign_changes(current), pair_changes);
  EXPECT_LT(r.error, 0.01);
  EXPECT_EQ(sign_changes(current), pair_changes);
}

// The same scene as a scene file (what bench/near_field_cost.sh times),
// through the Lua loader, naming no near_field: the magnet leaves the
// 4000-turn coil at the speed of the RK4 on the sheet's flux (0.1720 m/s;
// the pole pair's near field would hold it inside the coil).
TEST(NearField, IsOnByDefaultInASceneFile) {
  const an::Result reference = an::run_induction(1.0 / 240, {.induction_order = 2});
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene loaded = lua::load_scene(
      test::source("tests/coupled/scenes/magnet_through_air_coil.lua"), registry, {});
  World& w = *loaded.world;
  w.start();
  const auto steps = std::uint64_t(std::llround(loaded.seconds / w.dt()));
  for (std::uint64_t i = 0; i < steps; ++i) w.step();
  const double v = w.value<Vec3>(w.find("mag"), "velocity").value_or(Vec3{}).x;
  std::printf("scene file: the magnet leaves at %.4f m/s (RK4 on the sheet: %.4f)\n", v,
              reference.exact);
  EXPECT_NEAR(v, reference.exact, 0.01 * reference.exact);
}

}  // namespace
}  // namespace alloy
