// Tests for resolvers/electricity/electricity_from_collisions.hpp through the
// real rigid body and collisions set: a conductive bar falling onto a contact
// closes a circuit one step after the touch (paper 4.1.2), lifting it opens
// the circuit again (4.1.4 - 4.1.5), and a touch reaches the terminal of the
// half of a two-terminal part it lands on.
#include "resolvers/electricity/electricity_from_collisions.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "resolvers/electricity/electricity_plugins.hpp"
#include "resolvers/plugins.hpp"

namespace alloy::electricity {
namespace {

ObjectId box(World& w, const std::string& name, Vec3 position, Vec3 size, double mass) {
  const ObjectId b = w.create(name);
  w.set(b, "shape", std::string("box"));
  w.set(b, "size", size);
  w.set(b, "position", position);
  if (mass > 0)
    w.set(b, "mass", mass);
  else
    w.set(b, "static", true);
  return b;
}
ObjectId wire(World& w, const std::string& name, ObjectId from, int ft, ObjectId to, int tt) {
  const ObjectId id = w.create(name);
  w.set(id, "wire_from", from);
  w.set(id, "wire_from_terminal", std::int64_t(ft));
  w.set(id, "wire_to", to);
  w.set(id, "wire_to_terminal", std::int64_t(tt));
  return id;  // default resistance: 0.01 Ohm
}

/// The loop a touch between `contact` and `bar` closes: a 6 V battery (0.1 Ohm
/// inside), its + to the contact, the bar through a 12 Ohm lamp back to its -.
ObjectId lamp_loop(World& w, ObjectId contact, ObjectId bar) {
  const ObjectId battery = w.create("battery");
  w.set(battery, "emf", 6.0);
  w.set(battery, "internal_resistance", 0.1);
  const ObjectId lamp = w.create("lamp");
  w.set(lamp, "conductive", true);
  w.set(lamp, "resistance", 12.0);
  wire(w, "w1", battery, 1, contact, 0);
  wire(w, "w2", bar, 0, lamp, 0);
  wire(w, "w3", lamp, 1, battery, 0);
  return lamp;
}

class FromCollisionsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    register_electricity_plugins(registry);  // idempotent if the native set already has it
  }

  static double num(const World& w, ObjectId id, const char* p) {
    return std::get<double>(w.get(id, p));
  }
  static bool has_event(const World& w, const std::string& type, ObjectId a, ObjectId b = {}) {
    for (const Event& e : w.events())
      if (e.type == type && ((e.a == a && e.b == b) || (e.a == b && e.b == a))) return true;
    return false;
  }

  PluginRegistry registry;
};

TEST_F(FromCollisionsTest, ABarDroppedAcrossTheContactClosesTheCircuitOneStepLater) {
  World w(registry);
  // The switch of the doorbell: a fixed contact, and a bar that falls onto it.
  const ObjectId contact = box(w, "contact", {0, 0, 0}, {0.3, 0.02, 0.02}, 0);
  const ObjectId bar = box(w, "bar", {0, 0.05, 0}, {0.3, 0.02, 0.02}, 0.05);
  w.set(contact, "conductive", true);
  w.set(bar, "conductive", true);
  const ObjectId lamp = lamp_loop(w, contact, bar);

  std::uint64_t began = 0, connected = 0;
  int connects = 0;
  for (int k = 0; k < 240 && connected == 0; ++k) {
    w.step();
    if (has_event(w, "contact_began", contact, bar)) began = w.step_count();
    if (has_event(w, "connected", contact, bar)) connected = w.step_count(), ++connects;
    if (connected == 0) {
      EXPECT_EQ(num(w, lamp, "current"), 0.0);
    }
  }
  ASSERT_GT(began, 0u) << "the bar never reached the contact";
  EXPECT_EQ(connected, began + 1);  // the one-step delay of paper 3.2
  EXPECT_TRUE(has_event(w, "circuit_closed", lamp));
  const double expected = 6.0 / (0.1 + 12.0 + 1e-3 + 3 * 0.01);  // + contact + three wires
  EXPECT_NEAR(num(w, lamp, "current"), expected, 1e-9);
  EXPECT_TRUE(std::get<bool>(w.get(lamp, "powered")));

  // Resting on the contact, the circuit stays closed: no flicker.
  for (int k = 0; k < 240; ++k) {
    w.step();
    if (has_event(w, "connected", contact, bar)) ++connects;
    ASSERT_FALSE(has_event(w, "disconnected", contact, bar)) << "at step " << w.step_count();
  }
  EXPECT_EQ(connects, 1);
  EXPECT_NEAR(num(w, lamp, "current"), expected, 1e-9);

  // Lift the bar off (a player's hand): contact ends, then the circuit opens.
  w.set(bar, "position", Vec3{0, 0.3, 0});
  w.set(bar, "velocity", Vec3{});
  std::uint64_t ended = 0, disconnected = 0;
  for (int k = 0; k < 4 && disconnected == 0; ++k) {
    w.step();
    if (has_event(w, "contact_ended", contact, bar)) ended = w.step_count();
    if (has_event(w, "disconnected", contact, bar)) disconnected = w.step_count();
  }
  ASSERT_GT(ended, 0u);
  EXPECT_EQ(disconnected, ended + 1);
  EXPECT_TRUE(has_event(w, "circuit_opened", lamp));
  EXPECT_EQ(num(w, lamp, "current"), 0.0);
}

