// Tests for resolvers/electricity/electricity.hpp in a real World: circuits
// built from parts and wire objects, contacts made by connect / disconnect
// commands, against Ohm's law and the analytic RL responses.
#include "resolvers/electricity/electricity.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "runtime/energy_ledger.hpp"

namespace alloy::electricity {
namespace {

class ElectricityTest : public ::testing::Test {
 protected:
  void SetUp() override { register_electricity_resolver(registry); }

  static WorldDef def(int substeps = 1, double dt = 1.0 / 240.0) {
    WorldDef d;
    d.dt = dt;
    d.settings["electricity"].set("substeps", std::int64_t(substeps));
    return d;
  }
  static ObjectId battery(World& w, const std::string& name, double emf, double r) {
    const ObjectId id = w.create(name);
    w.set(id, "emf", emf);
    w.set(id, "internal_resistance", r);
    w.set(id, "conductive", true);
    return id;
  }
  static ObjectId coil(World& w, const std::string& name, double l, double r) {
    const ObjectId id = w.create(name);
    w.set(id, "inductance", l);
    w.set(id, "resistance", r);
    w.set(id, "conductive", true);
    return id;
  }
  static ObjectId resistor(World& w, const std::string& name, double r) {
    const ObjectId id = w.create(name);
    w.set(id, "conductive", true);
    w.set(id, "resistance", r);
    return id;
  }
  static ObjectId bar(World& w, const std::string& name) {
    const ObjectId id = w.create(name);
    w.set(id, "conductive", true);
    return id;
  }
  static ObjectId wire(World& w, const std::string& name, ObjectId from, int from_terminal,
                       ObjectId to, int to_terminal, double r) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(from_terminal));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(to_terminal));
    w.set(id, "resistance", r);
    return id;
  }
  static double num(const World& w, ObjectId id, const char* p) {
    return std::get<double>(w.get(id, p));
  }
  static bool flag(const World& w, ObjectId id, const char* p) {
    return std::get<bool>(w.get(id, p));
  }
  static ElectricityResolver& resolver(World& w) {
    return dynamic_cast<ElectricityResolver&>(*w.stage("electricity"));
  }
  static std::vector<Event> of_type(const std::vector<Event>& events, const std::string& type) {
    std::vector<Event> out;
    std::copy_if(events.begin(), events.end(), std::back_inserter(out),
                 [&](const Event& e) { return e.type == type; });
    return out;
  }

  PluginRegistry registry;
};

TEST_F(ElectricityTest, ResistiveDividerMatchesOhmsLaw) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 9.0, 0.5);
  const ObjectId r1 = resistor(w, "r1", 100.0);
  const ObjectId r2 = resistor(w, "r2", 200.0);
  const ObjectId tap = bar(w, "tap");  // a node part between the two resistors
  wire(w, "w1", b, 1, r1, 0, 0.01);
  wire(w, "w2", r1, 1, tap, 0, 0.02);
  wire(w, "w3", tap, 0, r2, 0, 0.03);
  const ObjectId w4 = wire(w, "w4", r2, 1, b, 0, 0.04);
  w.step();
  const double total = 0.5 + 100 + 200 + 0.01 + 0.02 + 0.03 + 0.04;
  const double i = 9.0 / total;
  // Exact to rounding: the matrix spans 100 S (a 0.01 Ohm wire) to 5 mS, so
  // LU loses about four digits of the sixteen.
  const double tol = 1e-10;
  for (ObjectId id : {b, r1, r2, w4}) EXPECT_NEAR(num(w, id, "current"), i, tol * i);
  EXPECT_NEAR(num(w, b, "voltage"), 9.0 - 0.5 * i, tol * 9);  // terminal voltage, + minus -
  EXPECT_NEAR(num(w, r1, "voltage"), 100 * i, tol * 9);       // drop along the current
  EXPECT_NEAR(num(w, r2, "voltage"), 200 * i, tol * 9);
  // Potentials are measured from the battery's negative terminal.
  EXPECT_NEAR(num(w, tap, "voltage"), (200 + 0.03 + 0.04) * i, tol * 9);
  EXPECT_NEAR(num(w, tap, "current"), i, tol * i);  // what passes through the node
  EXPECT_NEAR(num(w, w4, "voltage"), 0.04 * i, tol * 9);
  for (ObjectId id : {b, r1, r2, tap, w4}) EXPECT_TRUE(flag(w, id, "powered"));
}

TEST_F(ElectricityTest, OpenCircuitCarriesNoCurrentAndStaysFinite) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.1);
  const ObjectId r = resistor(w, "r", 10.0);
  const ObjectId end = bar(w, "end");
  wire(w, "w1", b, 1, r, 0, 0.01);
  wire(w, "w2", r, 1, end, 0, 0.01);  // end does not lead back to the battery
  w.run(3);
  for (ObjectId id : {b, r, end}) {
    EXPECT_EQ(num(w, id, "current"), 0.0);  // exactly: an element off every loop carries nothing
    EXPECT_TRUE(std::isfinite(num(w, id, "voltage")));
    EXPECT_FALSE(flag(w, id, "powered"));
  }
  // Potentials to rounding (1e-12 of the emf).
  EXPECT_NEAR(num(w, b, "voltage"), 6.0, 1e-11);    // open-circuit voltage is the emf
  EXPECT_NEAR(num(w, end, "voltage"), 6.0, 1e-11);  // the dead end floats at the + terminal
  EXPECT_NEAR(num(w, r, "voltage"), 0.0, 1e-11);    // no current, no drop
  EXPECT_FALSE(resolver(w).closed(b));
}

TEST_F(ElectricityTest, ShortCircuitIsLimitedByTheInternalResistance) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 1.5, 0.2);
  const ObjectId s = wire(w, "short", b, 1, b, 0, 0.0);  // 0 Ohm: taken as 1 micro-Ohm
  w.step();
  EXPECT_NEAR(num(w, b, "current"), 1.5 / 0.2, 1.5 / 0.2 * 1e-5);
  EXPECT_NEAR(num(w, s, "current"), 1.5 / 0.2, 1.5 / 0.2 * 1e-5);
  EXPECT_NEAR(num(w, b, "voltage"), 0.0, 1e-5);
  // An ideal battery (0 Ohm) shorted by an ideal wire: huge, but finite.
  w.set(b, "internal_resistance", 0.0);
  w.step();
  EXPECT_TRUE(std::isfinite(num(w, b, "current")));
  EXPECT_NEAR(num(w, b, "current"), 1.5 / (2 * kMinResistance), 1.0);
}

