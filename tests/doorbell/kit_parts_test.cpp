// The kit's electrical, magnetic and acoustic parts (mods/kit/parts/electric,
// magnetic, acoustic.lua): each is a function from arguments to properties;
// these tests redo the arithmetic by hand (mods/kit/README.md, "How the
// numbers come out") and check the refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <numbers>

#include "tests/doorbell/doorbell_support.hpp"

namespace alloy::doorbell::test {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double mu0 = 1.25663706212e-6;

template <class T>
T get(const World& w, const std::string& object, const std::string& property) {
  const ObjectId id = w.find(object);
  if (!id) throw std::runtime_error("no object " + object);
  return std::get<T>(w.get(id, property));
}
bool has(const World& w, const std::string& object, const std::string& property) {
  const ObjectId id = w.find(object);
  auto p = w.properties().find(property);
  return id && p && w.store().has(id, *p);
}
std::string kind(const World& w, const std::string& object, const std::string& property) {
  const EnumValue v = get<EnumValue>(w, object, property);
  return w.properties().def(*w.properties().find(property)).enum_values.at(std::size_t(v.index));
}

/// Osborn's axial demagnetising factor of a prolate spheroid, p = length / diameter > 1.
double demagnetizing(double p) {
  const double s = std::sqrt(p * p - 1);
  return (p / s * std::log(p + s) - 1) / (p * p - 1);
}

class KitParts : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    scene = lua::load_scene(source("tests/doorbell/scenes/kit_parts.lua"), registry);
  }
  const World& w() const { return *scene.world; }
  PluginRegistry registry;
  lua::LoadedScene scene;
};

TEST_F(KitParts, BatteriesAreEmfsWithTerminalsAtTheirEnds) {
  EXPECT_DOUBLE_EQ(get<double>(w(), "battery", "emf"), 6);
  EXPECT_DOUBLE_EQ(get<double>(w(), "battery", "internal_resistance"), 0.5);
  EXPECT_TRUE(get<bool>(w(), "battery", "conductive"));
  EXPECT_TRUE(get<bool>(w(), "battery", "static"));
  EXPECT_FALSE(has(w(), "battery", "mass"));
  EXPECT_EQ(get<Vec3>(w(), "battery", "size"), (Vec3{0.115, 0.067, 0.067}));
  EXPECT_DOUBLE_EQ(get<double>(w(), "pack", "emf"), 12);
  EXPECT_TRUE(get<bool>(w(), "pack", "pinned"));
  EXPECT_DOUBLE_EQ(get<double>(w(), "pack", "mass"), 0.6);
}

TEST_F(KitParts, ContactsConductAndMayBePinned) {
  EXPECT_TRUE(get<bool>(w(), "contact", "conductive"));
  EXPECT_TRUE(get<bool>(w(), "contact", "static"));
  EXPECT_DOUBLE_EQ(get<double>(w(), "contact", "friction"), 0.4);  // brass
  EXPECT_TRUE(get<bool>(w(), "pinned_contact", "pinned"));
  EXPECT_NEAR(get<double>(w(), "pinned_contact", "mass"), 8960 * 0.02 * 0.01 * 0.02, 1e-12);
}

TEST_F(KitParts, AWiresResistanceIsRhoLengthOverArea) {
  EXPECT_EQ(get<ObjectId>(w(), "lead", "wire_from"), w().find("battery"));
  EXPECT_EQ(get<ObjectId>(w(), "lead", "wire_to"), w().find("contact"));
  EXPECT_EQ(get<std::int64_t>(w(), "lead", "wire_from_terminal"), 1);
  EXPECT_EQ(get<std::int64_t>(w(), "lead", "wire_to_terminal"), 0);
  // 1.5 x the 0.3 m between the parts' centres, 0.5 mm copper.
  EXPECT_NEAR(get<double>(w(), "lead", "resistance"), 1.68e-8 * 0.45 / (pi * 0.25e-6 / 4), 1e-12);
  EXPECT_NEAR(get<double>(w(), "long_lead", "resistance"), 1.68e-8 * 2 / (pi * 1e-6 / 4), 1e-12);
  EXPECT_FALSE(has(w(), "lead", "position")) << "a wire is not a body";
}