TEST_F(FromCollisionsTest, NonConductivePartsDoNotConnect) {
  World w(registry);
  const ObjectId contact = box(w, "contact", {0, 0, 0}, {0.3, 0.02, 0.02}, 0);
  const ObjectId wood = box(w, "wood", {0, 0.021, 0}, {0.3, 0.02, 0.02}, 0.05);
  w.set(contact, "conductive", true);
  w.set(wood, "conductive", false);
  const ObjectId battery = w.create("battery");
  w.set(battery, "emf", 6.0);
  wire(w, "w1", battery, 1, contact, 0);
  w.run(60);
  auto& e = dynamic_cast<ElectricityResolver&>(*w.stage("electricity"));
  EXPECT_EQ(e.contact_count(), 0u);
  // Made conductive while it rests there, it connects (the interaction compares
  // states, it does not wait for a new touch).
  w.set(wood, "conductive", true);
  w.run(2);
  EXPECT_TRUE(e.connected(contact, wood));
}

/// A battery body lying along x (- at -x, + at +x), a small bar dropped onto
/// one end of it, wired back through a 1 Ohm resistor to the battery's - terminal.
double current_when_dropped_at(PluginRegistry& registry, double x) {
  World w(registry);
  const ObjectId battery = w.create("battery");
  w.set(battery, "shape", std::string("box"));
  w.set(battery, "size", Vec3{0.1, 0.02, 0.02});
  w.set(battery, "position", Vec3{});
  w.set(battery, "static", true);
  w.set(battery, "emf", 1.5);
  w.set(battery, "internal_resistance", 0.5);
  w.set(battery, "conductive", true);
  const ObjectId probe = w.create("probe");
  w.set(probe, "shape", std::string("box"));
  w.set(probe, "size", Vec3{0.03, 0.02, 0.02});
  w.set(probe, "position", Vec3{x, 0.03, 0});
  w.set(probe, "mass", 0.01);
  w.set(probe, "conductive", true);
  const ObjectId r = w.create("r");
  w.set(r, "conductive", true);
  w.set(r, "resistance", 1.0);
  wire(w, "w1", probe, 0, r, 0);
  wire(w, "w2", r, 1, battery, 0);
  w.run(120);  // 0.5 s: landed and resting
  auto& e = dynamic_cast<ElectricityResolver&>(*w.stage("electricity"));
  EXPECT_TRUE(e.connected(battery, probe));
  return std::get<double>(w.get(r, "current"));
}

TEST_F(FromCollisionsTest, ATouchReachesTheTerminalOfTheHalfItLandsOn) {
  // On the + end the loop probe - resistor - (-) - battery - (+) - probe closes.
  EXPECT_NEAR(current_when_dropped_at(registry, +0.035), 1.5 / (0.5 + 1.0 + 1e-3 + 2 * 0.01), 1e-9);
  // On the - end the probe and the resistor only join the - terminal to itself.
  EXPECT_EQ(current_when_dropped_at(registry, -0.035), 0.0);
}

TEST_F(FromCollisionsTest, TerminalAtFollowsThePartsOrientation) {
  const Quat half_turn = Quat::from_angle_z(3.14159265358979);
  EXPECT_EQ(ElectricityFromCollisions::terminal_at({1, 0, 0}, {}, {1.2, 0.1, 0}), 1);
  EXPECT_EQ(ElectricityFromCollisions::terminal_at({1, 0, 0}, {}, {0.8, 0.1, 0}), 0);
  EXPECT_EQ(ElectricityFromCollisions::terminal_at({1, 0, 0}, half_turn, {1.2, 0.1, 0}),
            0);  // + end now at -x
}

