// Tests for the magnetism plugins in a world (resolvers/magnetism/): the
// magnetic_forces set against the pole formula, Newton's third law, softening;
// electromagnets driven through magnetism_from_electricity (zero current, the
// one-step delay, polarity, time constant, events) pulling soft iron with a
// force quadratic in the current that saturates; skipping; bad parts named.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "magnet_scene.hpp"

namespace alloy::magnetism {
namespace {

using namespace testing;

/// Force on bar b from bar a, both along their x axes, written independently
/// of the resolver: the four Coulomb terms, softened with `eps` (0: not at all).
Vec3 four_pole_force(Vec3 ca, Vec3 axis_a, double qa, double da, Vec3 cb, Vec3 axis_b, double qb,
                     double db, double eps = 0) {
  const Vec3 pa[2] = {ca + axis_a * (da / 2), ca - axis_a * (da / 2)};
  const Vec3 pb[2] = {cb + axis_b * (db / 2), cb - axis_b * (db / 2)};
  const double sa[2] = {qa, -qa}, sb[2] = {qb, -qb};
  Vec3 f;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const Vec3 r = pb[j] - pa[i];
      const double d = std::sqrt(dot(r, r) + eps * eps);
      f += r * (1.25663706212e-6 / (4 * std::numbers::pi) * sa[i] * sb[j] / (d * d * d));
    }
  return f;
}

class MagnetismTest : public ::testing::Test {
 protected:
  void SetUp() override {
    register_current_source(registry);
    register_magnetism_resolver(registry);
  }
  WorldDef softening(double eps) {
    WorldDef def;
    def.settings[MagneticForces::kName].set("softening", eps);
    return def;
  }
  PluginRegistry registry;
  const double d = kMagneticLengthRatio * kBarSize.x;  // default pole separation
};

TEST_F(MagnetismTest, NorthAttractsSouthAsThePoleFormulaSays) {
  World w(registry);
  const ObjectId a = add_permanent(w, "a", {0, 0, 0}, 0, 20);
  const ObjectId b = add_permanent(w, "b", {0.2, 0, 0}, 0, 30);  // its south faces a's north
  w.start();
  const MagneticForces& f = forces_of(w);
  const Vec3 fb = f.find(b)->force;
  const Vec3 ref = four_pole_force({0, 0, 0}, {1, 0, 0}, 20, d, {0.2, 0, 0}, {1, 0, 0}, 30, d);
  EXPECT_LT(fb.x, 0) << "b is pulled toward a";
  // Softening 5 mm at pole distances of 11.5 to 28.5 cm: 0.46 % weaker.
  EXPECT_NEAR(fb.x, ref.x, 0.01 * std::abs(ref.x));
  const double eps = MagneticForces::kDefaultSoftening;
  EXPECT_NEAR(fb.x,
              four_pole_force({0, 0, 0}, {1, 0, 0}, 20, d, {0.2, 0, 0}, {1, 0, 0}, 30, d, eps).x,
              1e-12 * std::abs(ref.x));
  EXPECT_NEAR(fb.y, 0, 1e-12 * std::abs(ref.x));
  EXPECT_NEAR(f.find(a)->force.x, -fb.x, 1e-12 * std::abs(fb.x));
  // The poles are where the docs say, north (> 0) at +x.
  ASSERT_EQ(f.poles().size(), 4u);
  EXPECT_NEAR(f.poles()[0].position.x, d / 2, 1e-15);
  EXPECT_GT(f.poles()[0].strength, 0);
  EXPECT_NEAR(f.poles()[1].position.x, -d / 2, 1e-15);
  EXPECT_LT(f.poles()[1].strength, 0);
}

TEST_F(MagnetismTest, WithoutSofteningFarMagnetsFollowTheDipoleLaw) {
  World w(registry, softening(0));
  add_permanent(w, "a", {0, 0, 0}, 0, 20);
  const ObjectId b = add_permanent(w, "b", {2.0, 0, 0}, 0, 30);
  w.start();
  const Vec3 fb = forces_of(w).find(b)->force;
  EXPECT_NEAR(fb.x, four_pole_force({0, 0, 0}, {1, 0, 0}, 20, d, {2, 0, 0}, {1, 0, 0}, 30, d).x,
              1e-12 * std::abs(fb.x));
  // Coaxial dipoles: F = 3 mu0 m1 m2 / (2 pi r^4), attractive; (d/r)^2 corrections 0.5 %.
  const double m1 = 20 * d, m2 = 30 * d;
  EXPECT_NEAR(fb.x, -3 * kMu0 * m1 * m2 / (2 * std::numbers::pi * 16.0), 0.01 * std::abs(fb.x));
}

TEST_F(MagnetismTest, LikePolesRepelAndANegativeStrengthTurnsTheMagnetAround) {
  auto force_on_b = [&](double angle_b, double qb) {
    World w(registry);
    add_permanent(w, "a", {0, 0, 0}, 0, 20);
    const ObjectId b = add_permanent(w, "b", {0.2, 0, 0}, angle_b, qb);
    w.start();
    return forces_of(w).find(b)->force;
  };
  const Vec3 turned = force_on_b(std::numbers::pi, 30);  // north faces north
  EXPECT_GT(turned.x, 0) << "like poles repel";
  const Vec3 reversed = force_on_b(0, -30);
  EXPECT_NEAR(reversed.x, turned.x, 1e-12 * turned.x);
  EXPECT_NEAR(force_on_b(0, 30).x, -turned.x, 1e-12 * turned.x);
}

TEST_F(MagnetismTest, ForcesAreEqualAndOppositeAndTorquesBalance) {
  World w(registry);
  const ObjectId a = add_permanent(w, "a", {0, 0, 0}, 0.3, 20);
  const ObjectId b = add_permanent(w, "b", {0.15, 0.08, 0.01}, 2.0, -35);
  w.start();
  const MagneticBody& ba = *forces_of(w).find(a);
  const MagneticBody& bb = *forces_of(w).find(b);
  const double scale = length(ba.force);
  ASSERT_GT(scale, 0);
  EXPECT_LT(length(ba.force + bb.force), 1e-13 * scale);
  // Angular momentum: the pole forces are central, so the torques about the
  // origin cancel.
  const Vec3 total = ba.torque + bb.torque + cross(Vec3{0, 0, 0}, ba.force) +
                     cross(Vec3{0.15, 0.08, 0.01}, bb.force);
  EXPECT_GT(length(ba.torque), 1e-3 * scale * 0.01);  // a real torque, not a trivial zero
  EXPECT_LT(length(total), 1e-13 * scale);
}

TEST_F(MagnetismTest, SofteningKeepsTouchingPolesFinite) {
  // Poles at the very ends: end to end, a's north and b's south coincide.
  const double eps = MagneticForces::kDefaultSoftening, q = 50;
  double peak = 0;
  for (int i = 0; i <= 100; ++i) {
    World w(registry);
    const ObjectId a = add_permanent(w, "a", {0, 0, 0}, 0, q);
    const ObjectId b = add_permanent(w, "b", {0.1 + 1e-4 * i, 0, 0}, 0, q);
    w.set(a, prop::kPoleSeparation, 0.1);
    w.set(b, prop::kPoleSeparation, 0.1);
    w.start();
    const Vec3 f = forces_of(w).find(b)->force;
    ASSERT_TRUE(is_finite(f)) << "gap " << 1e-4 * i;
    peak = std::max(peak, length(f));
  }
  // At most the softened peak of the touching pair plus the three far pairs.
  const double bound =
      kMu0Over4Pi * q * q * (2 / (3 * std::sqrt(3.0) * eps * eps) + 3 / (0.1 * 0.1));
  EXPECT_LT(peak, bound);
  EXPECT_GT(peak, 0.5 * bound);
}

/// A 500-turn coil at the origin and a soft-iron bar 15 cm along x, the
/// coil's current published as 0 and the world run `steps` steps.
struct CoilAndIron {
  ObjectId coil, iron;
};
CoilAndIron coil_and_iron(World& w, std::uint64_t steps) {
  const ObjectId coil = add_coil(w, "coil", {0, 0, 0}, 0, 500);
  const ObjectId iron = add_iron(w, "iron", {0.15, 0, 0}, 0, 1000);
  w.set(coil, prop::kCurrent, 0.0);
  w.run(steps);
  return {coil, iron};
}

TEST_F(MagnetismTest, ElectromagnetWithoutCurrentExertsNothing) {
  World w(registry);
  const auto [coil, iron] = coil_and_iron(w, 3);
  EXPECT_EQ(number(w, coil, prop::kPoleStrength), 0.0);
  EXPECT_EQ(forces_of(w).find(iron)->force, Vec3{});
  EXPECT_EQ(forces_of(w).find(iron)->pole_strength, 0.0);
  EXPECT_EQ(forces_of(w).find(coil)->force, Vec3{});
  EXPECT_TRUE(forces_of(w).poles().empty());
}

TEST_F(MagnetismTest, CurrentMagnetisesTheCoilOneStepLater) {
  // The paper's path: the interaction queues the current on the magnetism
  // resolver, whose pole strength the forces use from its next advance on
  // (magnetic_forces' setting coils_from_current = false).
  WorldDef def;
  def.settings[MagneticForces::kName].set("coils_from_current", false);
  World w(registry, def);
  const auto [coil, iron] = coil_and_iron(w, 5);
  auto& source = current_source_of(w);
  source.next = 2.0;
  w.step();  // electricity publishes 2 A; the interaction queues it
  EXPECT_EQ(number(w, coil, prop::kCurrent), 2.0);
  EXPECT_EQ(number(w, coil, prop::kPoleStrength), 0.0) << "not before the next advance";
  EXPECT_EQ(forces_of(w).find(iron)->force, Vec3{});
  w.step();  // magnetism performs it
  const double area = kBarSize.y * kBarSize.z;
  EXPECT_NEAR(number(w, coil, prop::kPoleStrength), area / d * 500 * 2.0, 1e-12);
  EXPECT_LT(forces_of(w).find(iron)->force.x, 0) << "soft iron is pulled toward the coil";
  EXPECT_EQ(magnetism_of(w).commanded_current(coil), 2.0);
  // Switching off works the same way, one step late.
  source.next = 0.0;
  w.step();
  EXPECT_GT(number(w, coil, prop::kPoleStrength), 0.0);
  w.step();
  EXPECT_EQ(number(w, coil, prop::kPoleStrength), 0.0);
  EXPECT_EQ(forces_of(w).find(iron)->force, Vec3{});
}

TEST_F(MagnetismTest, ACoilPullsWithTheCircuitsCurrentOfTheSameStep) {
  // The default (coils_from_current): magnetic_forces makes a coil that a
  // circuit drives as strong as the circuit's current of this update, so
  // the force the rigid body kicks with at an instant is that instant's
  // current (docs/magnetism.md "The coupling's timing"); the resolver's
  // pole_strength still follows a step later (the paper's path, events).
  World w(registry);
  const auto [coil, iron] = coil_and_iron(w, 5);
  auto& source = current_source_of(w);
  source.next = 2.0;
  w.step();  // electricity publishes 2 A
  const double area = kBarSize.y * kBarSize.z;
  const double q = area / d * 500 * 2.0;
  EXPECT_EQ(number(w, coil, prop::kPoleStrength), 0.0) << "the resolver's, a step later";
  EXPECT_NEAR(forces_of(w).find(coil)->pole_strength, q, 1e-12 * q);
  EXPECT_LT(forces_of(w).find(iron)->force.x, 0) << "soft iron is pulled in the same step";
  w.step();
  EXPECT_NEAR(number(w, coil, prop::kPoleStrength), q, 1e-12 * q);
  // Off: the pull ends with the current, in the same step.
  source.next = 0.0;
  w.step();
  EXPECT_EQ(forces_of(w).find(iron)->force, Vec3{});
  EXPECT_GT(number(w, coil, prop::kPoleStrength), 0.0) << "the resolver's, a step later";
}

/// Forces on a soft-iron bar 15 cm from a 500-turn coil carrying `current`
/// (steady state), and on the coil.
struct IronAndCoil {
  Vec3 iron, coil;
};
IronAndCoil iron_force(PluginRegistry& registry, double current, double saturation_pole = -1) {
  World w(registry);
  const ObjectId coil = add_coil(w, "coil", {0, 0, 0}, 0, 500);
  const ObjectId iron = add_iron(w, "iron", {0.15, 0, 0}, 0, 1000);
  if (saturation_pole >= 0) w.set(iron, prop::kSaturationPole, saturation_pole);
  w.set(coil, prop::kCurrent, 0.0);
  w.start();
  current_source_of(w).next = current;
  w.run(3);
  return {forces_of(w).find(iron)->force, forces_of(w).find(coil)->force};
}

TEST_F(MagnetismTest, ForceOnSoftIronGrowsWithTheSquareOfTheCurrent) {
  std::vector<double> f;
  for (double i : {0.25, 0.5, 1.0, 2.0}) {
    const IronAndCoil r = iron_force(registry, i);
    f.push_back(-r.iron.x);
    // The iron pulls the coil as hard: Newton's third law holds for induced poles too.
    EXPECT_NEAR(r.coil.x, -r.iron.x, 1e-12 * std::abs(r.iron.x));
  }
  for (std::size_t k = 0; k + 1 < f.size(); ++k) {
    EXPECT_GT(f[k], 0);
    EXPECT_NEAR(f[k + 1] / f[k], 4.0, 1e-4) << "doubling the current quadruples the pull";
  }
}

TEST_F(MagnetismTest, ForceOnSoftIronSaturates) {
  // A small saturation pole so that kit currents reach it: 0.02 A*m.
  const double qsat = 0.02;
  std::vector<double> currents = {0.005, 0.01, 1, 2, 4, 8};
  std::vector<double> f;
  for (double i : currents) f.push_back(-iron_force(registry, i, qsat).iron.x);
  EXPECT_NEAR(f[1] / f[0], 4.0, 0.01) << "linear regime";
  for (std::size_t k = 2; k + 1 < f.size(); ++k) {
    EXPECT_GT(f[k + 1], f[k]) << "more current still pulls harder";
    EXPECT_NEAR(f[k + 1] / f[k], 2.0, 0.01) << "saturated iron: force only linear in the current";
  }
}

TEST_F(MagnetismTest, CurrentDirectionSetsThePolarity) {
  auto force_on_magnet = [&](double current) {
    World w(registry);
    const ObjectId coil = add_coil(w, "coil", {0, 0, 0}, 0, 500);
    const ObjectId magnet = add_permanent(w, "magnet", {0.2, 0, 0}, 0, 20);  // south faces the coil
    w.set(coil, prop::kCurrent, 0.0);
    w.start();
    current_source_of(w).next = current;
    w.run(2);
    return forces_of(w).find(magnet)->force.x;
  };
  EXPECT_LT(force_on_magnet(3.0), 0) << "north at the coil's +x end attracts the magnet's south";
  EXPECT_GT(force_on_magnet(-3.0), 0) << "reversed current repels";
  EXPECT_NEAR(force_on_magnet(3.0), -force_on_magnet(-3.0), 1e-12);
}

TEST_F(MagnetismTest, CoilTimeConstantRampsThePoleStrengthExponentially) {
  World w(registry);
  const ObjectId coil = add_coil(w, "coil", {0, 0, 0}, 0, 100);
  w.set(coil, prop::kCurrent, 0.0);
  w.set(coil, prop::kCoilTimeConstant, 0.02);
  w.start();
  current_source_of(w).next = 1.0;
  w.step();  // the interaction queues 1 A
  const double target = kBarSize.y * kBarSize.z / d * 100 * 1.0;
  for (int n = 1; n <= 24; ++n) {
    w.step();
    EXPECT_NEAR(number(w, coil, prop::kPoleStrength), target * (1 - std::exp(-n * w.dt() / 0.02)),
                1e-12 * target)
        << "step " << n;
  }
}

TEST_F(MagnetismTest, CoilsSwitchingOnAndOffAreEvents) {
  World w(registry);
  const ObjectId coil = add_coil(w, "coil", {0, 0, 0}, 0, 100);
  w.set(coil, prop::kCurrent, 0.0);
  std::vector<Event> seen;
  w.add_observer([&](const Event& e) { seen.push_back(e); });
  w.run(2);
  auto& source = current_source_of(w);
  source.next = 1.5;
  w.run(3);
  source.next = 0;
  w.run(3);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].type, "electromagnet_on");
  EXPECT_EQ(seen[0].source, "magnetism");
  EXPECT_EQ(seen[0].a, coil);
  EXPECT_DOUBLE_EQ(seen[0].value("current"), 1.5);
  EXPECT_EQ(seen[1].type, "electromagnet_off");
}