TEST_F(ElectricityTest, AnIsolatedPartIsFiniteAndDead) {
  World w(registry);
  battery(w, "battery", 1.5, 0.1);
  const ObjectId lone = bar(w, "lone");
  const ObjectId c = coil(w, "coil", 0.01, 1.0);
  w.run(2);
  for (ObjectId id : {lone, c}) {
    EXPECT_EQ(num(w, id, "current"), 0.0);
    EXPECT_EQ(num(w, id, "voltage"), 0.0);
    EXPECT_FALSE(flag(w, id, "powered"));
  }
}

/// Battery (E, r) wired to a coil (L, R) with wires of `wire_r` each: an RL loop.
struct RlLoop {
  ObjectId battery, coil;
  double e, r_total, l;
  double analytic(double t) const { return e / r_total * (1 - std::exp(-t * r_total / l)); }
};

RlLoop make_rl(World& w) {
  const double e = 6.0, r = 0.1, rc = 5.9, l = 0.06, wire_r = 0.01;
  RlLoop rl{.e = e, .r_total = r + rc + 2 * wire_r, .l = l};
  rl.battery = w.create("battery");
  w.set(rl.battery, "emf", e);
  w.set(rl.battery, "internal_resistance", r);
  rl.coil = w.create("coil");
  w.set(rl.coil, "inductance", l);
  w.set(rl.coil, "resistance", rc);
  for (auto [name, from, ft, to, tt] :
       {std::tuple{"w1", rl.battery, 1, rl.coil, 0}, std::tuple{"w2", rl.coil, 1, rl.battery, 0}}) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
    w.set(id, "resistance", wire_r);
  }
  return rl;
}

/// Largest |I_sim(t) - I(t)| over five time constants, relative to E/R.
double rl_rise_error(PluginRegistry& registry, double dt, int substeps) {
  World w(registry, [&] {
    WorldDef d;
    d.dt = dt;
    d.settings["electricity"].set("substeps", std::int64_t(substeps));
    return d;
  }());
  const RlLoop rl = make_rl(w);
  const double tau = rl.l / rl.r_total;
  double worst = 0;
  while (w.time() < 5 * tau) {
    w.step();
    const double i = std::get<double>(w.get(rl.coil, "current"));
    worst = std::max(worst, std::abs(i - rl.analytic(w.time())));
  }
  return worst / (rl.e / rl.r_total);
}

TEST_F(ElectricityTest, CoilCurrentRisesWithItsTimeConstant) {
  // tau = L / R = 0.06 / 6.02 = 9.97 ms; dt = 1/240 s = 4.17 ms = 0.42 tau.
  // The trapezoidal rule (after one backward-Euler guard substep) is second
  // order: the largest error over the rise falls 4x per halving of the step
  // (measured; see docs/electricity.md).
  const double e240 = rl_rise_error(registry, 1.0 / 240, 1);
  const double e480 = rl_rise_error(registry, 1.0 / 480, 1);
  const double e960 = rl_rise_error(registry, 1.0 / 960, 1);
  const double e240x4 = rl_rise_error(registry, 1.0 / 240, 4);  // 4 substeps = dt / 4
  RecordProperty("rl_error_dt240", std::to_string(e240));
  RecordProperty("rl_error_dt240x4", std::to_string(e240x4));
  EXPECT_LT(e240, 0.03);
  // h = 0.42 tau is not yet asymptotic (3.1 measured); 1/480 to 1/960 is.
  EXPECT_NEAR(e240 / e480, 3.5, 0.6);
  EXPECT_NEAR(e480 / e960, 4.0, 0.6);
  // The default: 0.16 % of E/R (it was 1.8 % with backward Euler), nearly all
  // from the guard substep at the closing, whose two half-steps are first order.
  EXPECT_LT(e240x4, 2e-3);
  EXPECT_LT(e240x4, e960);  // the same substep, seen at every 4th substep only

  // And the steady state is Ohm's law exactly.
  World w(registry);
  const RlLoop rl = make_rl(w);
  w.run(400);  // 1.7 s = 167 tau
  EXPECT_NEAR(num(w, rl.coil, "current"), rl.e / rl.r_total, 1e-12);
  EXPECT_NEAR(num(w, rl.coil, "voltage"), 5.9 * rl.e / rl.r_total, 1e-11);
  EXPECT_TRUE(flag(w, rl.coil, "powered"));
}

/// Per-substep decay factors of a source-free RL loop: the guard substep
/// (two backward-Euler half-steps) and a trapezoidal substep.
double guard_decay(double h, double r, double l) {
  return 1.0 / ((1 + h / 2 * r / l) * (1 + h / 2 * r / l));
}
double trapezoid_decay(double h, double r, double l) {
  return (1 - h / 2 * r / l) / (1 + h / 2 * r / l);
}

TEST_F(ElectricityTest, CoilDecaysThroughItsFlybackPathWhenTheSwitchOpens) {
  // battery + -> bar s1 ~contact~ bar s2 -> coil 0, coil 1 -> battery -, with a
  // 20 Ohm flyback resistor across the coil. Opening the s1-s2 contact leaves
  // the loop coil + flyback: I(t) = I0 exp(-t (R_coil + R_fly + wires) / L).
  World w(registry);  // default: 4 substeps
  const ObjectId b = battery(w, "battery", 6.0, 0.1);
  const ObjectId s1 = bar(w, "s1"), s2 = bar(w, "s2");
  const ObjectId c = coil(w, "coil", 0.06, 5.9);
  const ObjectId fly = resistor(w, "flyback", 20.0);
  wire(w, "w1", b, 1, s1, 0, 0.0);
  wire(w, "w2", s2, 0, c, 0, 0.0);
  wire(w, "w3", c, 1, b, 0, 0.0);
  wire(w, "f1", c, 0, fly, 0, 0.005);
  wire(w, "f2", fly, 1, c, 1, 0.005);
  w.start();
  resolver(w).connect(s1, s2);
  w.run(480);  // 2 s: steady
  const double i0 = num(w, c, "current");
  ASSERT_GT(i0, 0.5);
  EXPECT_NEAR(num(w, fly, "current"), 5.9 * i0 / 20.01, 1e-9);  // in parallel with the coil's R
  resolver(w).disconnect(s1, s2);
  EXPECT_TRUE(resolver(w).connected(s1, s2));  // queued, not yet performed
  const double h = w.dt() / 4, l = 0.06, r_loop = 5.9 + 20.0 + 0.01;
  double worst = 0;
  for (int k = 1; k <= 20; ++k) {
    w.step();
    const double i = num(w, c, "current");
    // The integrator's own answer, to rounding: a guard substep at the
    // opening, trapezoidal substeps after it.
    EXPECT_NEAR(i,
                i0 * guard_decay(h, r_loop, l) * std::pow(trapezoid_decay(h, r_loop, l), 4 * k - 1),
                1e-12 * i0)
        << "step " << k;
    worst = std::max(worst, std::abs(i - i0 * std::exp(-k * w.dt() * r_loop / l)) / i0);
    EXPECT_NEAR(num(w, fly, "current"), -i, 1e-12);  // the flyback carries the coil current back
    EXPECT_EQ(num(w, b, "current"), 0.0);            // the battery hangs off the loop by one end
  }
  EXPECT_FALSE(resolver(w).connected(s1, s2));
  // tau = 2.3 ms = 0.55 dt: a fast decay for this step (it was 6.4 % of I0
  // with backward Euler); the guard substep's first-order error dominates.
  RecordProperty("flyback_worst_error", std::to_string(worst));
  EXPECT_LT(worst, 0.02);
}

