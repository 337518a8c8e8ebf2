// Tests for resolvers/light/: lamps radiate the power they take, the
// illuminance set's inverse-square and cosine laws, and photocells whose
// resistance falls with the light on them, against closed forms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/light/light_interactions.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/energy_ledger.hpp"
#include "runtime/world.hpp"

namespace alloy::light {
namespace {

constexpr double kPiValue = 3.14159265358979323846;

class LightTest : public ::testing::Test {
 protected:
  void SetUp() override { register_native_plugins(registry); }

  static WorldDef def(double ambient = 0) {
    WorldDef d;
    d.dt = 1.0 / 240.0;
    if (ambient > 0) d.settings["illuminance"].set("ambient", ambient);
    return d;
  }
  static ObjectId placed(World& w, const std::string& name, Vec3 at, double angle = 0) {
    const ObjectId id = w.create(name);
    w.set(id, "position", at);
    w.set(id, "orientation", Quat::from_angle_z(angle));
    return id;
  }
  static ObjectId battery(World& w, const std::string& name, double emf, double r, Vec3 at) {
    const ObjectId id = placed(w, name, at);
    w.set(id, "emf", emf);
    w.set(id, "internal_resistance", r);
    w.set(id, "conductive", true);
    return id;
  }
  // A lamp: a resistor that carries a luminous efficacy.
  static ObjectId lamp(World& w, const std::string& name, double r, double efficacy, Vec3 at) {
    const ObjectId id = placed(w, name, at);
    w.set(id, "conductive", true);
    w.set(id, "resistance", r);
    w.set(id, "luminous_efficacy", efficacy);
    return id;
  }
  // A photocell facing +y turned by `angle` about z: a resistor (its
  // resistance property is the dark one) that receives light.
  static ObjectId photocell(World& w, const std::string& name, Vec3 at, double angle = 0) {
    const ObjectId id = placed(w, name, at, angle);
    w.set(id, "conductive", true);
    w.set(id, "resistance", kDark);
    w.set(id, "light_receiver", true);
    w.set(id, "dark_resistance", kDark);
    w.set(id, "dark_illuminance", kE0);
    w.set(id, "photo_gamma", kGamma);
    w.set(id, "lit_resistance", kLit);
    return id;
  }
  static ObjectId receiver(World& w, const std::string& name, Vec3 at, double angle = 0) {
    const ObjectId id = placed(w, name, at, angle);
    w.set(id, "light_receiver", true);
    return id;
  }
  static void wire(World& w, const std::string& name, ObjectId from, int ft, ObjectId to, int tt) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
    w.set(id, "resistance", kWire);
  }
  // battery + -> a -> b -> battery - (b may be null: a alone).
  static void loop(World& w, const std::string& tag, ObjectId bat, ObjectId a, ObjectId b = {}) {
    wire(w, tag + "_w1", bat, 1, a, 0);
    if (b.is_null()) {
      wire(w, tag + "_w2", a, 1, bat, 0);
    } else {
      wire(w, tag + "_w2", a, 1, b, 0);
      wire(w, tag + "_w3", b, 1, bat, 0);
    }
  }
  static double num(const World& w, ObjectId id, const char* p) {
    return std::get<double>(w.get(id, p));
  }
  static LightResolver& light(World& w) { return dynamic_cast<LightResolver&>(*w.stage("light")); }
  static IlluminanceSet& set(World& w) {
    return dynamic_cast<IlluminanceSet&>(*w.stage("illuminance"));
  }
  static electricity::ElectricityResolver& electric(World& w) {
    return dynamic_cast<electricity::ElectricityResolver&>(*w.stage("electricity"));
  }