TEST_F(FromCollisionsTest, ABatteryAddedToARunningWorldFindsThePartsAlreadyTouching) {
  World w(registry);
  const ObjectId contact = box(w, "contact", {0, 0, 0}, {0.3, 0.02, 0.02}, 0);
  const ObjectId bar = box(w, "bar", {0, 0.021, 0}, {0.3, 0.02, 0.02}, 0.05);
  w.set(contact, "conductive", true);
  w.set(bar, "conductive", true);
  w.run(60);  // resting on the contact; no electricity yet (nothing carries emf)
  ASSERT_FALSE(w.has_stage("electricity"));
  const ObjectId lamp = lamp_loop(w, contact, bar);
  w.step();  // the resolver and the interaction come to life; the interaction is primed at
             // creation (as at start), sees the touching pair, and the resolver connects it
             // in this same step's advance
  ASSERT_TRUE(w.has_stage("electricity_from_collisions"));
  EXPECT_NEAR(num(w, lamp, "current"), 6.0 / (0.1 + 12.0 + 1e-3 + 3 * 0.01), 1e-9);
}

/// When a bar gliding at constant speed onto a fixed contact (no gravity)
/// is connected, and when its contact began: the steps (World::step_count)
/// of the "connected" and "contact_began" events. The touch is due at
/// (k + fraction) steps: the gap is v (k + fraction) h.
struct Glide {
  std::uint64_t began = 0, connected = 0;  ///< the first of each, 0: none
  int connects = 0, disconnects = 0;       ///< in 30 steps
};
/// The world of those tests: no gravity, the step 1/240 s, `ahead` and the
/// engine as asked; `place` makes the contact and the moving part (both
/// conductive, returned in that order), wired in a loop with a battery and
/// a lamp. Runs 30 steps; with `restore_at`, saved at that step and
/// continued in a fresh world restored from the save.
template <class Place>
Glide touch_onto_contact(PluginRegistry& registry, bool ahead, bool box2d, Place place,
                         std::uint64_t restore_at = 0, int electricity_every = 1) {
  WorldDef def;
  def.dt = 1.0 / 240;
  if (electricity_every > 1) def.every["electricity"] = electricity_every;
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  if (ahead) def.settings["electricity_from_collisions"].set("ahead", true);
  if (box2d) def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  auto first = std::make_unique<World>(registry, def);
  World* w = first.get();
  auto part = [&](const char* name, Vec3 at, Vec3 size, double mass) {
    const ObjectId b = box(*w, name, at, size, mass);
    w->set(b, "conductive", true);
    return b;
  };
  const auto [contact, mover] = place(*w, part);
  lamp_loop(*w, contact, mover);
  Glide g;
  std::unique_ptr<World> second;
  for (int n = 0; n < 30; ++n) {
    if (restore_at > 0 && w->step_count() == restore_at) {
      // Saved here and continued in a fresh world, as a loaded save is.
      const Snapshot at = w->snapshot();
      second = std::make_unique<World>(registry, def);
      second->restore(at);
      w = second.get();
    }
    w->step();
    for (const Event& e : w->events()) {
      const bool ours = (e.a == contact && e.b == mover) || (e.a == mover && e.b == contact);
      if (ours && e.type == "contact_began" && g.began == 0) g.began = w->step_count();
      if (ours && e.type == "connected" && g.connected == 0) g.connected = w->step_count();
      g.connects += ours && e.type == "connected";
      g.disconnects += ours && e.type == "disconnected";
    }
  }
  return g;
}

/// A bar gliding at 0.5 m/s onto a fixed contact, its touch due at
/// (10 + fraction) steps: the gap is v (10 + fraction) h.
Glide glide_onto_contact(PluginRegistry& registry, double fraction, bool ahead, bool box2d,
                         std::uint64_t restore_at = 0, int electricity_every = 1) {
  const double h = 1.0 / 240, v = 0.5;
  return touch_onto_contact(
      registry, ahead, box2d,
      [&](World& w, auto& part) {
        const Vec3 size{0.3, 0.02, 0.02};
        const ObjectId contact = part("contact", {0, 0, 0}, size, 0);
        const ObjectId bar = part("bar", {0, 0.02 + v * (10 + fraction) * h, 0}, size, 0.05);
        w.set(bar, "velocity", Vec3{0, -v, 0});
        return std::pair{contact, bar};
      },
      restore_at, electricity_every);
}

