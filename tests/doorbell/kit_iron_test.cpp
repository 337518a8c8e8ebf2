// Iron in the kit's coils and bars, tried with the viewer's palette parts
// (tests/doorbell/scenes/kit_iron.lua): a palette coil on a palette battery
// moves a palette armature lying 4 mm from its pole, standing 1 to 4 mm
// under it, or touching it (issue 17);
// an unpowered cored coil pulls a magnet and an air-cored one does not; an
// iron bar across a field turns to align (issue 13).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "tests/doorbell/doorbell_support.hpp"

namespace alloy::doorbell::test {
namespace {

constexpr double pi = std::numbers::pi;

// One run of the scene, shared by the tests: 1 s of simulated time, with the
// positions and angles of the parts the tests read at its start and end.
class KitIron : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::LoadedScene scene =
        lua::load_scene(source("tests/doorbell/scenes/kit_iron.lua"), registry);
    World& w = *scene.world;
    const char* parts[] = {"lying_armature",      "idle_armature",       "standing_armature",
                           "standing_2_armature", "standing_3_armature", "standing_4_armature",
                           "touching_armature",   "loose_armature",      "core_magnet",
                           "air_magnet",          "turn_armature"};
    for (const char* p : parts) start_[p] = state(w, p);
    // The bar's angle through the run, to see it settle.
    for (int i = 0; i < 240; ++i) {
      w.run(1);
      turn_.push_back(state(w, "turn_armature").angle);
    }
    for (const char* p : parts) end_[p] = state(w, p);
  }
  struct State {
    Vec3 at;
    double angle = 0;
  };
  static State state(const World& w, const std::string& name) {
    const ObjectId id = w.find(name);
    if (!id) throw std::runtime_error("no object " + name);
    return {std::get<Vec3>(w.get(id, "position")),
            angle_z(std::get<Quat>(w.get(id, "orientation")))};
  }
  static Vec3 moved(const std::string& name) { return end_[name].at - start_[name].at; }
  static inline std::map<std::string, State> start_, end_;
  static inline std::vector<double> turn_;
};

TEST_F(KitIron, APaletteCoilPullsAnArmatureLying4mmFromItsPole) {
  // The coil's +x end is 4 mm to the armature's left: it slides there.
  EXPECT_LT(moved("lying_armature").x, -0.0035) << "pulled onto the pole";
  EXPECT_GT(moved("lying_armature").x, -0.0045) << "and stopped by the coil";
  // With no battery the core is unmagnetised and nothing pulls.
  EXPECT_LT(std::abs(moved("idle_armature").x), 1e-5);
}

TEST_F(KitIron, APaletteCoilLiftsAnArmatureStandingUnderIt) {
  // 1, 2, 3 and 4 mm below the upright coil's pole face: lifted onto it
  // (issue 17). Until session 16 only across 1 mm: soft iron's induced poles
  // sat 0.075 of its length inside its faces, and from 2 mm the pull was less
  // than the bar's 0.386 N weight.
  EXPECT_GT(moved("standing_armature").y, 0.0008) << "lifted " << moved("standing_armature").y;
  EXPECT_GT(moved("standing_2_armature").y, 0.0018) << "lifted " << moved("standing_2_armature").y;
  EXPECT_GT(moved("standing_3_armature").y, 0.0028) << "lifted " << moved("standing_3_armature").y;
  EXPECT_GT(moved("standing_4_armature").y, 0.0038) << "lifted " << moved("standing_4_armature").y;
  // And no higher than the coil's face (a lift of the gap, less the
  // contact's slop).
  EXPECT_LT(moved("standing_4_armature").y, 0.0045);
}

TEST_F(KitIron, APaletteCoilHoldsUpAnArmatureTouchingIt) {
  EXPECT_LT(std::abs(moved("touching_armature").y), 1e-3) << "held against the coil";
  EXPECT_LT(moved("loose_armature").y, -1.0) << "without the battery it falls";
}

TEST_F(KitIron, AnUnpoweredCoilsIronCoreIsPulledByAMagnet) {
  // A magnet hung on a hinge 12 cm up, 10 mm from the coil: it swings to
  // the core (the pull is mutual: the core is pulled as hard).
  EXPECT_LT(moved("core_magnet").x, -0.005) << "swung to the coil";
  // An air-cored coil with no current is not magnetic at all.
  EXPECT_LT(std::abs(moved("air_magnet").x), 1e-4) << "a hinge settling, no pull";
}

TEST_F(KitIron, AnIronBarAcrossAFieldTurnsToAlignWithIt) {
  // Put down at 60 degrees to the field between the magnets (along x).
  EXPECT_NEAR(start_["turn_armature"].angle, pi / 3, 1e-9);
  const double settled = std::remainder(end_["turn_armature"].angle, pi);
  EXPECT_LT(std::abs(settled), 0.05) << "settled at " << settled * 180 / pi << " degrees";
  // It turned towards the field at once, not away from it first.
  EXPECT_LT(turn_[23], pi / 3 - 0.01);
}

}  // namespace
}  // namespace alloy::doorbell::test