TEST_F(KitParts, ACoilsWindingAndCoreGiveItsResistanceInductanceAndPull) {
  // 500 turns of 0.5 mm copper between an 18 mm iron core and 30 mm, 50 mm long.
  const double ri = 0.009, ro = 0.015, L = 0.05, N = 500, d = 0.5e-3;
  const double mean_area = pi * (ro * ro * ro - ri * ri * ri) / (3 * (ro - ri));
  const double chi = 5000, nd = demagnetizing(L / 0.018);
  const double a_eff = mean_area + chi / (1 + nd * chi) * pi * 0.018 * 0.018 / 4;
  EXPECT_EQ(kind(w(), "coil", "magnet"), "electromagnet");
  EXPECT_DOUBLE_EQ(get<double>(w(), "coil", "turns"), N);
  EXPECT_NEAR(get<double>(w(), "coil", "resistance"),
              1.68e-8 * N * pi * (ri + ro) / (pi * d * d / 4), 1e-9);
  EXPECT_NEAR(get<double>(w(), "coil", "inductance"), mu0 * N * N * a_eff / L, 1e-9);
  EXPECT_NEAR(get<double>(w(), "coil", "coil_factor"), a_eff / (0.85 * L), 1e-9);
  // The figures the kit's README quotes.
  EXPECT_NEAR(get<double>(w(), "coil", "resistance"), 3.23, 0.005);
  EXPECT_NEAR(get<double>(w(), "coil", "inductance"), 0.0163, 0.0001);
  EXPECT_NEAR(get<double>(w(), "coil", "coil_factor"), 0.061, 0.0005);
  EXPECT_FALSE(has(w(), "coil", "conductive"))
      << "its winding is enamelled: touching it connects nothing";
  // The core is soft iron to the other parts too: an 18 mm rod, saturating
  // at Ms V over the pole separation.
  EXPECT_DOUBLE_EQ(get<double>(w(), "coil", "susceptibility"), chi);
  EXPECT_DOUBLE_EQ(get<double>(w(), "coil", "core_diameter"), 0.018);
  EXPECT_NEAR(get<double>(w(), "coil", "saturation_pole"),
              1.71e6 * pi * 0.018 * 0.018 / 4 * L / (0.85 * L), 1e-9);
  EXPECT_FALSE(has(w(), "air_coil", "susceptibility"));
  // Without the core: the winding's own area, far less pull per ampere-turn.
  EXPECT_NEAR(get<double>(w(), "air_coil", "coil_factor"), mean_area / (0.85 * L), 1e-12);
  EXPECT_GT(get<double>(w(), "coil", "coil_factor"),
            4 * get<double>(w(), "air_coil", "coil_factor"));
}

TEST_F(KitParts, TooManyTurnsForTheBobbinAreRefused) {
  const std::filesystem::path f = std::filesystem::temp_directory_path() /
                                  ("alloy_kit_coil_" + std::to_string(::getpid()) + ".lua");
  std::ofstream(f)
      << "local kit = require \"kit\"\nworld {}\n"
         "kit.coil { name = \"fat\", at = { 0, 0 }, turns = 500, wire_diameter = 0.7e-3 }\n";
  try {
    lua::load_scene(f, registry);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().object, "fat");
    EXPECT_EQ(e.where().line, 3);
    EXPECT_NE(std::string(e.what()).find("do not fit"), std::string::npos) << e.what();
  }
  std::filesystem::remove(f);
}

TEST_F(KitParts, MagnetsPoleStrengthComesFromTheirRemanence) {
  const double q =
      1.2 / mu0 * 0.01 * 0.01 / 0.85;  // M = Br / mu0 over the cross-section, poles 0.85 L apart
  EXPECT_EQ(kind(w(), "magnet", "magnet"), "permanent");
  EXPECT_NEAR(get<double>(w(), "magnet", "pole_strength"), q, 1e-9);
  EXPECT_NEAR(get<double>(w(), "magnet", "pole_strength"), 112.3, 0.1);
  EXPECT_NEAR(get<double>(w(), "ferrite", "pole_strength"), -q / 3, 1e-9)
      << "north at -x: negative";
  EXPECT_DOUBLE_EQ(get<double>(w(), "ferrite", "density"), 4900);
}