/// A bar 0.3 m long spinning in place at 2 rad/s (its centre at rest) whose
/// end's corner sweeps up into a fixed contact above it, the touch due at
/// (10 + fraction) steps: the corner (0.15, 0.01) turned by theta is at height
/// 0.15 sin(theta) + 0.01 cos(theta), the contact's face at that height for
/// theta = w (10 + fraction) h.
Glide spin_onto_contact(PluginRegistry& registry, double fraction, bool ahead, bool box2d) {
  const double h = 1.0 / 240, spin = 2.0;
  return touch_onto_contact(registry, ahead, box2d, [&](World& w, auto& part) {
    const double theta = spin * (10 + fraction) * h;
    const double face = 0.15 * std::sin(theta) + 0.01 * std::cos(theta);
    const ObjectId contact = part("contact", {0.14, face + 0.01, 0}, {0.04, 0.02, 0.02}, 0);
    const ObjectId bar = part("bar", {0, 0, 0}, {0.3, 0.02, 0.02}, 0.05);
    w.set(bar, "angular_velocity", Vec3{0, 0, spin});
    return std::pair{contact, bar};
  });
}

// Contacts between steps (setting `ahead`). The touch is due 0.3 or 0.7 of
// a step into step k + 1 = 11: the collisions set sees it at that step's end
// (contact_began at step 11) and, without `ahead`, the circuit is connected
// in the next advance (step 12), 1.7 or 1.3 steps after the touch. With
// `ahead`, at the end of step 10 the bar is predicted to touch within half a
// step when the touch is due 0.3 of a step on, and is connected in step 11's
// advance, 0.3 of a step early; due 0.7 on, it is not predicted, and is
// connected as without (1.3 steps late): the connection comes at the step
// boundary nearest the touch plus one step, never more than half a step
// early. On ODE, the closed form of a glide at constant speed.
TEST_F(FromCollisionsTest, AheadConnectsATouchDueInTheFirstHalfOfAStepAtThatStepsStart) {
  for (const double fraction : {0.3, 0.7}) {
    const Glide plain = glide_onto_contact(registry, fraction, false, false);
    const Glide ahead = glide_onto_contact(registry, fraction, true, false);
    SCOPED_TRACE(fraction);
    EXPECT_EQ(plain.began, 11u);
    EXPECT_EQ(plain.connected, 12u);
    EXPECT_EQ(ahead.began, 11u);
    EXPECT_EQ(ahead.connected, fraction < 0.5 ? 11u : 12u);
  }
}

// The same on Box2D's engine. Box2D finds its contacts at the start of its
// step, so its contact_began comes a step after ODE's (step 12), and its
// shapes carry a skin (Box2D's polygon radius), so they touch a little
// before the boxes' faces meet. The prediction tests Box2D's own shapes at
// the predicted poses: with `ahead` a touch due early in step 11 is
// connected in step 11 (a step before Box2D reports it), one due late in
// step 12, as Box2D's report; without, always a step after the report. Which
// fractions come early depends on the skin: the earliest ones do, the latest
// do not, and nothing in between goes back.
TEST_F(FromCollisionsTest, AheadPredictsTouchesOnBox2DsShapesToo) {
  std::vector<bool> early;
  for (const double fraction : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    const Glide plain = glide_onto_contact(registry, fraction, false, true);
    const Glide ahead = glide_onto_contact(registry, fraction, true, true);
    SCOPED_TRACE(::testing::Message()
                 << fraction << " plain " << plain.began << "/" << plain.connected << " ahead "
                 << ahead.began << "/" << ahead.connected);
    EXPECT_EQ(plain.began, 12u);
    EXPECT_EQ(plain.connected, 13u);
    EXPECT_EQ(ahead.began, 12u);
    EXPECT_TRUE(ahead.connected == 11u || ahead.connected == 12u);
    early.push_back(ahead.connected == 11u);
  }
  EXPECT_TRUE(early[0] && early[1]);
  EXPECT_TRUE(!early[3] && !early[4]);
  EXPECT_TRUE(std::is_sorted(early.rbegin(), early.rend()));  // true, ..., true, false, ...
}