  static constexpr double kDark = 1e6, kE0 = 0.0139, kGamma = 0.7, kLit = 100, kWire = 0.01;
  PluginRegistry registry;
};

// P = V^2 / R on the lamp, and the closed form E^2 R / (R + r)^2; its flux is
// efficacy x P, one step after the electricity computed it.
TEST_F(LightTest, LampRadiatesItsElectricalPower) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {0, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0.2, 0, 0});
  loop(w, "l", b, l);
  w.step();
  // The first step primes: the light resolver advanced before any current flowed.
  EXPECT_EQ(num(w, l, "radiant_power"), 0.0);
  w.step();
  const double total = 12.0 + 0.5 + 2 * kWire;
  const double p = 6.0 * 6.0 * 12.0 / (total * total);
  const double v = num(w, l, "voltage");
  EXPECT_NEAR(num(w, l, "radiant_power"), p, 1e-10 * p);
  EXPECT_NEAR(num(w, l, "radiant_power"), v * v / 12.0, 1e-10 * p);
  EXPECT_NEAR(num(w, l, "luminous_flux"), 10.0 * p, 1e-9 * p);
  EXPECT_NEAR(light(w).emitted_energy(), p * w.dt(), 1e-10 * p * w.dt());
  EXPECT_EQ(light(w).lit_count(), 1u);
}

// Light is a ledger account (docs/energy.md "Light"): a lamp on a 6 V, 0.5
// Ohm battery through a 7.5 Ohm resistor takes P = E^2 R / (R + r)^2, steady
// from the first step (no coil, no capacitor); its visible share, efficacy /
// 683 lm/W, leaves electricity's heat as the transfer "light" and the light
// resolver receives the same, record by record, holds a step's worth (the
// step's delay) and lets the rest leave the scene.
TEST_F(LightTest, LampsLightIsALedgerAccountWithTwoSidesThatAgree) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {0, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0.2, 0, 0});
  const ObjectId r = placed(w, "resistor", {0.4, 0, 0});
  w.set(r, "conductive", true);
  w.set(r, "resistance", 7.5);
  loop(w, "l", b, l, r);
  EnergyLedger books;
  w.start();
  books.record(w);
  const int steps = 240;
  double worst = 0;  // the two sides' largest disagreement in one record, J
  for (int k = 0; k < steps; ++k) {
    w.step();
    books.record(w);
    const EnergyAccount* given = books.find("electricity", "light");
    const EnergyAccount* taken = books.find("light", "light");
    ASSERT_TRUE(given && taken);
    worst = std::max(worst, std::abs(given->last + taken->last));
  }
  const double total_r = 12.0 + 7.5 + 0.5 + 3 * kWire, i = 6.0 / total_r;
  const double p = i * i * 12.0, eta = 10.0 / 683, dt = w.dt();
  const double light_given = -books.find("electricity", "light")->total;
  const double received = books.find("light", "light")->total;
  const double left = books.find("light", "light leaving the scene")->total;
  const double held = books.find("light", "light queued for the next step")->total;
  const double heat = books.find("electricity", "heat (I^2 R)")->total;
  std::printf(
      "lamp %.6f W (closed form), light %.9f J given, %.9f J received, %.9f J left, %.9f J "
      "held (closed form eta P t %.9f J); worst record %.1e J; residue %.1e of %.4f J moved\n",
      p, light_given, received, left, held, eta * p * steps * dt, worst, books.total().residue(),
      books.total().moved);
  // Every record's two sides agree to rounding, and so do the run's.
  EXPECT_LT(worst, 1e-15);
  EXPECT_NEAR(received, light_given, 1e-14);
  // The closed form: eta P over every advance; the light resolver radiated
  // all but the last step's, which waits for its next advance.
  EXPECT_NEAR(light_given, eta * p * steps * dt, 1e-10 * light_given);
  EXPECT_NEAR(held, eta * p * dt, 1e-10 * held);
  EXPECT_NEAR(left, eta * p * (steps - 1) * dt, 1e-10 * left);
  // Heat and light together are the circuit's whole I^2 R.
  EXPECT_NEAR(heat + light_given, i * i * total_r * steps * dt, 1e-9 * heat);
  EXPECT_LT(books.total().fraction(), 1e-12);
}