TEST_F(MagnetismTest, ACommandForSomethingElseIsRefusedAndSaid) {
  World w(registry);
  const ObjectId magnet = add_permanent(w, "magnet", {0, 0, 0}, 0, 20);
  w.start();
  magnetism_of(w).set_coil_current(magnet, 1.0);
  w.step();
  ASSERT_EQ(w.events().size(), 1u);
  EXPECT_EQ(w.events()[0].type, "magnetism_command_refused");
  EXPECT_EQ(number(w, magnet, prop::kPoleStrength), 20.0);
}

TEST_F(MagnetismTest, ASceneWithoutMagnetsInstantiatesNoMagnetism) {
  World w(registry);
  const ObjectId rock = w.create("rock");
  w.set(rock, prop::kPosition, Vec3{0, 0, 0});
  w.run(3);
  for (const char* name : {"magnetism", "magnetic_forces", "magnetism_from_electricity"})
    EXPECT_FALSE(w.has_stage(name)) << name;
}

TEST_F(MagnetismTest, ForcesAreNotRecomputedWhileNothingChanges) {
  World w(registry);
  add_permanent(w, "a", {0, 0, 0}, 0, 20);
  const ObjectId b = add_permanent(w, "b", {0.2, 0, 0}, 0, 30);
  w.run(10);
  EXPECT_EQ(forces_of(w).updates(), 1u);  // the priming update only
  w.set(b, prop::kPosition, Vec3{0.25, 0, 0});
  w.step();
  EXPECT_EQ(forces_of(w).updates(), 2u);
}