// A part that turns: its touch is predicted from its angular velocity (the
// motor's spokes on Box2D, where the rotor is one body turning about the
// axle, and every part whose own turning moves its edge). The prediction is
// geometry alone, so on both engines the touch due inside step 11 is
// connected in step 11 when early in it and in step 12 when late, though
// Box2D reports the contact a step after ODE (above).
TEST_F(FromCollisionsTest, AheadPredictsATurningPartsTouch) {
  for (const bool box2d : {false, true}) {
    for (const double fraction : {0.2, 0.8}) {
      const Glide plain = spin_onto_contact(registry, fraction, false, box2d);
      const Glide ahead = spin_onto_contact(registry, fraction, true, box2d);
      SCOPED_TRACE(::testing::Message()
                   << (box2d ? "box2d " : "ode ") << fraction << " plain " << plain.began << "/"
                   << plain.connected << " ahead " << ahead.began << "/" << ahead.connected);
      EXPECT_EQ(plain.began, box2d ? 12u : 11u);
      EXPECT_EQ(plain.connected, plain.began + 1);
      EXPECT_EQ(ahead.began, plain.began);
      // Geometry alone: the touch is due inside step 11 on both engines.
      EXPECT_EQ(ahead.connected, fraction < 0.5 ? 11u : 12u);
    }
  }
}

// A save made while a predicted connection is queued (at the end of step
// 10, a touch due 0.3 into step 11) loses nothing: the restored world
// connects in step 11, as the run that went on did. On Box2D the restored
// engine has no contacts until its first advance, and its prediction needs
// only its bodies (adv21: it answered nothing there, and the connection
// came a step late or the circuit opened for a step).
TEST_F(FromCollisionsTest, ARestoreKeepsAPredictedConnection) {
  for (const bool box2d : {false, true})
    for (const std::uint64_t at : {9u, 10u, 11u}) {
      const Glide straight = glide_onto_contact(registry, 0.3, true, box2d);
      const Glide restored = glide_onto_contact(registry, 0.3, true, box2d, at);
      SCOPED_TRACE(::testing::Message() << (box2d ? "box2d" : "ode") << " saved at " << at);
      EXPECT_EQ(straight.connected, 11u);
      EXPECT_EQ(restored.connected, straight.connected);
      EXPECT_EQ(restored.connects, straight.connects);
      EXPECT_EQ(restored.disconnects, straight.disconnects);
    }
}

// A touch shorter than a step on Box2D, whose contact set reports it a step
// late: predicted at the end of one step, it is neither reported nor
// predicted at the next (the bar bounced), and without the hold it was
// disconnected there and connected again when Box2D reported it: two makes
// and two breaks, twice the charge (adv21 box2d_flicker). One of each.
TEST_F(FromCollisionsTest, OnBox2DAShortTouchIsConnectedOnce) {
  const double h = 1.0 / 240;
  for (const double v : {3.0, 5.0}) {
    // A 4 mm block at v onto a contact 1 mm thick, the touch 0.3 into step 5,
    // bouncing off (restitution 1).
    const Glide g = touch_onto_contact(registry, true, true, [&](World& w, auto& part) {
      const ObjectId contact = part("contact", {0.0005, 0, 0}, {0.001, 0.02, 0.02}, 0);
      const ObjectId block =
          part("block", {-(4 + 0.3) * h * v - 0.002, 0, 0}, {0.004, 0.004, 0.02}, 0.001);
      w.set(block, "velocity", Vec3{v, 0, 0});
      for (const ObjectId o : {contact, block}) w.set(o, "restitution", 1.0);
      return std::pair{contact, block};
    });
    SCOPED_TRACE(::testing::Message()
                 << v << " m/s: began " << g.began << ", connected " << g.connected);
    ASSERT_GT(g.began, 0u) << "Box2D saw the touch";
    EXPECT_EQ(g.connects, 1);
    EXPECT_EQ(g.disconnects, 1);
  }
}

