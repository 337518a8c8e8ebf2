// Strong induction coupling (issue 13, adversary adv13's F2): a magnet
// dropped into a closed coil at the default step, where the eddy braking
// rate G^2/(m R) times the step is above 1, is thrown back up by the
// one-step-late coupling. electricity_from_magnetism reports such a pair
// once (the event `induction_coupling_strong`, naming the coil and the
// part, with the step that would bring the gain down); at that step the
// magnet falls as it should. An open coil, and the bundled motor, doorbell
// and generator, report nothing (docs/energy.md "Limits").
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "lua/scene_loader.hpp"
#include "resolvers/electricity/electricity_from_magnetism.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

namespace alloy {
namespace {

constexpr const char* kStrong = "induction_coupling_strong";

struct Drop {
  test::EventRecords events;
  double highest_after_start = -1e9;  ///< the magnet's highest y after its first 0.05 s, m
  double largest_gain = 0;            ///< the stage's largest per-step gain
};

/// Runs `scene` for `seconds` at `dt` (0: the scene's own), recording events
/// and the magnet's height (when it has one named "mag").
Drop run(const std::string& scene, double dt, double seconds) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(test::source("mods"));
  lua::LoadedScene loaded = lua::load_scene(test::source(scene), registry, load);
  World& w = *loaded.world;
  if (dt > 0) w.set_dt(dt);
  Drop out;
  out.events.record(w);
  w.start();
  const ObjectId mag = w.find("mag");
  const auto steps = std::uint64_t(std::llround(seconds / w.dt()));
  for (std::uint64_t i = 0; i < steps; ++i) {
    w.step();
    if (mag && w.time() > 0.05)
      out.highest_after_start =
          std::max(out.highest_after_start, w.value<Vec3>(mag, "position").value_or(Vec3{}).y);
  }
  if (const auto* stage = dynamic_cast<const magnetism::ElectricityFromMagnetism*>(
          w.stage(magnetism::ElectricityFromMagnetism::kName)))
    out.largest_gain = stage->largest_coupling_gain();
  return out;
}

TEST(StrongCoupling, AMagnetDroppedIntoAClosedCoilAtTheDefaultStepIsReportedOnce) {
  const Drop d = run("tests/coupled/scenes/drop_into_coil.lua", 0, 1.0);
  const auto strong = d.events.of(kStrong);
  std::printf("1/240 s: largest gain %.3f, %zu report(s), highest after 0.05 s %.4f m\n",
              d.largest_gain, strong.size(), d.highest_after_start);
  ASSERT_EQ(strong.size(), 1u);
  EXPECT_EQ(strong[0]->a, "coil");
  EXPECT_EQ(strong[0]->b, "mag");
  EXPECT_GE(strong[0]->value("gain"), magnetism::ElectricityFromMagnetism::kStrongCouplingGain);
  EXPECT_DOUBLE_EQ(strong[0]->value("dt"), 1.0 / 240);
  EXPECT_LT(strong[0]->value("dt_suggested"), 1.0 / 240);
  EXPECT_DOUBLE_EQ(strong[0]->value("mass"), 0.015);
  // Reported when the magnet nears the coil (before 0.1 s, gain at least
  // the threshold). Before session 20 the magnet was then thrown back and
  // rose above its release (0.163 m at 0.57 s); since the coil pulls with the
  // circuit's current of the kick's instant, its highest after 0.05 s is
  // 0.0645 m at 1/240 s, against 0.0676 m in runs at 1/960 and 1/3840 s of
  // either coupling (0.0742 and 0.0676 m new, 0.0675 and 0.0676 m before):
  // the trajectory is right to 5 %, but the books are not (docs/energy.md
  // "Limits"), so the report stays.
  EXPECT_LT(strong[0]->time, 0.1);
  EXPECT_GT(d.highest_after_start, 0.055);
  EXPECT_LT(d.highest_after_start, 0.075) << "not thrown back above its release";
}

TEST(StrongCoupling, AtHalfTheSuggestedStepTheMagnetIsNotThrownBack) {
  const Drop coarse = run("tests/coupled/scenes/drop_into_coil.lua", 0, 1.0);
  ASSERT_EQ(coarse.events.of(kStrong).size(), 1u);
  const double suggested = coarse.events.of(kStrong)[0]->value("dt_suggested");
  // The suggestion brings the gain where the pair was reported down to
  // half the threshold; the magnet goes on into a steeper gradient (2.7
  // Wb/m where it was reported, 6.3 inside the coil), so half of it.
  const double dt = 1.0 / std::ceil(2 / suggested);
  const Drop fine = run("tests/coupled/scenes/drop_into_coil.lua", dt, 1.0);
  std::printf("1/%.0f s: largest gain %.3f, highest after 0.05 s %.4f m (release 0.08 m)\n", 1 / dt,
              fine.largest_gain, fine.highest_after_start);
  // Braked, never thrown back: it stays below where it was after 0.05 s of
  // free fall (0.08 - g 0.05^2 / 2 = 0.0677 m). Measured 0.0674 m, with a
  // largest gain of 0.58 (so reported again, deep in the coil).
  EXPECT_LT(fine.highest_after_start, 0.068);
  EXPECT_LT(fine.largest_gain, 1.0);
}

TEST(StrongCoupling, BelowTheThresholdNothingIsReportedAndTheMagnetFalls) {
  const Drop fine = run("tests/coupled/scenes/drop_into_coil.lua", 1.0 / 1920, 1.0);
  std::printf("1/1920 s: largest gain %.3f, highest after 0.05 s %.4f m\n", fine.largest_gain,
              fine.highest_after_start);
  EXPECT_TRUE(fine.events.of(kStrong).empty());
  EXPECT_LT(fine.largest_gain, magnetism::ElectricityFromMagnetism::kStrongCouplingGain);
  EXPECT_GT(fine.largest_gain, 0.1);  // the coupling is there, only weaker
  EXPECT_LT(fine.highest_after_start, 0.068);
}

TEST(StrongCoupling, AnOpenCoilReportsNothing) {
  const Drop d = run("tests/coupled/scenes/drop_into_open_coil.lua", 0, 0.3);
  EXPECT_TRUE(d.events.of(kStrong).empty());
  EXPECT_EQ(d.largest_gain, 0.0);
}

TEST(StrongCoupling, TheBundledInductionScenesReportNothing) {
  for (const char* scene : {"mods/motor", "mods/doorbell", "mods/generator"}) {
    const Drop d = run(scene, 0, 1.0);
    std::printf("%s: largest gain %.2e over 1 s\n", scene, d.largest_gain);
    EXPECT_TRUE(d.events.of(kStrong).empty()) << scene;
    // Measured 0.17 (the motor: its rotor's magnets, each taken at its own
    // mass though the rotor's inertia resists the coil), 0.012 (the
    // doorbell), 0.29 (the generator since its coils lost their iron cores in
    // session 18: air-cored coils of 5100 turns 1.5 mm from the spokes; 0.022
    // before). Below the report threshold with room; the generator's margin
    // is the smallest.
    EXPECT_LT(d.largest_gain, (std::string(scene) == "mods/generator" ? 0.7 : 0.5) *
                                  magnetism::ElectricityFromMagnetism::kStrongCouplingGain)
        << scene;
  }
}

}  // namespace
}  // namespace alloy