TEST_F(ElectricityTest, CoilCurrentCollapsesAtOnceWhenNoPathRemains) {
  // Hard circuit: a switch opens a coil's only loop while current flows.
  // Without a path, KCL forces the coil current to zero at the first substep
  // after the contact opens; everything stays finite, and the field's energy
  // 1/2 L I0^2 (what a real switch burns in its spark) is reported on the
  // coil's circuit_opened event.
  World w(registry, def(1));
  const ObjectId b = battery(w, "battery", 6.0, 0.1);
  const ObjectId s1 = bar(w, "s1"), s2 = bar(w, "s2");
  const ObjectId c = coil(w, "coil", 0.06, 5.9);
  wire(w, "w1", b, 1, s1, 0, 0.0);
  wire(w, "w2", s2, 0, c, 0, 0.0);
  wire(w, "w3", c, 1, b, 0, 0.0);
  w.start();
  resolver(w).connect(s1, s2);
  w.run(480);
  const double i0 = num(w, c, "current");
  ASSERT_GT(i0, 0.9);
  resolver(w).disconnect(s1, s2);
  w.step();
  EXPECT_EQ(num(w, c, "current"), 0.0);
  EXPECT_TRUE(std::isfinite(num(w, c, "voltage")));
  EXPECT_FALSE(flag(w, c, "powered"));
  const auto opened = of_type(w.events(), "circuit_opened");
  const auto it =
      std::find_if(opened.begin(), opened.end(), [&](const Event& e) { return e.a == c; });
  ASSERT_NE(it, opened.end());
  EXPECT_NEAR(it->value("energy"), 0.5 * 0.06 * i0 * i0, 1e-12);
  w.step();
  EXPECT_EQ(num(w, c, "voltage"), 0.0);
  EXPECT_EQ(num(w, c, "current"), 0.0);
}

TEST_F(ElectricityTest, ContactCommandsTakeEffectAtTheNextAdvanceWithEvents) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.1);
  const ObjectId s1 = bar(w, "s1"), s2 = bar(w, "s2");
  const ObjectId r = resistor(w, "lamp", 12.0);
  wire(w, "w1", b, 1, s1, 0, 0.0);
  wire(w, "w2", s2, 0, r, 0, 0.0);
  wire(w, "w3", r, 1, b, 0, 0.0);
  w.step();
  EXPECT_TRUE(of_type(w.events(), "circuit_closed").empty());
  resolver(w).connect(s2, s1);  // either order
  EXPECT_FALSE(resolver(w).connected(s1, s2));
  EXPECT_EQ(num(w, r, "current"), 0.0);
  w.step();
  EXPECT_TRUE(resolver(w).connected(s1, s2));
  // Contact: 1 mOhm; the three 0 Ohm wires: 1 micro-Ohm each.
  EXPECT_NEAR(num(w, r, "current"), 6.0 / (12.0 + 0.1 + 1e-3 + 3e-6), 1e-10);
  const auto connected = of_type(w.events(), "connected");
  ASSERT_EQ(connected.size(), 1u);
  EXPECT_EQ(connected[0].a, std::min(s1, s2));
  EXPECT_EQ(connected[0].b, std::max(s1, s2));
  EXPECT_EQ(connected[0].source, "electricity");
  const auto closed = of_type(w.events(), "circuit_closed");
  ASSERT_EQ(closed.size(), 2u);  // the battery and the lamp: the two-terminal elements
  EXPECT_EQ(closed[0].a, b);
  EXPECT_EQ(closed[1].a, r);
  EXPECT_NEAR(closed[1].value("current"), num(w, r, "current"), 1e-15);

  resolver(w).connect(s1, s2);  // again: nothing new
  w.step();
  EXPECT_TRUE(w.events().empty());

  resolver(w).disconnect(s1, s2);
  w.step();
  EXPECT_EQ(of_type(w.events(), "disconnected").size(), 1u);
  const auto opened = of_type(w.events(), "circuit_opened");
  ASSERT_EQ(opened.size(), 2u);
  EXPECT_EQ(opened[1].a, r);
  EXPECT_EQ(opened[1].value("current"), 0.0);
  EXPECT_EQ(num(w, r, "current"), 0.0);
  EXPECT_FALSE(flag(w, r, "powered"));
}

TEST_F(ElectricityTest, FactorisesAgainOnlyWhenTheNetworkChanges) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.1);
  const ObjectId s1 = bar(w, "s1"), s2 = bar(w, "s2");
  const ObjectId c = coil(w, "coil", 0.06, 5.9);
  wire(w, "w1", b, 1, s1, 0, 0.0);
  wire(w, "w2", s2, 0, c, 0, 0.0);
  wire(w, "w3", c, 1, b, 0, 0.0);
  const ObjectId lone = bar(w, "lone");  // a component without a source: never factorised
  w.run(10);
  ElectricityResolver& e = resolver(w);
  // One component (battery, coil and both bars, open between s1 and s2).
  EXPECT_EQ(e.factorizations(), 1u);
  w.run(50);
  EXPECT_EQ(e.factorizations(), 1u);  // stepping reuses the factorisation
  w.set(b, "emf", 12.0);              // a source value: right-hand side only
  w.run(5);
  EXPECT_EQ(e.factorizations(), 1u);
  const auto builds = e.network_builds();
  w.create("unrelated");  // a structural change elsewhere: rebuilt, same matrix, not refactorised
  w.run(5);
  EXPECT_GT(e.network_builds(), builds);
  EXPECT_EQ(e.factorizations(), 1u);
  e.connect(s1, s2);  // the topology changes: the loop closes
  w.run(5);
  EXPECT_EQ(e.factorizations(), 2u);
  e.connect(s1, lone);  // a dead end joins the circuit: a new matrix
  w.run(5);
  EXPECT_EQ(e.factorizations(), 3u);
  w.set(c, "resistance", 3.0);  // an impedance: the matrix changes
  w.run(5);
  EXPECT_EQ(e.factorizations(), 4u);
  EXPECT_GT(num(w, c, "current"), 0.5);
}