// The lamp's wire cut: the next step it takes nothing and is dark.
TEST_F(LightTest, ALampOutOfItsCircuitIsDark) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {0, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0.2, 0, 0});
  loop(w, "l", b, l);
  for (int i = 0; i < 3; ++i) w.step();
  ASSERT_GT(num(w, l, "luminous_flux"), 1.0);
  w.destroy(w.find("l_w2"));
  for (int i = 0; i < 3; ++i) w.step();
  EXPECT_EQ(num(w, l, "luminous_flux"), 0.0);
  EXPECT_EQ(num(w, l, "radiant_power"), 0.0);
  EXPECT_EQ(light(w).emitted_energy(), 0.0);
}

// Receivers facing the lamp at 1, 2 and 4 m: E = Phi / (4 pi d^2), so each
// doubling of the distance quarters it; a face turned by 60 degrees gets
// half (cosine law), one turned away gets nothing; ambient adds to each.
TEST_F(LightTest, IlluminanceFollowsTheInverseSquareAndCosineLaws) {
  World w(registry, def(0.5));
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {-1, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0, 0, 0});
  loop(w, "l", b, l);
  // Below the lamp, faces up (+y) towards it.
  std::vector<ObjectId> at;
  for (double d : {1.0, 2.0, 4.0})
    at.push_back(receiver(w, "r" + std::to_string(int(d)), {0, -d, 0}));
  const ObjectId tilted = receiver(w, "tilted", {0, -1, 0}, kPiValue / 3);
  const ObjectId away = receiver(w, "away", {0, -1, 0}, kPiValue);
  for (int i = 0; i < 4; ++i) w.step();
  const double flux = num(w, l, "luminous_flux");
  ASSERT_GT(flux, 10.0);
  const IlluminanceSet& s = set(w);
  EXPECT_EQ(s.receivers().size(), 5u);
  for (std::size_t k = 0; k < 3; ++k) {
    const double d = std::pow(2.0, double(k));
    const double e = flux / (4 * kPiValue * d * d);
    EXPECT_NEAR(s.share(at[k], l), e, 1e-12 * e) << "at " << d << " m";
    EXPECT_NEAR(s.illuminance(at[k]), e + 0.5, 1e-12 * e);
  }
  EXPECT_NEAR(s.share(at[0], l) / s.share(at[1], l), 4.0, 1e-12);
  EXPECT_NEAR(s.share(at[0], l) / s.share(at[2], l), 16.0, 1e-12);
  EXPECT_NEAR(s.share(tilted, l), 0.5 * s.share(at[0], l), 1e-12 * flux);
  EXPECT_EQ(s.share(away, l), 0.0);
  EXPECT_EQ(s.illuminance(away), 0.5);  // ambient only
}

// Two lamps add; a lamp closer than a bulb's size counts as 1 cm away.
TEST_F(LightTest, LampsAddAndACloseLampIsFinite) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {-1, 0, 0});
  const ObjectId l1 = lamp(w, "l1", 12.0, 10.0, {0, 1, 0});
  const ObjectId l2 = lamp(w, "l2", 12.0, 10.0, {0, 2, 0});
  loop(w, "l", b, l1, l2);
  const ObjectId r = receiver(w, "r", {0, 0, 0});
  const ObjectId touching = receiver(w, "touching", {0, 1 - 1e-6, 0});
  for (int i = 0; i < 3; ++i) w.step();
  const double flux = num(w, l1, "luminous_flux");
  ASSERT_GT(flux, 1.0);
  EXPECT_NEAR(set(w).illuminance(r), flux / (4 * kPiValue) * (1 + 0.25), 1e-12 * flux);
  const double close = set(w).share(touching, l1);
  EXPECT_NEAR(close, flux / (4 * kPiValue * kMinDistance * kMinDistance), 1e-9 * close);
}

