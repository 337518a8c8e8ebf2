// The energy books of whole runs (docs/energy.md): each stage reports what it
// moved, EnergyLedger::record asks them after every step, and the books close.
// Circuits against the closed forms of their heat; a pendulum and a bouncing
// ball (gravity, the rigid body, its contacts and restitution); the motor and
// the doorbell through their scenes. And the books broken on purpose: with
// one account left out they do not close.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "lua/scene_loader.hpp"
#include "resolvers/electricity/electricity.hpp"
#include "resolvers/electricity/electricity_from_magnetism.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/engine.hpp"
#include "runtime/energy_ledger.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy {
namespace {

/// Records the world's books after start and after each of `steps` steps.
/// `drop`: an account ("stage/name") to leave out of the books, to break them.
void run_books(World& w, EnergyLedger& ledger, std::uint64_t steps, const std::string& drop = "") {
  auto record = [&] {
    if (drop.empty()) return ledger.record(w);
    // The same as record(), less one account.
    for (const std::string& name : w.active_stages()) {
      EnergyReport r, kept;
      w.stage(name)->report_energy(w.stage_view(name), r);
      for (const auto& e : r.entries()) {
        if (name + "/" + e.account == drop) continue;
        switch (e.kind) {
          case EnergyKind::Source:
            kept.source(e.account, e.joules);
            break;
          case EnergyKind::Sink:
            kept.sink(e.account, e.joules);
            break;
          case EnergyKind::Store:
            kept.store(e.account, e.joules);
            break;
          case EnergyKind::Transfer:
            kept.transfer(e.account, e.joules);
            break;
        }
      }
      ledger.add(name, kept);
    }
    ledger.close_record();
  };
  w.start();
  record();
  for (std::uint64_t i = 0; i < steps; ++i) {
    w.step();
    record();
  }
}

/// A scene file (path from the source tree, mods/ on the module path),
/// loaded with the native plugins, and its books over `seconds` at `dt`
/// (0: the scene's step), recorded after every step.
struct BookedScene {
  PluginRegistry registry;
  lua::LoadedScene loaded;
  EnergyLedger books;
  World& world() { return *loaded.world; }
  explicit BookedScene(const char* scene) {
    register_native_plugins(registry);
    lua::LoadOptions load;
    load.mod_paths.push_back(test::source("mods"));
    loaded = lua::load_scene(test::source(scene), registry, load);
  }
  void run(double seconds, double dt = 0) {
    if (dt > 0) world().set_dt(dt);
    run_steps(std::uint64_t(std::llround(seconds / world().dt())));
  }
  void run_steps(std::uint64_t steps) { run_books(world(), books, steps); }
};

double total(const EnergyLedger& l, const char* stage, const char* name) {
  const EnergyAccount* a = l.find(stage, name);
  return a ? a->total : std::nan("");
}

// --- circuits ----------------------------------------------------------------

void join(World& w, const std::string& name, ObjectId from, int ft, ObjectId to, int tt) {
  const ObjectId id = w.create(name);
  w.set(id, "wire_from", from);
  w.set(id, "wire_from_terminal", std::int64_t(ft));
  w.set(id, "wire_to", to);
  w.set(id, "wire_to_terminal", std::int64_t(tt));
  w.set(id, "resistance", 0.0);  // 1 uOhm (kMinResistance)
}

struct Circuit {
  PluginRegistry registry;
  std::unique_ptr<World> world;
  double e = 6, r_total = 0, tau = 0;
};

/// RC: battery 6 V with 0.5 Ohm, a 99.5 Ohm resistor, a 1 mF capacitor, closed
/// from the start; RC = 0.1 s (three 0 Ohm wires add 3 uOhm).
void build_rc(Circuit& c, double dt) {
  electricity::register_electricity_resolver(c.registry);
  WorldDef d;
  d.dt = dt;
  c.world = std::make_unique<World>(c.registry, d);
  World& w = *c.world;
  const ObjectId b = w.create("battery");
  w.set(b, "emf", c.e);
  w.set(b, "internal_resistance", 0.5);
  const ObjectId r = w.create("r");
  w.set(r, "conductive", true);
  w.set(r, "resistance", 99.5);
  const ObjectId cap = w.create("cap");
  w.set(cap, "capacitance", 1e-3);
  w.set(cap, "plate_charge", 0.0);
  w.set(cap, "conductive", true);
  join(w, "w1", b, 1, r, 0);
  join(w, "w2", r, 1, cap, 0);
  join(w, "w3", cap, 1, b, 0);
  c.r_total = 100 + 3e-6, c.tau = c.r_total * 1e-3;
}

TEST(EnergyBooks, RcChargeHeatIsHalfTheBatteryWork) {
  // Over t: q = CE (1 - e^-t/RC); the battery's work is E q, the capacitor
  // holds q^2 / 2C, and the rest, E q - q^2/2C, is heat (-> 1/2 C E^2 each).
  Circuit c;
  build_rc(c, 1.0 / 240);
  EnergyLedger books;
  run_books(*c.world, books, 120);  // 0.5 s = 5 RC
  const double t = c.world->time(), cap = 1e-3;
  const double q = cap * c.e * (1 - std::exp(-t / c.tau));
  const double work = c.e * q, stored = q * q / (2 * cap), heat = work - stored;
  const double w = total(books, "electricity", "battery work");
  const double h = total(books, "electricity", "heat (I^2 R)");
  const double s = total(books, "electricity", "capacitors (q^2 / 2C)");
  std::printf(
      "RC, 0.5 s at 1/240 s: battery %.6f J (exact %.6f), heat %.6f J (exact %.6f), "
      "stored %.6f J (exact %.6f), residue %.2e of %.6f J moved\n",
      w, work, h, heat, s, stored, books.total().residue(), books.total().moved);
  EXPECT_NEAR(w / work, 1, 1e-4);
  EXPECT_NEAR(h / heat, 1, 1e-3);
  EXPECT_NEAR(s / stored, 1, 1e-4);
  // The books close to rounding (Tellegen's theorem, step by step; the
  // micro-ohm wires cost the solve some digits: 2e-9 measured).
  EXPECT_LT(books.total().fraction(), 1e-8);
  // The guard substep at the closing is the only switching loss: tiny.
  EXPECT_LT(total(books, "electricity", "switching (guard steps, opened coils)"), 1e-3 * heat);
}

TEST(EnergyBooks, RlRiseHeatMatchesTheClosedForm) {
  // Battery 6 V with 0.5 Ohm, coil 0.06 H with 5.5 Ohm: I = E/R (1 - e^-t/tau),
  // tau = L/R = 10 ms. The heat is R int I^2 dt =
  // E^2/R (t - 2 tau (1 - e^-t/tau) + tau/2 (1 - e^-2t/tau)); the coil holds 1/2 L I^2.
  PluginRegistry registry;
  electricity::register_electricity_resolver(registry);
  WorldDef d;
  d.dt = 1.0 / 240;
  World w(registry, d);
  const ObjectId b = w.create("battery");
  w.set(b, "emf", 6.0);
  w.set(b, "internal_resistance", 0.5);
  const ObjectId coil = w.create("coil");
  w.set(coil, "inductance", 0.06);
  w.set(coil, "resistance", 5.5);
  join(w, "w1", b, 1, coil, 0);
  join(w, "w2", coil, 1, b, 0);
  EnergyLedger books;
  run_books(w, books, 60);  // 0.25 s = 25 tau
  const double r = 6 + 2e-6, tau = 0.06 / r, t = w.time(), e = 6.0;
  const double heat =
      e * e / r * (t - 2 * tau * (1 - std::exp(-t / tau)) + tau / 2 * (1 - std::exp(-2 * t / tau)));
  const double i = e / r * (1 - std::exp(-t / tau)), field = 0.5 * 0.06 * i * i;
  const double h = total(books, "electricity", "heat (I^2 R)");
  const double f = total(books, "electricity", "coil fields (1/2 L I^2)");
  std::printf(
      "RL, 0.25 s at 1/240 s: heat %.6f J (exact %.6f), field %.6f J (exact %.6f), "
      "switching %.2e J, residue %.2e of %.6f J moved\n",
      h, heat, f, field, total(books, "electricity", "switching (guard steps, opened coils)"),
      books.total().residue(), books.total().moved);
  EXPECT_NEAR(h / heat, 1, 1e-3);
  EXPECT_NEAR(f / field, 1, 1e-6);
  EXPECT_LT(books.total().fraction(), 1e-9);
}

TEST(EnergyBooks, ATransformerSwitchedOnAtTheStartClosesToRounding) {
  // adv13's F8: a static transformer whose battery is on from t = 0 left
  // 0.44 % of the energy moved at 1/240 s (0.13 % at 1/480: second order),
  // the same switched on later 1e-13 %. The network is built again at the
  // second step with nothing changed (the history kept), and the rebuild
  // zeroed the last solution, from which the books take a trapezoidal
  // substep's start values: half of that substep's battery work and wire
  // heat went unbooked while current flowed. Measured now: 1.6e-13 %.
  for (double dt : {1.0 / 240, 1.0 / 480}) {
    BookedScene scene("tests/energy/scenes/transformer.lua");
    scene.run(0.05, dt);
    const EnergyLedger& books = scene.books;
    const EnergyBalance b = books.total();
    std::printf(
        "transformer, 0.05 s at 1/%.0f s: battery %.6f J, shared field %+.2e J, residue "
        "%.2e of %.6f J moved\n",
        1 / dt, total(books, "electricity", "battery work"),
        total(books, "electricity", "coils' shared field (M I_a I_b)"), b.fraction(), b.moved);
    ASSERT_GT(b.moved, 0.1);
    // Coupled: the secondary carries current, the shared field is booked.
    EXPECT_LT(total(books, "electricity", "coils' shared field (M I_a I_b)"), -1e-5);
    EXPECT_LT(b.fraction(), 1e-9) << "dt 1/" << 1 / dt;
  }
}

TEST(EnergyBooks, PresetChargeAndCurrentOpenTheStoresAtTheirLevel) {
  // A scene that starts with a coil carrying 2 A (0.06 H, 1/2 L I^2 = 0.12 J)
  // shorted by 1 Ohm, and a capacitor holding 10 mC (10 mF: q^2/2C = 5 mJ)
  // across 2 Ohm: both discharge into heat, and the books must open with
  // that energy stored. Before, the stores opened at 0 (nothing is built
  // before the first advance), so the whole 0.125 J looked created: a
  // residue of 100 % of the energy moved.
  PluginRegistry registry;
  electricity::register_electricity_resolver(registry);
  WorldDef d;
  d.dt = 1.0 / 240;
  World w(registry, d);
  const ObjectId coil = w.create("coil");
  w.set(coil, "inductance", 0.06);
  w.set(coil, "resistance", 0.0);
  w.set(coil, "current", 2.0);
  const ObjectId r1 = w.create("r1");
  w.set(r1, "conductive", true);
  w.set(r1, "resistance", 1.0);
  join(w, "w1", coil, 1, r1, 0);
  join(w, "w2", r1, 1, coil, 0);
  const ObjectId cap = w.create("cap");
  w.set(cap, "capacitance", 1e-2);
  w.set(cap, "plate_charge", 1e-2);
  const ObjectId r2 = w.create("r2");
  w.set(r2, "conductive", true);
  w.set(r2, "resistance", 2.0);
  join(w, "w3", cap, 1, r2, 0);
  join(w, "w4", r2, 1, cap, 0);
  EnergyLedger books;
  run_books(w, books, 240);  // 1 s: 17 L/R, 50 RC
  const double heat = total(books, "electricity", "heat (I^2 R)");
  const double field = total(books, "electricity", "coil fields (1/2 L I^2)");
  const double charge = total(books, "electricity", "capacitors (q^2 / 2C)");
  std::printf("preset stores, 1 s: heat %.6f J, field %.6f J, capacitor %.6f J, residue %.2e\n",
              heat, field, charge, books.total().residue());
  EXPECT_NEAR(field, -0.12, 1e-6);
  EXPECT_NEAR(charge, -0.005, 1e-6);
  EXPECT_NEAR(heat, 0.125, 1e-4);
  EXPECT_LT(books.total().fraction(), 1e-9);
}

TEST(EnergyBooks, LeftOutAccountsLeaveAResidue) {
  // Broken on purpose: the RC's books without the heat, without the
  // capacitor, without the battery. Each leaves a residue far above the
  // 0.1 % the other tests allow, so they would catch a resolver that forgot one.
  for (const char* drop : {"electricity/heat (I^2 R)", "electricity/capacitors (q^2 / 2C)",
                           "electricity/battery work"}) {
    Circuit c;
    build_rc(c, 1.0 / 240);
    EnergyLedger books;
    run_books(*c.world, books, 120, drop);
    EXPECT_GT(books.total().fraction(), 0.3) << drop;
  }
}

// --- mechanics ---------------------------------------------------------------

using scenes::Sim;

TEST(EnergyBooks, PendulumTradesPotentialForKineticEnergy) {
  // The 1 m bar pendulum at 0.5 rad, 10 s: gravity's potential energy and the
  // bar's kinetic energy trade back and forth; the hinge does (nearly) no work.
  Sim s([] {
    WorldDef d;
    d.dt = 1.0 / 240;
    return d;
  }());
  scenes::build_bar_pendulum(*s, 1.0, 0.5);
  EnergyLedger books;
  run_books(*s, books, 2400);
  const EnergyBalance& b = books.total();
  const double joints =
      total(books, "rigid_body", "contacts and joints (residue of the kinetic energy)");
  const double integration = total(books, "rigid_body", "integration and position corrections");
  const double mismatch =
      total(books, "rigid_body", "gravity") + total(books, "gravity.uniform", "gravity");
  std::printf(
      "pendulum, 10 s at 1/240 s: moved %.4f J, kinetic %+.2e J, potential %+.2e J, hinge "
      "%.2e J, integration %.2e J, gravity's two sides apart %.2e J, residue %.2e\n",
      b.moved, total(books, "rigid_body", "kinetic energy"),
      total(books, "gravity.uniform", "potential energy (uniform field)"), joints, integration,
      mismatch, b.residue());
  EXPECT_LT(b.fraction(), 1e-3);
  // The work gravity's forces did along the steps is the potential it lost.
  EXPECT_LT(std::abs(mismatch), 1e-9 * b.moved);
  // Energy swings through the books (m g d (1 - cos 0.5) = 0.60 J, four
  // times a period of 1.67 s): most is the swing, not the hinge.
  EXPECT_GT(b.moved, 10.0);
  EXPECT_LT(std::abs(joints) + std::abs(integration), 0.01 * b.moved);
}

/// The ball of the bounce tests (0.5 kg, r = 0.1 m, dropped 1 m, e = 0.7)
/// run for 10 s with the books kept after every step, on the rigid body
/// `stage` (the engine `def` chooses).
struct BounceBooks {
  EnergyBalance balance;
  double first = -1;  ///< restitution when the ball first moves up, J
  double restitution = 0, contacts = 0, integration = 0, potential = 0;
};
BounceBooks bounce_books(WorldDef def, const char* stage) {
  def.dt = 1.0 / 240;
  Sim s(std::move(def));
  const scenes::Bounce bounce = scenes::build_bounce(*s, 1.0, 0.7);
  EnergyLedger books;
  s->start();
  books.record(*s);
  BounceBooks out;
  for (int i = 0; i < 2400; ++i) {
    s->step();
    books.record(*s);
    if (out.first < 0 && s.velocity(bounce.ball).y > 0)
      out.first = total(books, stage, "restitution (collision impulses)");
  }
  out.balance = books.total();
  out.restitution = total(books, stage, "restitution (collision impulses)");
  out.contacts = total(books, stage, "contacts and joints (residue of the kinetic energy)");
  out.integration = total(books, stage, "integration and position corrections");
  out.potential = total(books, "gravity.uniform", "potential energy (uniform field)");
  const double arrive = 0.5 * 9.81 * 1.0;
  std::printf(
      "%s bounce, 10 s at 1/240 s: first bounce %.4f J (exact %.4f), all bounces %.4f J, "
      "contacts %.4f J, integration %.4f J, potential %+.4f J, residue %.2e of %.4f J moved\n",
      stage, out.first, (1 - 0.49) * arrive, out.restitution, out.contacts, out.integration,
      out.potential, out.balance.residue(), out.balance.moved);
  return out;
}

TEST(EnergyBooks, BouncingBallLosesOneMinusESquaredAtEachBounce) {
  // A 0.5 kg ball (r = 0.1 m) dropped 1 m onto a floor, restitution 0.7.
  // The first bounce takes (1 - e^2) of the 4.905 J it arrives with.
  const BounceBooks b = bounce_books({}, "rigid_body");
  const double arrive = 0.5 * 9.81 * 1.0;
  EXPECT_NEAR(b.first / ((1 - 0.49) * arrive), 1, 0.02);
  EXPECT_LT(b.balance.fraction(), 1e-3);
  // At rest after 10 s: the drop's 4.905 J went into the bounces and the floor.
  EXPECT_NEAR(b.restitution + b.contacts + b.integration, arrive, 0.02 * arrive);
}

// --- the rigid body on Box2D -------------------------------------------------
//
// rigid_body.box2d keeps the same books as ODE's engine, under the same
// names (resolvers/rigid_body_box2d/box2d_energy.cpp); before session 19 it
// kept none (adv15 F12: a run on Box2D booked only the other stages' sides).

WorldDef box2d_world(double dt, int substeps = 1) {
  WorldDef d;
  d.dt = dt;
  d.use = {{"rigid_body", "rigid_body.box2d"}};
  d.settings["rigid_body.box2d"].set("substeps", std::int64_t(substeps));
  return d;
}

constexpr const char* kBox2D = "rigid_body.box2d";
constexpr const char* kContacts = "contacts and joints (residue of the kinetic energy)";
constexpr const char* kIntegration = "integration and position corrections";

TEST(EnergyBooks, Box2DPendulumsBooksCloseAndGravitysSidesAgree) {
  // The ODE test's pendulum (1 m bar, 0.5 rad, 10 s) on Box2D, with one
  // substep and with three (the books are per Box2D step). Box2D's position
  // solver pushes the bar back onto its hinge with no velocity every step;
  // the books take each load's work along its point's actual displacement,
  // so gravity's two sides agree to rounding all the same, and the rigid
  // body's own books close by construction: the residue is rounding.
  for (int substeps : {1, 3}) {
    Sim s(box2d_world(1.0 / 240, substeps));
    scenes::build_bar_pendulum(*s, 1.0, 0.5);
    EnergyLedger books;
    run_books(*s, books, 2400);
    const EnergyBalance& b = books.total();
    const double joints = total(books, kBox2D, kContacts);
    const double integration = total(books, kBox2D, kIntegration);
    const double mismatch =
        total(books, kBox2D, "gravity") + total(books, "gravity.uniform", "gravity");
    std::printf(
        "box2d pendulum, %d substep(s), 10 s at 1/240 s: moved %.4f J, kinetic %+.2e J, "
        "potential %+.2e J, hinge %.2e J, integration %.2e J, gravity's two sides apart %.2e J, "
        "residue %.2e\n",
        substeps, b.moved, total(books, kBox2D, "kinetic energy"),
        total(books, "gravity.uniform", "potential energy (uniform field)"), joints, integration,
        mismatch, b.residue());
    // The swing, m g d (1 - cos 0.5) = 0.60 J four times a period: as on
    // ODE (14.53 J); half of it when the rigid body's side was missing.
    EXPECT_GT(b.moved, 13.0);
    // The one joule-scale rounding: the bar's start pose in single precision
    // (Box2D's), 6e-9 m lower than the authored one that gravity.uniform's
    // first potential is of, m g 6e-9 = 5.8e-8 J, once.
    EXPECT_LT(b.fraction(), 1e-8) << substeps;
    EXPECT_LT(std::abs(b.unexplained()), 1e-8 * b.moved) << substeps;
    EXPECT_LT(std::abs(mismatch), 1e-8 * b.moved) << substeps;
    // The position solver pulls the bar back onto its hinge every step with
    // no velocity: gravity's work along that pull is the integration line's
    // (-0.17 J at one substep), and the hinge's residue nearly returns it;
    // what the two leave is what the pendulum lost, 0.17 % of the swing.
    EXPECT_LT(std::abs(joints + integration), 0.005 * b.moved) << substeps;
  }
}

TEST(EnergyBooks, Box2DBooksARatedLoadAtEachSubstepsValue) {
  // A load with rates (add_load, as magnetism's with rates) on a free ball,
  // four substeps a step: substep k applies value + rate k h. The books take
  // it at each substep's value, so its transfer is the kinetic energy it gave
  // along x and in spin (gravity acts along y): 1/2 m vx^2 + 1/2 I w^2 from
  // the written motion, to the integrator's share (1.0e-3 measured). Taken at the
  // step's value, the books would miss the rate's 8 % of the force.
  Sim s(box2d_world(1.0 / 240, 4));
  const double m = 0.5, r = 0.1;
  const ObjectId ball = scenes::add_sphere(*s, {0, 1, 0}, r, m, "ball");
  EnergyLedger books;
  s->start();
  books.record(*s);
  auto* engine = dynamic_cast<rigid::RigidBodyEngine*>(s->stage(kBox2D));
  ASSERT_NE(engine, nullptr);
  for (int i = 0; i < 240; ++i) {
    engine->add_load(ball, {1, 0, 0}, {0, 0, 0.01}, {50, 0, 0}, {0, 0, 0.5});
    s->step();
    books.record(*s);
  }
  const double pushed = total(books, kBox2D, "loads from outside the stages");
  const double vx = s.velocity(ball).x, w = std::get<Vec3>(s->get(ball, "angular_velocity")).z;
  const double gained = 0.5 * m * vx * vx + 0.5 * (0.4 * m * r * r) * w * w;
  std::printf("box2d rated load, 1 s at 1/240 s, 4 substeps: booked %.6f J, given %.6f J\n", pushed,
              gained);
  EXPECT_GT(gained, 1.0);
  EXPECT_NEAR(pushed / gained, 1, 2e-3);
  EXPECT_LT(std::abs(books.total().unexplained()), 1e-9 * books.total().moved);
}

TEST(EnergyBooks, Box2DBouncingBallLosesOneMinusESquaredAtTheFirstBounce) {
  // The same ball on Box2D, which bounces it inside its velocity solve (a
  // bias of e times the approach speed after the step's kick); the books
  // take the bouncing point's impulses' work as restitution. The ball meets
  // the floor at 4.45 m/s, a step's kick and 2 mm faster than from 1 m:
  // 2.531 J against 2.502 J. It never comes to rest: Box2D's position
  // solver lifts it out of the floor by a little each bounce, and it keeps
  // bouncing at the 0.1 m/s threshold; each such bounce books restitution
  // that the contacts' residue gives back (-1.0 J in 10 s).
  WorldDef def;
  def.use = {{"rigid_body", kBox2D}};
  const BounceBooks b = bounce_books(std::move(def), kBox2D);
  const double arrive = 0.5 * 9.81 * 1.0;
  EXPECT_NEAR(b.first / ((1 - 0.49) * arrive), 1, 0.02);
  EXPECT_LT(b.balance.fraction(), 1e-9);
  EXPECT_LT(std::abs(b.balance.unexplained()), 1e-9 * b.balance.moved);
  // The drop's 4.905 J went into the bounces and the floor.
  EXPECT_NEAR(b.restitution + b.contacts + b.integration, arrive, 0.02 * arrive);
}

TEST(EnergyBooks, AnEngineSwapCarriesTheKineticStoreOver) {
  // The pendulum on ODE, swapped to Box2D at 1 s and back at 2.5 s (adv15
  // F12's case). The ledger hands the bodies' kinetic energy from the
  // engine that left to the one that came (the same store under another
  // stage), and the engine swapped in keeps its books from its first
  // advance. Before: the new engine's store opened at 0 (the bar's kinetic
  // energy at the swap booked as created) and its first step went unbooked.
  for (bool swapped : {false, true}) {
    Sim s([] {
      WorldDef d;
      d.dt = 1.0 / 240;
      return d;
    }());
    const scenes::BarPendulum p = scenes::build_bar_pendulum(*s, 1.0, 0.5);
    if (swapped) {
      s->schedule_swap(1.0, "", "rigid_body", kBox2D);
      s->schedule_swap(2.5, "", kBox2D, "rigid_body");
    }
    EnergyLedger books;
    run_books(*s, books, 960);
    const EnergyBalance& b = books.total();
    const double kinetic = total(books, "rigid_body", "kinetic energy") +
                           (swapped ? total(books, kBox2D, "kinetic energy") : 0.0);
    std::printf(
        "pendulum, 4 s at 1/240 s, %s: moved %.4f J, kinetic store's change %+.6e J, residue "
        "%.2e of the energy moved\n",
        swapped ? "ODE -> Box2D at 1 s -> ODE at 2.5 s" : "ODE alone", b.moved, kinetic,
        b.fraction());
    ASSERT_GT(b.moved, 5.0);
    // The store's change is the bar's kinetic energy now (it starts at rest),
    // from its written motion: the swaps made none and lost none.
    const Vec3 v = s.velocity(p.bar);
    const double w = std::get<Vec3>(s->get(p.bar, "angular_velocity")).z;
    const double inertia = p.mass * (p.length * p.length + p.width * p.width) / 12;
    const double expected = 0.5 * p.mass * dot(v, v) + 0.5 * inertia * w * w;
    EXPECT_NEAR(kinetic, expected, 1e-3 * b.moved) << swapped;
    // Float rounding at the hand-over (Box2D is single precision): 1e-8.
    EXPECT_LT(b.fraction(), 1e-6) << swapped;
  }
}

// --- the motor and the doorbell ---------------------------------------------

struct SceneBooks {
  EnergyBalance balance;
  double battery = 0, heat = 0, magnetism_mismatch = 0, coils_work = 0;
  double iron_work = 0;        ///< what magnetic_forces' pairs with an induced share did, J
  double hand_work = 0;        ///< what a mod's stage booked as given through "drive", J
  double drive_mismatch = 0;   ///< the sum of the "drive" transfer's sides, J
  double string_work = 0;      ///< what the rigid body booked as given to a string, J
  double string_mismatch = 0;  ///< the sum of the "string" transfer's sides, J
  /// What the rigid body's own books leave: its transfers received less its
  /// sinks and its kinetic energy's change, J (0 when they close).
  double rigid_own = 0;
};

/// `engine`: the rigid body swapped in at the start (null: the scene's, ODE).
SceneBooks scene_books(const char* scene, double dt, double seconds, const char* engine = nullptr) {
  BookedScene booked(scene);
  if (engine) booked.world().schedule_swap(0, "", "rigid_body", engine);
  booked.run(seconds, dt);
  const EnergyLedger& books = booked.books;
  SceneBooks out{.balance = books.total()};
  out.battery = total(books, "electricity", "battery work");
  out.heat = total(books, "electricity", "heat (I^2 R)");
  for (const EnergyAccount& a : books.accounts())
    if (a.kind == EnergyKind::Transfer && a.name == "magnetism") out.magnetism_mismatch += a.total;
  out.coils_work = -total(books, "electricity", "magnetism");
  out.iron_work = -total(books, "magnetic_forces", "magnetism");
  const std::string rigid = engine ? engine : "rigid_body";
  for (const EnergyAccount& a : books.accounts()) {
    if (a.kind == EnergyKind::Transfer && a.name == "drive") {
      out.drive_mismatch += a.total;
      if (a.stage != rigid) out.hand_work -= a.total;
    }
    if (a.kind == EnergyKind::Transfer && a.name == "string") {
      out.string_mismatch += a.total;
      if (a.stage == rigid) out.string_work -= a.total;
    }
    if (a.stage == rigid)
      out.rigid_own +=
          a.kind == EnergyKind::Transfer || a.kind == EnergyKind::Source ? a.total : -a.total;
  }
  std::printf(
      "%s%s, %.0f s at 1/%.0f s: battery %.4f J, heat %.4f J, EMF's work %.5f J, magnetism "
      "mismatch %+.2e J, residue %+.2e J = %.4f %% of %.4f J moved\n%s",
      scene, engine ? " on Box2D" : "", seconds, 1 / dt, out.battery, out.heat, out.coils_work,
      out.magnetism_mismatch, out.balance.residue(), 100 * out.balance.fraction(),
      out.balance.moved, books.table().c_str());
  return out;
}

TEST(EnergyBooks, MotorsBooksCloseAndTheResidueShrinksWithTheStep) {
  // Since the motor was retuned so that back-EMF sets its speed (6000-turn
  // coils, an oiled bearing: docs/motor.md), most of the battery's work
  // passes through the magnet-coil coupling. The coupling is
  // energy-consistent to second order (docs/magnetism.md "The coupling's
  // timing": the coil's force carries the current predicted for the step the
  // EMF is paid over, the EMF ramps to the flux rate at the step's end), and
  // the pull a coil's pole strength keeps for the steps after its loop
  // opened at a commutation is booked from the field the opening released
  // ("An opened loop"). Over 10 s the residue is 0.155 % of the energy moved
  // at 1/240 s and 0.091 % at 1/480 s; it was 0.65 % and 0.040 % with that
  // pull left as the coupling's mismatch, 5.7 % at 1/240 s with the force
  // 1.5 steps behind its current. That was induction order 1, whose residue
  // no longer fell at each halving (0.091 % at 1/480 s, 0.100 % at 1/960 s).
  // Since session 17 the default is order 2 (the force's current is the
  // kick's, one step on, not the step's mean the circuit pays the EMF with):
  // the dynamics are second order and so is the residue, but from a larger
  // start: 1.80, 0.80, 0.186 % at 1/120, 1/240, 1/480 s (0.053 % at 1/960 s,
  // session 16), a mismatch that grows steadily through the run (the kick's
  // current against the step's mean, (dt/2) dI/dt dPhi a step).
  // Session 20 (docs/energy.md "Session 20"): the coils pull with the
  // circuit's current of the kick's instant, the rigid body books their work
  // along the mean velocity (paired with the circuit's trapezoid), the EMF's
  // mean over a step is the flux's change along the predicted path, and the
  // permanent magnets' pairs are booked across a coil's switching: 0.080 %
  // at 1/240 s, 0.016 % at 1/480 s (0.80 and 0.19 % before), and the
  // stages' own books close to rounding (they left 0.16 % of the energy
  // moved, magnetic_forces skipping every step whose poles a coil's
  // switching changed).
  const SceneBooks coarse = scene_books("mods/motor", 1.0 / 240, 10);
  const SceneBooks fine = scene_books("mods/motor", 1.0 / 480, 10);
  for (const SceneBooks* m : {&coarse, &fine}) {
    EXPECT_GT(m->battery, 0.1);
    EXPECT_GT(m->coils_work, 0.05);
    EXPECT_LT(std::abs(m->balance.unexplained()), 1e-6 * m->balance.moved);
    EXPECT_LT(m->balance.fraction(), 1e-3) << "the issue's 0.1 %";
  }
  EXPECT_LT(fine.balance.fraction(), 0.4 * coarse.balance.fraction());
}

TEST(EnergyBooks, MotorsBooksOnBox2DCloseAsOnOde) {
  // The motor on Box2D (swapped in at the start, as `alloy run mods/motor
  // --swap rigid_body=rigid_body.box2d@0`): the rigid body's own books
  // close, and the magnet-coil coupling's two sides agree as on ODE (6.49 and
  // 1.68 mJ at 1/240 and 1/480 s; measured 6.8 and 1.6 mJ). Taken along the
  // chords its parts' centres move, the rotor's magnets' pull on one another
  // did work on Box2D's rotor (0.18 J at 1/240 s, 0.087 J at 1/480: first
  // order), which no other stage sees.
  const SceneBooks coarse = scene_books("mods/motor", 1.0 / 240, 10, kBox2D);
  const SceneBooks fine = scene_books("mods/motor", 1.0 / 480, 10, kBox2D);
  for (const SceneBooks* m : {&coarse, &fine}) {
    EXPECT_GT(m->coils_work, 0.1);
    EXPECT_LT(std::abs(m->rigid_own), 1e-9 * m->balance.moved);
  }
  // Session 20: 0.21 and 0.11 mJ at 1/240 and 1/480 s (0.031 and 0.016 %
  // of the energy moved; 6.8 and 1.6 mJ before), at the level of the run's
  // own variation, so no halving is asked.
  for (const SceneBooks* m : {&coarse, &fine}) {
    EXPECT_LT(std::abs(m->magnetism_mismatch), 3e-3 * m->coils_work);
    EXPECT_LT(m->balance.fraction(), 1e-3);
  }
}

TEST(EnergyBooks, AMagnetCrossingAnAirCoilsWindingMakesNoEnergy) {
  // A magnet moved radially out of a powered air coil, through its winding
  // (tests/energy/scenes/through_winding.lua). As a current sheet (the near
  // field, on by default) the coil's flux steps by mu0 n q L where the
  // magnet's string leaves the bore, and no force pays for the step. Session
  // 20's EMF takes the flux's change over a step; it took that step too, as
  // a current kick from 1.35 to 10.3 A and 0.52 J made from nothing (4.1, 4.6,
  // 5.0 % of the energy moved at 1/240, 1/480, 1/960 s: it did not fall with
  // the step; the adversary adv20's finding). Such a step now takes the ramp
  // of the rates alone (electricity_from_magnetism's flux jump): 1e-5 of
  // the energy moved and less.
  for (const double dt : {1.0 / 240, 1.0 / 480}) {
    BookedScene scene("tests/energy/scenes/through_winding.lua");
    scene.run(0.25, dt);
    const auto* faraday = dynamic_cast<magnetism::ElectricityFromMagnetism*>(
        scene.world().stage("electricity_from_magnetism"));
    ASSERT_NE(faraday, nullptr);
    const EnergyBalance& b = scene.books.total();
    std::printf(
        "through the winding at 1/%.0f s: %llu flux jump(s), residue %.2e of %.4f J moved\n",
        1 / dt, (unsigned long long)faraday->flux_jumps(), b.fraction(), b.moved);
    EXPECT_GE(faraday->flux_jumps(), 1u) << "the magnet's string crosses the winding";
    EXPECT_LT(b.fraction(), 1e-4);
  }
}

TEST(EnergyBooks, GeneratorsBooksCloseWithTheHandsWorkBooked) {
  // The hand's crank turns the rotor, the spokes' flux drives the lamp's
  // current, the current's field brakes the rotor: every joule the lamp gets
  // comes through the coupling. The hand is a mod's runtime stage
  // (mods/generator/runtime.lua) that books its work with w:energy (session
  // 19): a source (the hand is outside the books) and the transfer "drive"
  // it gives the rigid body, the torque it queued dotted into the crank's
  // turn over the advance. Before, the hand booked nothing and the residue
  // was the hand's work (103 % of the energy moved at 1/240 s). Now the two
  // sides of "drive" agree to rounding (a planar part turns by exactly h w
  // in ODE's step), and the residue is the magnetism coupling's mismatch
  // alone: 0.48 % of the energy moved at 1/240 s, 0.18 % at 1/480 s before
  // session 20's coupling, 0.017 % and 0.0073 % since.
  const SceneBooks coarse = scene_books("mods/generator", 1.0 / 240, 10);
  const SceneBooks fine = scene_books("mods/generator", 1.0 / 480, 10);
  for (const SceneBooks* g : {&coarse, &fine}) {
    EXPECT_LT(g->coils_work, -0.05) << "the rotor's motion drives the circuit";
    EXPECT_GT(g->hand_work, 0.4) << "the hand turns the crank (20 mN m from 0.2 s to 6 s)";
    EXPECT_LT(std::abs(g->drive_mismatch), 1e-9 * g->hand_work);
    EXPECT_LT(std::abs(g->balance.unexplained()), 1e-6 * g->balance.moved);
    // What is left is the coupling's: the residue is minus its mismatch.
    EXPECT_NEAR(g->balance.residue(), -g->magnetism_mismatch, 1e-6 * g->balance.moved);
  }
  EXPECT_LT(coarse.balance.fraction(), 1e-3) << "the issue's 0.1 %";
  EXPECT_LT(fine.balance.fraction(), 1e-3);
  EXPECT_LT(fine.balance.fraction(), 0.5 * coarse.balance.fraction());
}

TEST(EnergyBooks, TheWeightsStringBooksWhatItTakesAndGives) {
  // The generator turned by a falling weight on an elastic string
  // (mods/generator/weight.lua): the string's stage books the work of the
  // forces it queued, along the weight's move and the drum's move and turn,
  // as the rigid body takes it, with its stretch as a store and its damping
  // and integration error as sinks (session 19). Before, it booked nothing:
  // a "string" mismatch of -0.042 J, 3.2 % of the energy moved over 8 s.
  // Now the transfer's two sides agree to rounding and what is left is the
  // magnetism coupling's mismatch alone.
  const SceneBooks g = scene_books("mods/generator/weight.lua", 1.0 / 240, 8);
  EXPECT_GT(g.string_work, 0.02) << "the falling weight stretches and pulls the string";
  EXPECT_LT(std::abs(g.string_mismatch), 1e-9 * g.string_work);
  EXPECT_LT(std::abs(g.balance.unexplained()), 1e-6 * g.balance.moved);
  EXPECT_NEAR(g.balance.residue(), -g.magnetism_mismatch, 1e-6 * g.balance.moved);
}

/// A scene's books over a run whose stages close their own books: the
/// battery worked, the residue is what the couplings created, and it is
/// within the 0.1 % of the energy moved.
void expect_books_close(const SceneBooks& b, double battery) {
  EXPECT_GT(b.battery, battery);
  EXPECT_LT(std::abs(b.balance.unexplained()), 1e-5 * b.balance.moved);
  EXPECT_NEAR(b.balance.residue(), -b.balance.transfers, 1e-5 * b.balance.moved);
  EXPECT_LT(b.balance.fraction(), 1e-3) << "the issue's 0.1 %";
}

TEST(EnergyBooks, DoorbellBooksCloseWithTheOpenedCoilsPullBooked) {
  // Every stage's own books close. Before session 20 the electromagnet's
  // pole strength followed its current two steps late (electricity ->
  // magnetism_from_electricity -> magnetism -> magnetic_forces ->
  // rigid_body_from_magnetism), so it pulled the armature for up to two
  // steps after the interrupter opened the circuit, when no current flows
  // and no EMF pays for it. That pull is the
  // field's: electricity books it as the EMF's work at the commanded
  // strength, out of the energy the opening released (switching;
  // docs/magnetism.md "An opened loop"). Residue at 1/240 s: 0.075 % of the
  // energy moved with session 14's air-cored coil (0.1 % asked); 0.171 % with
  // the pull left unbooked. Since the coil's iron core is live (session 15)
  // it was 0.132 %, with the work of the core's induced share on the
  // armature booked by no one (0.044 J in 10 s). Session 16 books it
  // (magnetic_forces' "soft iron's work beyond its store": iron on iron
  // where a coil magnetises both has no store while the EMF is paid at held
  // strengths) and the residue shows the coupling's whole mismatch: 0.177 %
  // (0.093 % at 1/120 s, 0.161 % at 1/480 s: it does not fall with the
  // step; it is the interrupter's jump, docs/energy.md); with the iron's
  // poles on its faces and the coil 6 mm up, 0.136, 0.135 and 0.156 %.
  // Session 17, induction order 2 the default and the pack's resistance
  // 0.6 ohm (mods/doorbell/layout.lua): 0.340, 0.326 and 0.070 % at 1/120,
  // 1/240 and 1/480 s. Session 20: the coil pulls with the circuit's current
  // of the kick's instant, so its pull ends with the current, and the step
  // its loop opens in books half the kick's work (its mean-velocity share)
  // from the released field: 0.030 % and 0.0056 % at 1/240 and 1/480 s.
  const SceneBooks d = scene_books("mods/doorbell", 1.0 / 240, 10);
  const SceneBooks fine = scene_books("mods/doorbell", 1.0 / 480, 10);
  for (const SceneBooks* b : {&d, &fine}) {
    expect_books_close(*b, 1.0);
    // The core's induced share pulls the armature. Sessions 16 to 20 booked
    // that pull here as magnetic_forces' work beyond its store (0.042 J in
    // session 16, 0.016 and 0.013 J in session 20): no circuit paid for
    // iron on iron that a coil magnetises. Since session 21 the coil's EMF
    // carries the change of the iron's moments, so the circuit pays for it
    // and the doorbell, with no permanent magnet, leaves magnetic_forces
    // nothing to book (docs/energy.md "Session 21"): 0.030 % and 0.0056 %
    // at 1/240 and 1/480 s before, 0.017 % and 0.0049 % after.
    EXPECT_EQ(b->iron_work, 0.0);
  }
}

TEST(EnergyBooks, ALiveCoreMotorsBooksCloseAsTheStepShrinks) {
  // Session 20's two-phase motor with the kit's live cores
  // (tests/energy/scenes/live_core_motor.lua, docs/motor.md): the spokes
  // magnetise the four cores as they pass, and a core's moment links the
  // coils beside it. Until session 21 the EMF took the iron's poles at held
  // strengths, so the change of a core's moment as a spoke passed was in no
  // coil's EMF, and the work the cores' share from the coils' currents did
  // on the spokes was paid by no circuit: 1.79, 4.45 and 5.52 % of the
  // energy moved at 1/240, 1/480 and 1/960 s, growing as the step fell
  // (soft iron's work beyond its store +0.040, +0.080, +0.096 J). With the
  // iron solved again at the predicted poses (MagneticForces::emf_iron_poles)
  // and the store the iron's co-energy in the magnets' field alone:
  // 0.041, 0.023 and 0.0048 %.
  const SceneBooks coarse = scene_books("tests/energy/scenes/live_core_motor.lua", 1.0 / 240, 10);
  const SceneBooks fine = scene_books("tests/energy/scenes/live_core_motor.lua", 1.0 / 480, 10);
  for (const SceneBooks* b : {&coarse, &fine}) expect_books_close(*b, 0.5);
  EXPECT_LT(fine.balance.fraction(), 0.75 * coarse.balance.fraction()) << "falls with the step";
}

TEST(EnergyBooks, FreeIronsChangingMomentInducesTheCoilsEmf) {
  // Faraday through free soft iron (tests/energy/scenes/iron_beside_coil.lua
  // with the coil's own resistance raised to 10 kOhm, so that its
  // microamperes change nothing): a magnet turns beside a pinned iron bar on
  // an air coil's axis. The
  // coil's EMF, integrated over the run (the loop's resistance times the
  // charge: L dI is nothing here), must be minus the change of the flux
  // the coil links, which electricity_from_magnetism reports from every
  // pole, the bar's induced ones included. The bar does not move, so at
  // held pole strengths (the EMF until session 21) its share of the flux
  // had no rate, and the integral missed it.
  BookedScene scene("tests/energy/scenes/iron_beside_coil.lua");
  World& w = scene.world();
  const ObjectId coil = w.find("coil");
  w.set(coil, "resistance", 1.0e4);
  scene.run_steps(1);  // the stages exist from the first step
  const auto* faraday =
      dynamic_cast<magnetism::ElectricityFromMagnetism*>(w.stage("electricity_from_magnetism"));
  ASSERT_NE(faraday, nullptr);
  auto current = [&] { return std::get<double>(w.get(coil, "current")); };
  auto flux = [&] {
    const auto* f = faraday->find(coil);
    return f ? f->linkage.flux : std::nan("");
  };
  const double dt = w.dt(), resistance = 1.0e4 + 0.01;  // the coil and its wire
  const double flux0 = flux();
  double charge = 0, last = current(), largest = 0, bar_share = 0;
  const int steps = 90;  // 0.375 s: the magnet turns 3.75 rad
  for (int n = 0; n < steps; ++n) {
    scene.run_steps(1);
    const double now = current();
    charge += 0.5 * (last + now) * dt;
    last = now;
    largest = std::max(largest, std::abs(flux() - flux0));
  }
  const double integral = resistance * charge, change = flux() - flux0;
  {  // the bar's induced pole strength now
    const auto* forces =
        dynamic_cast<const magnetism::MagneticForces*>(w.stage(magnetism::MagneticForces::kName));
    ASSERT_NE(forces, nullptr);
    const magnetism::MagneticBody* bar = forces->find(w.find("bar"));
    ASSERT_NE(bar, nullptr);
    bar_share = std::abs(bar->pole_strength);
  }
  std::printf(
      "iron beside a coil, %d steps at 1/%.0f s: EMF's integral %+.6e Wb, flux change %+.6e Wb "
      "(largest excursion %.6e Wb), bar's pole strength now %.4f A m\n",
      steps, 1 / dt, integral, change, largest, bar_share);
  ASSERT_GT(largest, 1e-4) << "the magnet's turn changes the flux";
  EXPECT_GT(bar_share, 1.0) << "the magnet magnetises the bar";
  EXPECT_NEAR(integral, -change, 0.02 * largest);
}

TEST(EnergyBooks, IronsPullComesOutOfItsStore) {
  // An iron bar hung on a hinge swings onto a pinned magnet's end, with no
  // coil and no gravity (tests/energy/scenes/iron_swing.lua). The bar's
  // induced poles are set by the field, so before session 16 no store held
  // the work the magnet's pull does on it: all of it was booked as a source.
  // Now soft iron's co-energy in the magnets' field (-1/2 m.B, less as it
  // saturates) is magnetic_forces' store, and only what it does not explain
  // (the pole model's own error: the moment follows the mean field of its
  // samples, the force acts on the poles' line) is a source. Measured at
  // 1/240 s: over the approach from 15 mm (14 steps, before the contact)
  // 0.18 of 5.19 mJ (3.5 %); over the whole swing, with the last
  // millimetres in which the bar's face pole comes within a softening of
  // the magnet's, 6.7 of 18.1 mJ (5.5 to 5.9 of 16.8 to 17.2 mJ at 1/480,
  // 1/960 and 1/1920 s: the model's near field, not the step). With the store's 1/2 taken out
  // (m.B, a rigid moment's energy) the approach's source is as large as
  // its work, of the other sign.
  auto books_of = [](std::uint64_t steps) {
    BookedScene scene("tests/energy/scenes/iron_swing.lua");
    scene.run_steps(steps);
    return scene.books;
  };
  struct Figures {
    double given, store, beyond;
  };
  auto figures = [](const EnergyLedger& books, const char* what) {
    const Figures f{
        -total(books, "magnetic_forces", "magnetism"),
        total(books, "magnetic_forces", "soft iron's field (co-energy in the magnets' field)"),
        total(books, "magnetic_forces", "soft iron's work beyond its store")};
    std::printf(
        "iron swing, %s at 1/240 s: pull's work %.6f J, store's change %.6f J, beyond %+.2e J\n",
        what, f.given, f.store, f.beyond);
    EXPECT_LT(std::abs(books.total().unexplained()), 1e-6 * books.total().moved);
    return f;
  };
  const EnergyLedger approach_books = books_of(14), swing_books = books_of(240);
  const Figures approach = figures(approach_books, "the approach");
  EXPECT_GT(approach.given, 3e-3) << "the magnet pulls the bar in";
  EXPECT_NEAR(approach.store, -approach.given, 0.05 * approach.given) << "out of the iron's store";
  EXPECT_LT(std::abs(approach.beyond), 0.05 * approach.given);
  const Figures swing = figures(swing_books, "1 s");
  EXPECT_GT(-swing.store, 0.6 * swing.given);
  EXPECT_LT(-swing.store, swing.given);
}

}  // namespace
}  // namespace alloy