TEST_F(ElectricityTest, AResistiveCircuitSolvesOnceAndSolvesAgainAfterAnEdit) {
  // No coil, no capacitor: every substep's sources are the batteries' emfs,
  // the same bits each time, so the answer of the first solve is reused.
  // An edit of a value (a new matrix) or of a source must be solved again.
  World w(registry);
  const ObjectId b = battery(w, "battery", 9.0, 0.5);
  const ObjectId r1 = resistor(w, "r1", 100.0), r2 = resistor(w, "r2", 200.0);
  wire(w, "w1", b, 1, r1, 0, 0.0);
  wire(w, "w2", r1, 1, r2, 0, 0.0);
  wire(w, "w3", r2, 1, b, 0, 0.0);
  w.run(5);
  // A wire of 0 Ohm is held at 1 micro-Ohm; beside 100 Ohm that costs the
  // solve about eight digits, hence 1e-9 A.
  const double wires = 3e-6;
  ElectricityResolver& e = resolver(w);
  EXPECT_EQ(e.solves(), 1u);
  EXPECT_EQ(e.solves_skipped(), 5u * 4u);  // the first advance's guard substep is two
  EXPECT_NEAR(num(w, r1, "current"), 9.0 / (300.5 + wires), 1e-9);
  w.set(r2, "resistance", 50.0);  // a new matrix: the held answer is the old matrix's
  w.step();
  EXPECT_EQ(e.solves(), 2u);
  EXPECT_NEAR(num(w, r1, "current"), 9.0 / (150.5 + wires), 1e-9);
  w.set(b, "emf", 3.0);  // a new source, same matrix
  w.step();
  EXPECT_EQ(e.solves(), 3u);
  EXPECT_NEAR(num(w, r1, "current"), 3.0 / (150.5 + wires), 1e-9);
  e.set_resistance(r1, 10.0);  // a command: a new matrix again
  w.step();
  EXPECT_NEAR(num(w, r1, "current"), 3.0 / (60.5 + wires), 1e-9);
  // A coil in the loop: its companion source changes every substep while
  // the current rises, so every substep is solved.
  const std::uint64_t solved = e.solves();
  const ObjectId c = coil(w, "coil", 0.5, 1.0);
  wire(w, "w4", r2, 1, c, 0, 0.0);
  wire(w, "w5", c, 1, b, 0, 0.0);
  w.destroy(w.find("w3"));
  w.run(3);
  EXPECT_EQ(e.solves(), solved + 3 * 4 + 1);  // a guard step first (the network changed)
  EXPECT_GT(num(w, c, "current"), 0.0);
}

TEST_F(ElectricityTest, CoilStateLivesInItsCurrentProperty) {
  // A coil shorted through a resistor, no battery: its current only decays.
  // Set from outside (a scene, or a swapped-in resolver reading what the old
  // one wrote), the property is the state the resolver integrates from.
  World w(registry);
  const ObjectId c = coil(w, "coil", 0.1, 1.0);
  const ObjectId r = resistor(w, "r", 9.0);
  wire(w, "w1", c, 1, r, 0, 0.0);
  wire(w, "w2", r, 1, c, 0, 0.0);
  w.set(c, "current", 2.0);
  w.step();
  // R_loop = 10 Ohm (+ 2 micro-Ohm wires); the first step starts with a guard substep.
  const double h = w.dt() / 4, guard = guard_decay(h, 10.0 + 2e-6, 0.1),
               trap = trapezoid_decay(h, 10.0 + 2e-6, 0.1);
  EXPECT_NEAR(num(w, c, "current"), 2.0 * guard * std::pow(trap, 3), 1e-6);
  // A structural change rebuilds the resolver from properties: nothing is
  // lost, not even the trapezoidal history (same network: no guard).
  const double before = num(w, c, "current");
  w.create("unrelated");
  w.step();
  // (1e-9: the 1 uOhm wires beside 9 Ohm cost the solve about seven digits.)
  EXPECT_NEAR(num(w, c, "current"), before * std::pow(trap, 4), 1e-9);
  // An edit of the state between steps is honoured (a jump: a guard substep).
  w.set(c, "current", -1.0);
  w.step();
  EXPECT_NEAR(num(w, c, "current"), -1.0 * guard * std::pow(trap, 3), 1e-9);
}

TEST_F(ElectricityTest, ARebuildMidRunChangesNothing) {
  auto run = [&](bool disturb) {
    World w(registry);
    const RlLoop rl = make_rl(w);
    std::vector<double> trace;
    for (int k = 0; k < 40; ++k) {
      if (disturb && k % 7 == 3) w.create("noise" + std::to_string(k));
      w.step();
      trace.push_back(std::get<double>(w.get(rl.coil, "current")));
    }
    return trace;
  };
  EXPECT_EQ(run(false), run(true));  // bit for bit
}

TEST_F(ElectricityTest, IsInstantiatedOnlyWithABatteryOrACoil) {
  World w(registry);
  bar(w, "steel");
  bar(w, "brass");
  w.run(2);
  EXPECT_FALSE(w.has_stage("electricity"));
  battery(w, "battery", 1.5, 0.1);
  w.step();
  EXPECT_TRUE(w.has_stage("electricity"));
}

TEST_F(ElectricityTest, BadWiresAreReportedWithTheWiresName) {
  {
    World w(registry);
    const ObjectId b = battery(w, "battery", 1.5, 0.1);
    const ObjectId wood = w.create("wood");  // carries nothing electrical
    wire(w, "lead", b, 1, wood, 0, 0.0);
    try {
      w.step();
      FAIL() << "a wire to a non-conductive part went through";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().object, "lead");
      EXPECT_NE(std::string(e.what()).find("'wood', which is not an electrical part"),
                std::string::npos)
          << e.what();
    }
  }
  {
    World w(registry);
    const ObjectId b = battery(w, "battery", 1.5, 0.1);
    wire(w, "lead", b, 2, b, 0, 0.0);
    EXPECT_THROW(w.step(), InputError);
  }
  {
    // A wire whose part was destroyed is open, not an error (a player may delete parts).
    World w(registry);
    const ObjectId b = battery(w, "battery", 1.5, 0.1);
    const ObjectId s = bar(w, "s");
    const ObjectId lead = wire(w, "lead", b, 1, s, 0, 0.0);
    wire(w, "back", s, 0, b, 0, 0.0);
    w.step();
    EXPECT_GT(num(w, lead, "current"), 1.0);
    w.destroy(s);
    w.step();
    EXPECT_EQ(num(w, lead, "current"), 0.0);
    EXPECT_EQ(num(w, b, "current"), 0.0);
  }
}