// The LDR law alone: dark up to E0, a power law above, bounded below.
TEST_F(LightTest, PhotocellLawIsBoundedPowerLaw) {
  EXPECT_EQ(photocell_resistance(0, kDark, kE0, kGamma, kLit), kDark);
  EXPECT_EQ(photocell_resistance(kE0, kDark, kE0, kGamma, kLit), kDark);
  EXPECT_EQ(photocell_resistance(std::nan(""), kDark, kE0, kGamma, kLit), kDark);
  EXPECT_NEAR(photocell_resistance(10, kDark, kE0, kGamma, kLit), 10.0e3,
              0.02 * 10e3);  // the datasheet point
  const double r1 = photocell_resistance(100, kDark, kE0, kGamma, kLit);
  const double r2 = photocell_resistance(200, kDark, kE0, kGamma, kLit);
  EXPECT_NEAR(r1 / r2, std::pow(2.0, kGamma), 1e-12);
  EXPECT_EQ(photocell_resistance(1e9, kDark, kE0, kGamma, kLit), kLit);
}

// A photocell in its own circuit, facing a lamp at 0.1, 0.2 and 0.4 m: its
// resistance and current follow R(E(d)) (and so fall as the lamp nears).
TEST_F(LightTest, PhotocellResistanceFollowsTheLampsDistance) {
  std::vector<double> rs;
  for (double d : {0.1, 0.2, 0.4}) {
    World w(registry, def());
    const ObjectId b = battery(w, "battery", 6.0, 0.5, {-1, 0, 0});
    const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0, 0, 0});
    loop(w, "l", b, l);
    const ObjectId b2 = battery(w, "sense", 5.0, 0.0, {1, 0, 0});
    const ObjectId pc = photocell(w, "pc", {0, -d, 0});
    loop(w, "p", b2, pc);
    for (int i = 0; i < 4; ++i) w.step();
    const double flux = num(w, l, "luminous_flux");
    const double e = flux / (4 * kPiValue * d * d);
    const double r = kDark * std::pow(e / kE0, -kGamma);
    ASSERT_GT(r, kLit);
    EXPECT_NEAR(electric(w).set_resistance_of(pc), r, 1e-9 * r) << d;
    // The cell's current is the sense battery's over R + the two wires.
    const double i = 5.0 / (r + 2 * kWire + electricity::kMinResistance);
    EXPECT_NEAR(num(w, pc, "current"), i, 1e-8 * i) << d;
    rs.push_back(r);
    std::printf("lamp %.3f lm; photocell at %.1f m: %.3f lux, %.1f Ohm, %.4f mA\n", flux, d, e, r,
                1e3 * num(w, pc, "current"));
  }
  EXPECT_NEAR(rs[1] / rs[0], std::pow(4.0, kGamma), 1e-9);
  EXPECT_NEAR(rs[2] / rs[1], std::pow(4.0, kGamma), 1e-9);
}

// A photocell with no lamp anywhere keeps its resistance property (dark);
// removing its light (the lamp destroyed) brings it back there.
TEST_F(LightTest, PhotocellWithoutLightIsDark) {
  World w(registry, def());
  const ObjectId b2 = battery(w, "sense", 5.0, 0.0, {1, 0, 0});
  const ObjectId pc = photocell(w, "pc", {0, -0.1, 0});
  loop(w, "p", b2, pc);
  for (int i = 0; i < 3; ++i) w.step();
  const double dark_i = 5.0 / (kDark + 2 * kWire + electricity::kMinResistance);
  EXPECT_NEAR(num(w, pc, "current"), dark_i, 1e-9 * dark_i);
  EXPECT_EQ(electric(w).set_resistance_of(pc), kDark);  // E = 0 <= E0: the dark value
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {-1, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0, 0, 0});
  loop(w, "l", b, l);
  for (int i = 0; i < 4; ++i) w.step();
  EXPECT_GT(num(w, pc, "current"), 100 * dark_i);
  w.destroy(l);
  for (int i = 0; i < 4; ++i) w.step();
  EXPECT_NEAR(num(w, pc, "current"), dark_i, 1e-9 * dark_i);
}