// With the electricity every 4th step the connection acts over its next
// advance, 4 steps long: the prediction looks half of that on (2 steps), so
// the advance that carries the connection starts within two steps of the
// touch, early as often as late. Without it the connection is always late,
// by up to 4 steps; with a half world step only, touches 0.5 to 2 steps
// after an advance's start were as late as without (adv21 every.py).
TEST_F(FromCollisionsTest, AheadLooksHalfTheElectricitysOwnStepOn) {
  double early = 0, late = 0;
  for (int i = 0; i < 16; ++i) {
    const double touch = 10 + 6.1 + 0.25 * i;  // steps 16.1 to 19.85: one advance's span
    const Glide plain = glide_onto_contact(registry, touch - 10, false, false, 0, 4);
    const Glide ahead = glide_onto_contact(registry, touch - 10, true, false, 0, 4);
    SCOPED_TRACE(::testing::Message() << "touch at " << touch << " steps: connected "
                                      << plain.connected << " / " << ahead.connected);
    ASSERT_GT(plain.connected, 0u);
    ASSERT_GT(ahead.connected, 0u);
    // The advance that performs the connect spans the `connected` step's
    // last 4 steps: it starts at connected - 1 in world steps (the step
    // counted from 1 ends at its number).
    const double lag_plain = double(plain.connected) - 1 - touch;
    const double lag_ahead = double(ahead.connected) - 1 - touch;
    EXPECT_GE(lag_plain, 0);
    EXPECT_LE(lag_plain, 4);
    EXPECT_GE(lag_ahead, -2);
    EXPECT_LE(lag_ahead, 2);
    early += lag_ahead<0, late += lag_ahead> 0;
  }
  EXPECT_EQ(early, 8);
  EXPECT_EQ(late, 8);
}

// A save's waiting pairs are checked: a count outside 0 to the largest
// report lag, or counts that do not match the pairs, is damage, named with
// the stage (a hostile save could otherwise hold a circuit closed through
// parts apart for as long as its count said).
TEST_F(FromCollisionsTest, ADamagedSaveOfTheWaitingPairsIsRefusedByName) {
  WorldDef def;
  def.settings["electricity_from_collisions"].set("ahead", true);
  World w(registry, def);
  const ObjectId contact = box(w, "contact", {0, 0, 0}, {0.3, 0.02, 0.02}, 0);
  const ObjectId bar = box(w, "bar", {0, 0.03, 0}, {0.3, 0.02, 0.02}, 0.05);
  for (const ObjectId o : {contact, bar}) w.set(o, "conductive", true);
  lamp_loop(w, contact, bar);
  w.step();
  auto& stage = *w.stage("electricity_from_collisions");
  auto state = [&](std::vector<ObjectId> pairs, std::vector<std::int32_t> counts) {
    StateWriter out;
    out.put_vector(std::vector<ObjectId>{});
    out.put_vector(pairs);
    out.put_vector(counts);
    return out.bytes();
  };
  auto restore = [&](const std::vector<std::byte>& bytes) {
    StateReader in("electricity_from_collisions", bytes);
    stage.restore_state(in);
  };
  EXPECT_NO_THROW(restore(state({contact, bar}, {1})));
  for (const std::int32_t bad : {-1, ElectricityFromCollisions::kMaxReportLag + 1, 1 << 30}) {
    try {
      restore(state({contact, bar}, {bad}));
      ADD_FAILURE() << "a count of " << bad << " was taken";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("electricity_from_collisions"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find("count"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(restore(state({contact, bar}, {0, 0})), InputError);
}

// A circuit inside an area run by Box2D: the area's collisions.box2d
// provides `collisions` there, and the interaction follows it with an
// instance of its own in the area, as interactions follow an area's
// provider of their target (adv21 area_inside.lua: the global instance read
// ODE's set, which leaves the area's parts out, and the circuit never
// closed, silently). Glued to the global electricity resolver.
TEST_F(FromCollisionsTest, ACircuitInsideABox2DAreaCloses) {
  WorldDef def;
  def.dt = 1.0 / 240;
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  AreaDef right;
  right.name = "right";
  right.center = {1, 0, 0};
  right.half_extents = {1, 1, 1};
  right.plugins = {"rigid_body.box2d", "collisions.box2d", "rigid_body_from_gravity"};
  def.areas.push_back(right);
  World w(registry, def);
  const ObjectId contact = box(w, "contact", {1, 0, 0}, {0.3, 0.02, 0.02}, 0);
  const ObjectId bar = box(w, "bar", {1, 0.03, 0}, {0.3, 0.02, 0.02}, 0.05);
  w.set(bar, "velocity", Vec3{0, -0.5, 0});
  for (const ObjectId o : {contact, bar}) w.set(o, "conductive", true);
  const ObjectId lamp = lamp_loop(w, contact, bar);
  bool connected = false;
  for (int k = 0; k < 30; ++k) {
    w.step();
    for (const Event& e : w.events()) connected = connected || e.type == "connected";
  }
  EXPECT_TRUE(w.has_stage("electricity_from_collisions@right"));
  EXPECT_TRUE(connected);
  EXPECT_NEAR(num(w, lamp, "current"), 6.0 / (0.1 + 12.0 + 1e-3 + 3 * 0.01), 1e-9);
}

}  // namespace
}  // namespace alloy::electricity