TEST_F(ElectricityTest, ContactsJoinTheTerminalTheyAreGiven) {
  // A battery touched at its + end (terminal 1) by a bar that is wired back
  // to its - end: a short through the contact.
  World w(registry);
  const ObjectId b = battery(w, "battery", 1.5, 0.5);
  const ObjectId s = bar(w, "s");
  wire(w, "back", s, 0, b, 0, 0.0);
  w.start();
  resolver(w).connect(s, b, 0, 1);
  w.step();
  EXPECT_NEAR(num(w, b, "current"), 1.5 / (0.5 + 1e-3), 1e-5);
  resolver(w).connect(s, b, 0, 0);  // the same pair, now touching the - end: no loop
  w.step();
  EXPECT_EQ(num(w, b, "current"), 0.0);
}

TEST_F(ElectricityTest, SettingsAreValidated) {
  WorldDef d;
  d.settings["electricity"].set("substep", std::int64_t(2));
  World w(registry, d);
  battery(w, "battery", 1.5, 0.1);
  try {
    w.step();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'substeps'"), std::string::npos) << e.what();
  }
}

// --- capacitors, switches, second order ----------------------------------------

ObjectId make_capacitor(World& w, const std::string& name, double c, double q0) {
  const ObjectId id = w.create(name);
  w.set(id, "capacitance", c);
  w.set(id, "plate_charge", q0);
  w.set(id, "conductive", true);
  return id;
}
void join(World& w, const std::string& name, ObjectId from, int ft, ObjectId to, int tt,
          double r = 0.0) {
  const ObjectId id = w.create(name);
  w.set(id, "wire_from", from);
  w.set(id, "wire_from_terminal", std::int64_t(ft));
  w.set(id, "wire_to", to);
  w.set(id, "wire_to_terminal", std::int64_t(tt));
  w.set(id, "resistance", r);
}
WorldDef at_step(double dt) {
  WorldDef d;
  d.dt = dt;  // the default 4 substeps
  return d;
}

/// RC charge: battery (6 V, 0.5 Ohm) + resistor 99.5 Ohm + capacitor 1 mF, the
/// loop closed from the start; q(t) = C E (1 - exp(-t / RC)), RC = 0.1 s.
/// Largest |q - q(t)| over five time constants, relative to C E.
double rc_charge_error(PluginRegistry& registry, double dt) {
  World w(registry, at_step(dt));
  const double e = 6.0, c = 1e-3, r_total = 0.5 + 99.5 + 3e-6;  // three 0 Ohm wires: 1 uOhm each
  const ObjectId b = w.create("battery");
  w.set(b, "emf", e);
  w.set(b, "internal_resistance", 0.5);
  const ObjectId r = w.create("r");
  w.set(r, "conductive", true);
  w.set(r, "resistance", 99.5);
  const ObjectId cap = make_capacitor(w, "cap", c, 0.0);
  join(w, "w1", b, 1, r, 0);
  join(w, "w2", r, 1, cap, 0);
  join(w, "w3", cap, 1, b, 0);
  double worst = 0;
  while (w.time() < 5 * r_total * c - 1e-9) {
    w.step();
    const double q = std::get<double>(w.get(cap, "plate_charge"));
    worst = std::max(worst, std::abs(q - c * e * (1 - std::exp(-w.time() / (r_total * c)))));
  }
  return worst / (c * e);
}

/// LC (or RLC with the coil's resistance r): coil 0.06 H, capacitor 20 mF
/// charged to 0.12 C (6 V), joined by two 0 Ohm wires (1 uOhm each).
struct LcRun {
  double period = 0;  // from the charge's zero crossings, s
  double worst = 0;   // largest |q - q(t)| over the run, relative to q0
  double energy = 0;  // q^2 / 2C + L I^2 / 2 at the end, relative to its start
};
LcRun lc_run(PluginRegistry& registry, double dt, double r, double t_end) {
  World w(registry, at_step(dt));
  const double l = 0.06, c = 0.02, q0 = 0.12;
  const ObjectId coil = w.create("coil");
  w.set(coil, "inductance", l);
  w.set(coil, "resistance", r);
  const ObjectId cap = make_capacitor(w, "cap", c, q0);
  join(w, "w1", cap, 0, coil, 0);
  join(w, "w2", coil, 1, cap, 1);
  // q(t) = q0 e^{-at} (cos wt + a/w sin wt), a = R / 2L, w^2 = 1/LC - a^2.
  const double a = (r + 2e-6) / (2 * l), om = std::sqrt(1 / (l * c) - a * a);
  LcRun out;
  double q_prev = q0, t_prev = 0, first = -1, last = -1;
  int crossings = 0;
  while (w.time() < t_end - 1e-9) {
    w.step();
    const double q = std::get<double>(w.get(cap, "plate_charge")), t = w.time();
    const double exact = q0 * std::exp(-a * t) * (std::cos(om * t) + a / om * std::sin(om * t));
    out.worst = std::max(out.worst, std::abs(q - exact) / q0);
    if ((q_prev > 0) != (q > 0)) {
      // Linear interpolation of a zero crossing of a sine: O(h^3), below the rule's error.
      const double tc = t_prev + (t - t_prev) * q_prev / (q_prev - q);
      if (first < 0) first = tc;
      last = tc, ++crossings;
    }
    q_prev = q, t_prev = t;
  }
  out.period = crossings > 1 ? 2 * (last - first) / (crossings - 1) : 0;
  const double i = std::get<double>(w.get(coil, "current"));
  out.energy = (q_prev * q_prev / (2 * c) + l * i * i / 2) / (q0 * q0 / (2 * c));
  return out;
}

TEST_F(ElectricityTest, RcChargeIsWithinATenthOfAPercentAndSecondOrder) {
  const double e240 = rc_charge_error(registry, 1.0 / 240);
  const double e480 = rc_charge_error(registry, 1.0 / 480);
  const double e960 = rc_charge_error(registry, 1.0 / 960);
  RecordProperty("rc_error_dt240", std::to_string(e240));
  EXPECT_LT(e240, 1e-3);
  EXPECT_NEAR(e240 / e480, 4.0, 0.6);
  EXPECT_NEAR(e480 / e960, 4.0, 0.6);
}