// Light drives its own circuit back: a 12 V battery feeds, through a 50 Ohm
// resistor, a 60 Ohm lamp with a photocell across it, 2 cm away and facing
// it. The brighter the lamp, the lower the cell's resistance, the more it
// shunts the lamp: negative feedback through two physics, each leg a step
// late. It settles where R = law(E(R)), solved here by bisection with the
// same constants (g(R) = law(E(R)) - R falls through zero once).
TEST_F(LightTest, LampAndPhotocellLoopSettles) {
  const double d = 0.02, eta = 10, rl = 60, rs = 50, emf = 12, rint = 0.5;
  World w(registry, def());
  const ObjectId b = battery(w, "battery", emf, rint, {-1, 0, 0});
  const ObjectId series = placed(w, "series", {-0.5, 0, 0});
  w.set(series, "conductive", true);
  w.set(series, "resistance", rs);
  const ObjectId l = lamp(w, "lamp", rl, eta, {0, 0, 0});
  const ObjectId pc = photocell(w, "pc", {0, -d, 0});
  wire(w, "w1", b, 1, series, 0);
  wire(w, "w2", series, 1, l, 0);
  wire(w, "w3", l, 1, b, 0);
  wire(w, "w4", series, 1, pc, 0);
  wire(w, "w5", pc, 1, b, 0);
  // The lamp's voltage for a cell resistance r: each parallel branch has two wires.
  auto lamp_voltage = [&](double r) {
    const double a = rl + 2 * kWire, c = r + 2 * kWire, par = a * c / (a + c);
    return emf * par / (rint + kWire + rs + par) * rl / a;
  };
  auto law_of = [&](double r) {
    const double v = lamp_voltage(r);
    const double e = eta * v * v / rl / (4 * kPiValue * d * d);
    return photocell_resistance(e, kDark, kE0, kGamma, kLit);
  };
  double lo = kLit, hi = kDark;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (law_of(mid) > mid ? lo : hi) = mid;
  }
  const double fixed = 0.5 * (lo + hi);
  double last = 0, change = 0;
  for (int i = 0; i < 120; ++i) {
    w.step();
    const double r = electric(w).set_resistance_of(pc);
    change = std::abs(r - last);
    last = r;
  }
  EXPECT_NEAR(last, fixed, 1e-6 * fixed);
  EXPECT_LT(change, 1e-9 * fixed);  // settled, not cycling
  const double v = lamp_voltage(fixed);
  std::printf(
      "loop settles at R = %.2f Ohm (closed form %.2f), lamp %.3f V (%.3f V without the cell)\n",
      last, fixed, num(w, l, "voltage"), lamp_voltage(1e12));
  EXPECT_NEAR(num(w, l, "voltage"), v, 1e-5 * v);
  // The cell matters: without it the lamp would have 6.5 V.
  EXPECT_LT(v, 0.95 * lamp_voltage(1e12));
}

// Commands the resolvers must refuse: a negative or non-finite power, a
// command for an object that is not a lamp, a set_resistance on a battery.
TEST_F(LightTest, BadCommandsDoNothing) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {0, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0.2, 0, 0});
  loop(w, "l", b, l);
  w.step();
  w.step();
  const double p = num(w, l, "radiant_power");
  // Queued after the interaction's own command: the last command wins, so a
  // bad one that were accepted would show.
  light(w).emit(l, -1.0);
  light(w).emit(l, std::nan(""));
  light(w).emit(b, 5.0);
  electric(w).set_resistance(b, 1.0);
  electric(w).set_resistance(l, -3.0);
  w.step();
  EXPECT_NEAR(num(w, l, "radiant_power"), p, 1e-12 * p);
  const double total = 12.0 + 0.5 + 2 * kWire;
  EXPECT_NEAR(num(w, l, "current"), 6.0 / total, 1e-10);
}

// A photocell whose lit resistance exceeds its dark one is a scene error
// that names the object.
TEST_F(LightTest, PhotocellWithLitAboveDarkIsRefusedByName) {
  World w(registry, def());
  const ObjectId b = battery(w, "battery", 6.0, 0.5, {-1, 0, 0});
  const ObjectId l = lamp(w, "lamp", 12.0, 10.0, {0, 0, 0});
  loop(w, "l", b, l);
  const ObjectId pc = photocell(w, "bad_cell", {0, -0.1, 0});
  w.set(pc, "lit_resistance", 2e6);
  try {
    w.step();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad_cell"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("lit_resistance"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace alloy::light
