// Tests for resolvers/electricity/electricity_from_collisions.hpp through the
// real rigid body and collisions set: a conductive bar falling onto a contact
// closes a circuit one step after the touch (paper 4.1.2), lifting it opens
// the circuit again (4.1.4 - 4.1.5), and a touch reaches the terminal of the
// half of a two-terminal part it lands on.
#include "resolvers/electricity/electricity_from_collisions.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "resolvers/electricity/electricity_plugins.hpp"
#include "resolvers/plugins.hpp"

namespace alloy::electricity {
namespace {

class FromCollisionsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    register_electricity_plugins(registry);  // idempotent if the native set already has it
  }

  static ObjectId box(World& w, const std::string& name, Vec3 position, Vec3 size, double mass) {
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
  static ObjectId wire(World& w, const std::string& name, ObjectId from, int ft, ObjectId to,
                       int tt) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
    return id;  // default resistance: 0.01 Ohm
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
  const ObjectId battery = w.create("battery");
  w.set(battery, "emf", 6.0);
  w.set(battery, "internal_resistance", 0.1);
  const ObjectId lamp = w.create("lamp");
  w.set(lamp, "conductive", true);
  w.set(lamp, "resistance", 12.0);
  wire(w, "w1", battery, 1, contact, 0);
  wire(w, "w2", bar, 0, lamp, 0);
  wire(w, "w3", lamp, 1, battery, 0);

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
  for (auto [name, from, ft, to, tt] :
       {std::tuple{"w1", probe, 0, r, 0}, std::tuple{"w2", r, 1, battery, 0}}) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
  }
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
  const ObjectId battery = w.create("battery");
  w.set(battery, "emf", 6.0);
  w.set(battery, "internal_resistance", 0.1);
  const ObjectId lamp = w.create("lamp");
  w.set(lamp, "conductive", true);
  w.set(lamp, "resistance", 12.0);
  wire(w, "w1", battery, 1, contact, 0);
  wire(w, "w2", bar, 0, lamp, 0);
  wire(w, "w3", lamp, 1, battery, 0);
  w.step();  // the resolver and the interaction come to life; the interaction is primed at
             // creation (as at start), sees the touching pair, and the resolver connects it
             // in this same step's advance
  ASSERT_TRUE(w.has_stage("electricity_from_collisions"));
  EXPECT_NEAR(num(w, lamp, "current"), 6.0 / (0.1 + 12.0 + 1e-3 + 3 * 0.01), 1e-9);
}

}  // namespace
}  // namespace alloy::electricity