TEST_F(ElectricityTest, LcPeriodIsWithinATenthOfAPercentAndSecondOrder) {
  const double t_exact = 2 * M_PI * std::sqrt(0.06 * 0.02);  // 0.2177 s
  double err[3];
  for (int k = 0; k < 3; ++k) {
    const LcRun run = lc_run(registry, 1.0 / (240 << k), 0.0, 6 * t_exact);
    err[k] = std::abs(run.period - t_exact) / t_exact;
    // The trapezoidal rule keeps a lossless loop's energy (backward Euler's
    // period is second order too, but it bleeds energy: 43 % here). What
    // leaves is the 2 uOhm floor's, exp(-R t / L) = 1 - 4.4e-5, and the guard
    // substep's at the start: 4.5e-4 at 1/240 s, 4x less per halving.
    EXPECT_NEAR(run.energy, std::exp(-2e-6 * 6 * t_exact / 0.06), 1e-3 / (1 << (2 * k))) << k;
  }
  RecordProperty("lc_period_error_dt240", std::to_string(err[0]));
  EXPECT_LT(err[0], 1e-3);
  EXPECT_NEAR(err[0] / err[1], 4.0, 0.6);
  EXPECT_NEAR(err[1] / err[2], 4.0, 0.6);
}

TEST_F(ElectricityTest, RlcDecayIsWithinATenthOfAPercentAndSecondOrder) {
  // R = 1 Ohm: a = 8.3 /s, w = 27.6 rad/s; two periods (0.45 s), the charge
  // against the closed form.
  double err[3];
  for (int k = 0; k < 3; ++k) err[k] = lc_run(registry, 1.0 / (240 << k), 1.0, 0.45).worst;
  RecordProperty("rlc_error_dt240", std::to_string(err[0]));
  EXPECT_LT(err[0], 1e-3);
  EXPECT_NEAR(err[0] / err[1], 4.0, 0.6);
  EXPECT_NEAR(err[1] / err[2], 4.0, 0.6);
}

TEST_F(ElectricityTest, ACapacitorKeepsItsChargeWhenItsCircuitIsEdited) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.5);
  const ObjectId r = resistor(w, "r", 9.5);
  const ObjectId cap = make_capacitor(w, "cap", 1e-3, 0.0);
  wire(w, "w1", b, 1, r, 0, 0.0);
  const ObjectId lead = wire(w, "w2", r, 1, cap, 0, 0.0);
  wire(w, "w3", cap, 1, b, 0, 0.0);
  w.run(24);  // 0.1 s = 10 RC
  const double q1 = num(w, cap, "plate_charge");
  EXPECT_NEAR(q1, 6e-3, 1e-6);
  EXPECT_NEAR(num(w, cap, "voltage"), 6.0, 1e-3);
  // Cut a wire while running: the capacitor is open, holds its charge exactly
  // and shows its voltage.
  w.destroy(lead);
  w.run(10);
  EXPECT_EQ(num(w, cap, "plate_charge"), q1);
  EXPECT_EQ(num(w, cap, "current"), 0.0);
  EXPECT_NEAR(num(w, cap, "voltage"), q1 / 1e-3, 1e-12);
  // Rewire it across a 10 Ohm resistor alone: it discharges from that charge,
  // q = q1 exp(-t / RC) (RC = 10 ms, here within 0.5 % of q1 after 2 steps).
  const ObjectId load = resistor(w, "load", 10.0);
  wire(w, "l1", cap, 0, load, 0, 0.0);
  wire(w, "l2", load, 1, cap, 1, 0.0);
  w.run(2);
  EXPECT_NEAR(num(w, cap, "plate_charge"), q1 * std::exp(-2 * w.dt() / (10.0 * 1e-3)), 5e-3 * q1);
  EXPECT_GT(num(w, load, "current"), 0.0);  // out of terminal 0, through the load
  // A charge set from outside is the state the resolver integrates from.
  w.set(cap, "plate_charge", -2e-3);
  w.step();
  EXPECT_LT(num(w, cap, "plate_charge"), 0.0);
  EXPECT_GT(num(w, cap, "plate_charge"), -2e-3);
}

TEST_F(ElectricityTest, ASwitchJoinsItsTerminalsOnlyWhileClosed) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.5);
  const ObjectId sw = w.create("switch");
  w.set(sw, "switch_closed", false);
  const ObjectId lamp = resistor(w, "lamp", 11.5);
  wire(w, "w1", b, 1, sw, 0, 0.0);
  wire(w, "w2", sw, 1, lamp, 0, 0.0);
  wire(w, "w3", lamp, 1, b, 0, 0.0);
  w.step();
  EXPECT_EQ(num(w, lamp, "current"), 0.0);
  EXPECT_NEAR(num(w, sw, "voltage"), 6.0, 1e-9);  // the whole emf across the open gap
  w.set(sw, "switch_closed", true);
  w.step();
  // Closed: the contact resistance setting, 1 mOhm.
  EXPECT_NEAR(num(w, lamp, "current"), 6.0 / (12.0 + 1e-3 + 3e-6), 1e-9);
  EXPECT_NEAR(num(w, sw, "current"), num(w, lamp, "current"), 1e-9);
  EXPECT_TRUE(resolver(w).closed(sw));
  w.set(sw, "resistance", 0.5);  // a switch may carry its own on-resistance
  w.step();
  EXPECT_NEAR(num(w, lamp, "current"), 6.0 / (12.5 + 3e-6), 1e-9);
  w.set(sw, "switch_closed", false);
  w.step();
  EXPECT_EQ(num(w, lamp, "current"), 0.0);
  EXPECT_FALSE(resolver(w).closed(sw));
}

// --- hard circuits: defined, finite, no NaN --------------------------------------

TEST_F(ElectricityTest, ASuperconductingLoopKeepsItsCurrentAndEnergy) {
  // A coil of 0 Ohm shorted by a 0 Ohm wire: R_loop = 1 uOhm (the floor,
  // on the wire; the coil's branch has 2L/h), tau = 60000 s. The trapezoidal
  // rule keeps 1/2 L I^2 of a lossless loop exactly; what decays here is the
  // floor's doing, and follows the exponential.
  World w(registry);
  const ObjectId c = coil(w, "coil", 0.06, 0.0);
  wire(w, "w", c, 1, c, 0, 0.0);
  w.set(c, "current", 3.0);
  w.run(2400);
  EXPECT_NEAR(num(w, c, "current"), 3.0 * std::exp(-10.0 * 1e-6 / 0.06), 1e-9);
  EXPECT_TRUE(std::isfinite(num(w, c, "voltage")));
}