TEST_F(KitParts, IronIsSoftIronSteelOnlyWhenAsked) {
  for (const char* name : {"armature", "iron_bar", "magnetic_steel"}) {
    ASSERT_TRUE(has(w(), name, "magnet")) << name;
    EXPECT_EQ(kind(w(), name, "magnet"), "soft_iron") << name;
  }
  EXPECT_DOUBLE_EQ(get<double>(w(), "armature", "susceptibility"), 5000);
  EXPECT_DOUBLE_EQ(get<double>(w(), "magnetic_steel", "susceptibility"), 300);
  // Ms V / (0.85 L): an iron bar 100 x 20 x 20 mm.
  EXPECT_NEAR(get<double>(w(), "iron_bar", "saturation_pole"),
              1.71e6 * 0.1 * 0.02 * 0.02 / (0.85 * 0.1), 1e-9);
  EXPECT_FALSE(has(w(), "steel_bar", "magnet")) << "a steel bar is magnetic only when asked";
  EXPECT_TRUE(get<bool>(w(), "steel_bar", "conductive"));
  EXPECT_FALSE(has(w(), "wooden_bar", "conductive"));
  EXPECT_FALSE(has(w(), "wooden_bar", "magnet"));
}

TEST_F(KitParts, BellsRingWithTheirMetalsStiffnessAndDamping) {
  EXPECT_EQ(kind(w(), "bell", "acoustic"), "bell");
  EXPECT_DOUBLE_EQ(get<double>(w(), "bell", "youngs_modulus"), 1.1e11);
  EXPECT_DOUBLE_EQ(get<double>(w(), "bell", "loss_factor"), 1e-4);
  EXPECT_DOUBLE_EQ(get<double>(w(), "bell", "density"), 8600);
  EXPECT_TRUE(get<bool>(w(), "bell", "static"));
  EXPECT_FALSE(has(w(), "bell", "pitch")) << "the sound resolver computes it";
  EXPECT_DOUBLE_EQ(get<double>(w(), "tuned_bell", "pitch"), 1200);
  EXPECT_DOUBLE_EQ(get<double>(w(), "tuned_bell", "decay"), 2);
  EXPECT_NEAR(get<double>(w(), "tuned_bell", "mass"), 8600 * 4.0 / 3.0 * pi * 0.05 * 0.05 * 0.05,
              1e-9);
}

TEST_F(KitParts, TheSceneRunsAndTheBatteryDrivesItsCircuit) {
  // The battery's + end is wired to the contact and the contact back to its -
  // end: a loop of two copper wires (81 milliohm) and the battery's 0.5 ohm.
  World& world = *scene.world;
  world.run(2);
  const double r =
      get<double>(w(), "lead", "resistance") + get<double>(w(), "long_lead", "resistance") + 0.5;
  EXPECT_NEAR(get<double>(w(), "battery", "current"), 6 / r, 1e-9);
}

TEST(KitCircuitParts, ResistorCapacitorAndSwitchBecomeTheirProperties) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene scene =
      lua::load_scene(source("tests/doorbell/scenes/circuit_parts.lua"), registry);
  World& world = *scene.world;
  EXPECT_DOUBLE_EQ(get<double>(world, "resistor", "resistance"), 100);
  EXPECT_TRUE(get<bool>(world, "resistor", "conductive"));
  EXPECT_DOUBLE_EQ(get<double>(world, "capacitor", "capacitance"), 1e-3);
  EXPECT_DOUBLE_EQ(get<double>(world, "capacitor", "resistance"), 0.03);  // its ESR
  EXPECT_NEAR(get<double>(world, "capacitor", "mass"), 0.06, 1e-12);
  EXPECT_FALSE(get<bool>(world, "switch", "switch_closed"));
  EXPECT_TRUE(get<bool>(world, "closed_switch", "switch_closed"));
  EXPECT_DOUBLE_EQ(get<double>(world, "closed_switch", "resistance"), 0.01);
  // Open: the capacitor keeps its charge; closed, it charges towards C E = 6 mC
  // through the resistor (RC = 0.1 s).
  world.run(24);
  EXPECT_DOUBLE_EQ(get<double>(world, "capacitor", "plate_charge"), 1e-3);
  world.set(world.find("switch"), "switch_closed", true);
  world.run(24);  // 0.1 s
  const double q = get<double>(world, "capacitor", "plate_charge");
  const double r = 100 + 0.5 + 0.03 + 0.001 + get<double>(world, "w1", "resistance") +
                   get<double>(world, "w2", "resistance") + get<double>(world, "w3", "resistance") +
                   get<double>(world, "w4", "resistance");
  EXPECT_NEAR(q, 6e-3 - 5e-3 * std::exp(-0.1 / (r * 1e-3)), 1e-6);
}

}  // namespace
}  // namespace alloy::doorbell::test