TEST_F(MagnetismTest, APartThatCannotBeSimulatedIsNamed) {
  World w(registry);
  const ObjectId iron = add_bar(w, "striker", MagnetKind::SoftIron, {0, 0, 0});
  (void)iron;
  try {
    w.step();
    FAIL() << "soft iron without a susceptibility was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("object 'striker'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("susceptibility"), std::string::npos) << e.what();
  }
}

// docs/security.md's open hole (session 18): `turns` and `coil_factor` had no
// upper bound; a coil of 1e12 turns overflowed the energy books with no object
// named. Beyond their bounds they are refused on the write, naming the property.
TEST_F(MagnetismTest, TurnsAndCoilFactorBeyondTheirBoundsAreRefused) {
  World w(registry);
  const ObjectId coil = add_coil(w, "solenoid", {0, 0, 0}, 0, 500);
  const std::pair<const char*, double> refused[] = {{prop::kTurns, 1e12},
                                                    {prop::kTurns, 2 * kMaxTurns},
                                                    {prop::kCoilFactor, 1e300},
                                                    {prop::kCoilFactor, 2 * kMaxCoilFactor}};
  for (const auto& [property, value] : refused) {
    try {
      w.set(coil, property, value);
      ADD_FAILURE() << property << " = " << value << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + property + "' must lie between"),
                std::string::npos)
          << e.what();
    }
  }
  // The bounds themselves are values a scene may use.
  w.set(coil, prop::kTurns, kMaxTurns);
  w.set(coil, prop::kCoilFactor, kMaxCoilFactor);
  EXPECT_EQ(std::get<double>(w.get(coil, prop::kTurns)), kMaxTurns);
}

TEST_F(MagnetismTest, BadSofteningSettingIsRefused) {
  World w(registry, softening(-1));
  add_permanent(w, "a", {0, 0, 0}, 0, 20);
  EXPECT_THROW(w.start(), InputError);
}

}  // namespace
}  // namespace alloy::magnetism