TEST_F(ElectricityTest, ABatteryShortedByAWireIsFinite) {
  // Ideal battery, ideal wire: each is raised to 1 uOhm, so 1.5 V drives 0.75 MA.
  World w(registry);
  const ObjectId b = battery(w, "battery", 1.5, 0.0);
  const ObjectId lead = wire(w, "lead", b, 1, b, 0, 0.0);
  w.run(3);
  EXPECT_NEAR(num(w, b, "current"), 1.5 / 2e-6, 1e-3);
  EXPECT_NEAR(num(w, lead, "current"), 1.5 / 2e-6, 1e-3);
  EXPECT_NEAR(num(w, b, "voltage"), 0.75, 1e-9);  // half the emf inside, half in the wire
}

TEST_F(ElectricityTest, InductorsInSeriesShareTheirFlux) {
  // Two coils carrying different currents joined into one loop: KCL forces one
  // current at once. The guard step conserves the loop's flux linkage
  // L1 I1 + L2 I2 (to order h R / L), the answer of ideal physics; the energy
  // 1/2 L1 L2 / (L1 + L2) (I1 - I2)^2 is lost in the joining contact.
  World w(registry);
  const ObjectId c1 = coil(w, "c1", 0.06, 0.1), c2 = coil(w, "c2", 0.02, 0.1);
  const ObjectId s1 = bar(w, "s1"), s2 = bar(w, "s2");
  wire(w, "a", c1, 1, c2, 0, 0.0);
  wire(w, "b", c2, 1, s1, 0, 0.0);
  wire(w, "c", s2, 0, c1, 0, 0.0);
  w.set(c1, "current", 2.0);
  w.set(c2, "current", 0.0);  // the loop is open between s1 and s2: both keep... nothing
  w.step();
  EXPECT_EQ(num(w, c1, "current"), 0.0);  // an open coil carries nothing
  w.set(c1, "current", 2.0);              // preset again, and close the loop in the same step
  resolver(w).connect(s1, s2);
  w.step();
  const double shared = (0.06 * 2.0 + 0.02 * 0.0) / 0.08;  // 1.5 A
  // One step (4.2 ms) of decay with tau = L / R = 0.08 / 0.2 = 0.4 s follows the jump.
  EXPECT_NEAR(num(w, c1, "current"), shared * std::exp(-w.dt() / 0.4), 2e-3 * shared);
  EXPECT_NEAR(num(w, c1, "current"), num(w, c2, "current"), 1e-12);
  EXPECT_TRUE(std::isfinite(num(w, c1, "voltage")) && std::isfinite(num(w, c2, "voltage")));
  // And no ringing after the guard: the decay stays monotone.
  double prev = num(w, c1, "current");
  for (int k = 0; k < 20; ++k) {
    w.step();
    EXPECT_LT(num(w, c1, "current"), prev);
    EXPECT_GT(num(w, c1, "current"), 0.0);
    prev = num(w, c1, "current");
  }
}

TEST_F(ElectricityTest, ACapacitorAcrossABatteryWithNoResistanceChargesAtOnce) {
  // 0 Ohm battery, 0 Ohm wires, ideal capacitor: tau = 4 uOhm x 10 mF = 40 ns.
  // The guard step charges it to C E within the first backward-Euler half-step
  // (a large, finite current, C E / (h/2) = 115 A); the trapezoidal steps
  // after it keep a residue of the second half-step's current, about 1e-4 of
  // that, which alternates from substep to substep (an even count of
  // substeps: the published value keeps its sign) and dies away slowly.
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.0);
  const ObjectId cap = make_capacitor(w, "cap", 0.01, 0.0);
  const ObjectId sw = w.create("switch");
  w.set(sw, "switch_closed", false);
  wire(w, "w1", b, 1, sw, 0, 0.0);
  wire(w, "w2", sw, 1, cap, 0, 0.0);
  wire(w, "w3", cap, 1, b, 0, 0.0);
  w.step();
  w.set(sw, "switch_closed", true);
  w.set(sw, "resistance", 0.0);
  w.step();
  EXPECT_NEAR(num(w, cap, "plate_charge"), 0.06, 1e-9);
  const double jump = 0.06 / (w.dt() / 8);
  for (int k = 0; k < 50; ++k) {
    w.step();
    EXPECT_NEAR(num(w, cap, "plate_charge"), 0.06, 1e-9) << k;
    EXPECT_LT(std::abs(num(w, cap, "current")), 2e-4 * jump) << k;
    EXPECT_NEAR(num(w, cap, "voltage"), 6.0, 1e-6);
  }
}

TEST_F(ElectricityTest, AZeroCapacitanceIsAnOpenGap) {
  World w(registry);
  const ObjectId b = battery(w, "battery", 6.0, 0.5);
  const ObjectId cap = make_capacitor(w, "cap", 0.0, 0.0);
  wire(w, "w1", b, 1, cap, 0, 0.0);
  wire(w, "w2", cap, 1, b, 0, 0.0);
  w.run(3);
  EXPECT_EQ(num(w, b, "current"), 0.0);
  EXPECT_EQ(num(w, cap, "current"), 0.0);
  EXPECT_EQ(num(w, cap, "plate_charge"), 0.0);
  EXPECT_NEAR(num(w, cap, "voltage"), 6.0, 1e-9);
}

// adv13 F3 / F4 (session 17): huge but finite circuit values passed the finite
// check, then overflowed in the solve ("component 0 gave a non-finite
// solution", no object named) or in the energy books (booked as 0 J).
TEST_F(ElectricityTest, CircuitValuesBeyondTheirRangesAreRefusedNamingTheObject) {
  World w(registry);
  const ObjectId b = battery(w, "bat", 6.0, 1.0);
  const ObjectId c = coil(w, "x", 0.01, 1.0);
  const ObjectId cap = make_capacitor(w, "cap", 0.01, 0.0);
  struct Case {
    ObjectId id;
    const char* property;
    double value;
  };
  const Case refused[] = {{b, "emf", 1e308},
                          {b, "emf", 1e200},
                          {b, "emf", -1e303},
                          {b, "internal_resistance", 1e300},
                          {c, "inductance", 1e300},
                          {c, "resistance", 1e13},
                          {cap, "capacitance", 1e300},
                          {cap, "plate_charge", 1e308},
                          {cap, "plate_charge", -1e160}};
  for (const Case& k : refused) {
    try {
      w.set(k.id, k.property, k.value);
      ADD_FAILURE() << k.property << " = " << k.value << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + k.property + "' must lie between"),
                std::string::npos)
          << e.what();
    }
  }
  // The edges of the ranges are values a scene may use.
  w.set(b, "emf", -kMaxEmf);
  w.set(b, "emf", kMaxEmf);
  w.set(c, "inductance", kMaxInductance);
  w.set(c, "resistance", kMaxResistance);
  w.set(cap, "capacitance", kMaxCapacitance);
  w.set(cap, "plate_charge", -kMaxCharge);
}

TEST_F(ElectricityTest, TheLargestValuesInRangeGiveFiniteCurrentsAndBooks) {
  // A megavolt across micro-ohm wires and an ideal coil (adv13's hugeemf at
  // the edge of the range): 1e12 A, finite, and the books finite too.
  World w(registry);
  const ObjectId b = battery(w, "bat", kMaxEmf, 0.0);
  const ObjectId x = coil(w, "x", 0.0, 0.0);
  wire(w, "w1", b, 1, x, 0, 0.0);
  wire(w, "w2", x, 1, b, 0, 0.0);
  EnergyLedger books;
  books.record(w);
  for (int k = 0; k < 3; ++k) {
    w.step();
    books.record(w);
  }
  EXPECT_TRUE(std::isfinite(num(w, b, "current")));
  EXPECT_GT(std::abs(num(w, b, "current")), 1e10);
  EXPECT_GT(books.total().sources, 0.0);
  EXPECT_TRUE(std::isfinite(books.total().sources));
}

TEST_F(ElectricityTest, ALedgerOpenedMidRunBooksFromItsOpeningAsOneKeptAllAlong) {
  // The books are kept only once a ledger asks (they cost a pass over every
  // element a substep). A ledger opened after 5 steps sees no flow from
  // before it opened, and from then on the same joules, to the bit, as one
  // kept from the first step: with an induced EMF that ramps every step,
  // whose mean over a substep starts from the last solve's EMF.
  auto run = [&](int open_at) {
    World w(registry);
    const ObjectId b = battery(w, "bat", 6.0, 0.5);
    const ObjectId x = coil(w, "x", 0.05, 1.0);
    wire(w, "w1", b, 1, x, 0, 0.01);
    wire(w, "w2", x, 1, b, 0, 0.01);
    EnergyLedger books;
    std::vector<EnergyBalance> flows;
    for (int k = 0; k < 12; ++k) {
      if (k == open_at) {
        books.record(w);
        flows.push_back(books.last());
      }
      if (k > 0) resolver(w).set_induced_emf(x, 0.25 * k);
      w.step();
      if (k >= open_at) books.record(w), flows.push_back(books.last());
    }
    return flows;
  };
  const std::vector<EnergyBalance> all_along = run(0), late = run(5);
  ASSERT_EQ(late.size(), 8u);
  EXPECT_EQ(late[0].sources, 0.0);  // the opening record: no battery work from before
  EXPECT_EQ(late[0].transfers, 0.0);
  EXPECT_GT(all_along[5].sources, 0.0);
  for (std::size_t r = 1; r < late.size(); ++r) {  // the records after steps 5 to 11
    const EnergyBalance& a = all_along[5 + r];
    EXPECT_EQ(late[r].sources, a.sources) << "record " << r;
    EXPECT_EQ(late[r].sinks, a.sinks) << "record " << r;
    EXPECT_EQ(late[r].transfers, a.transfers) << "record " << r;
    EXPECT_EQ(late[r].stored, a.stored) << "record " << r;
  }
}

TEST_F(ElectricityTest, ASolveThatOverflowsNamesTheCircuitsParts) {
  // An induced EMF is not a scene value (magnetism computes it): one of 1e308 V
  // in a 1-Ohm loop overflows the solve, and the error names the loop's parts.
  World w(registry);
  const ObjectId b = battery(w, "bat", 1.0, 0.0);
  const ObjectId x = coil(w, "x", 0.0, 1e-3);
  wire(w, "w1", b, 1, x, 0, 0.0);
  wire(w, "w2", x, 1, b, 0, 0.0);
  w.step();
  resolver(w).set_induced_emf(x, 1e308);
  try {
    w.step();
    FAIL() << "an overflowing solve went through";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.where().object, "x");
    EXPECT_NE(what.find("the circuit of 'bat', 'x'"), std::string::npos) << what;
    EXPECT_NE(what.find("no finite solution"), std::string::npos) << what;
  }
}

TEST_F(ElectricityTest, TheBooksRefuseAPowerThatOverflows) {
  // 1e200 V induced in a coil of 1 kH: a current of about 1e194 A is finite,
  // its power is not. The ledger would book it as 0 J; the resolver says so.
  World w(registry);
  const ObjectId b = battery(w, "bat", 1.0, 1.0);
  const ObjectId x = coil(w, "x", kMaxInductance, 1.0);
  wire(w, "w1", b, 1, x, 0, 0.0);
  wire(w, "w2", x, 1, b, 0, 0.0);
  EnergyLedger books;
  books.record(w);
  w.step();
  books.record(w);
  resolver(w).set_induced_emf(x, 1e200);
  w.step();
  EXPECT_TRUE(std::isfinite(num(w, x, "current")));
  try {
    books.record(w);
    FAIL() << "an overflowed power was booked";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("the energy books overflowed"), std::string::npos)
        << e.what();
  }
}

/// Writes +inf into `overheat` of every object carrying it at step 3: the
/// world refuses the value and freezes the object (as magnetism's inf pole
/// strength froze adv13's coil of 1e300 turns).
class Overheat : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& a, double) override {
    auto w = a.writer<double>("overheat");
    if (a.step() == 3)
      for (std::uint32_t s : w.members()) w.set(s, std::numeric_limits<double>::infinity());
  }
};

TEST_F(ElectricityTest, AWireToAFrozenPartHasAnOpenEnd) {
  // adv13 F4: the frozen coil left electricity's scope, and its wires then
  // failed the run as "not an electrical part", blaming the wire.
  registry.add({.info = {.name = "overheat",
                         .kind = StageKind::Resolver,
                         .writes = {"overheat"},
                         .needs = {"overheat"}},
                .properties = {{.name = "overheat", .kind = PropertyKind::Number}},
                .create = [](PluginContext&) { return std::make_unique<Overheat>(); }});
  World w(registry);
  const ObjectId b = battery(w, "bat", 1.0, 1.0);
  const ObjectId x = coil(w, "x", 0.01, 1.0);
  w.set(x, "overheat", 0.0);
  wire(w, "w1", b, 1, x, 0, 0.0);
  wire(w, "w2", x, 1, b, 0, 0.0);
  w.run(2);
  EXPECT_GT(num(w, b, "current"), 0.0);
  EXPECT_NO_THROW(w.run(4));
  EXPECT_TRUE(w.frozen(x));
  EXPECT_EQ(num(w, b, "current"), 0.0);  // the loop is open at the frozen coil
}

}  // namespace
}  // namespace alloy::electricity
