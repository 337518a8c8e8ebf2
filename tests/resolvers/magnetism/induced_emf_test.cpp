// The electricity resolver's side of induction (ElectricityResolver::
// set_induced_emf, fed by electricity_from_magnetism): an EMF in series with
// a coil, for one advance, from terminal 0 to 1; bad commands do nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "resolvers/electricity/electricity.hpp"
#include "runtime/world.hpp"

namespace alloy::electricity {
namespace {

/// A 10 mH, 1.99 Ohm coil closed on itself by a 0.01 Ohm wire: R = 2 Ohm, tau = 5 ms.
struct Loop {
  PluginRegistry registry;
  std::unique_ptr<World> world;
  ObjectId coil, wire;
  explicit Loop() {
    register_electricity_resolver(registry);
    world = std::make_unique<World>(registry);
    World& w = *world;
    coil = w.create("coil");
    w.set(coil, "inductance", 0.01);
    w.set(coil, "resistance", 1.99);
    wire = w.create("wire");
    w.set(wire, "wire_from", coil);
    w.set(wire, "wire_from_terminal", std::int64_t(0));
    w.set(wire, "wire_to", coil);
    w.set(wire, "wire_to_terminal", std::int64_t(1));
    w.set(wire, "resistance", 0.01);
    w.start();
  }
  ElectricityResolver& circuits() {
    return dynamic_cast<ElectricityResolver&>(*world->stage("electricity"));
  }
  double current() { return std::get<double>(world->get(coil, "current")); }
};

TEST(InducedEmf, DrivesItsCoilsCurrentFromTerminal0To1AndRampsToTheNextCommand) {
  Loop loop;
  for (int n = 0; n < 240; ++n) {  // 1 s: 200 time constants
    loop.circuits().set_induced_emf(loop.coil, 3.0);
    loop.world->step();
  }
  EXPECT_NEAR(loop.current(), 3.0 / 2.0, 1e-9);
  EXPECT_EQ(loop.circuits().induced_emf(loop.coil), 3.0);
  // No command: the EMF at that advance's end is 0, and it ramps there
  // linearly over the four trapezoidal substeps (h = 1/960 s, L = 10 mH,
  // R = 2 Ohm), from 3 V, where the last advance left it (a ramp of the
  // series EMF is no discontinuity for the guard). The trapezoidal rule,
  // step by step from the steady state (v_L = E - R I = 0):
  // (2L/h)(I' - I) = v_L + E' - R I', v_L' = E' - R I'.
  loop.world->step();
  EXPECT_EQ(loop.circuits().induced_emf(loop.coil), 0.0);
  const double h = 1.0 / 960, l = 0.01, r = 2.0;
  double i = 1.5, v_l = 0;
  for (int k = 1; k <= 4; ++k) {
    const double e = 3.0 * (1 - k / 4.0);
    i = (2 * l / h * i + v_l + e) / (2 * l / h + r);
    v_l = e - r * i;
  }
  EXPECT_NEAR(loop.current(), i, 1e-9);
  EXPECT_LT(loop.current(), 1.5);
  // The other way round.
  for (int n = 0; n < 240; ++n) {
    loop.circuits().set_induced_emf(loop.coil, -1.0);
    loop.world->step();
  }
  EXPECT_NEAR(loop.current(), -0.5, 1e-9);
}

TEST(InducedEmf, BadCommandsDoNothing) {
  Loop loop;
  ElectricityResolver& c = loop.circuits();
  c.set_induced_emf(loop.coil, std::numeric_limits<double>::quiet_NaN());
  c.set_induced_emf(loop.wire, 5.0);   // a wire is no coil
  c.set_induced_emf(ObjectId{}, 5.0);  // no object
  loop.world->step();
  EXPECT_EQ(loop.current(), 0.0);
  EXPECT_EQ(c.induced_emf(loop.coil), 0.0);
  // The last command before an advance wins.
  c.set_induced_emf(loop.coil, 9.0);
  c.set_induced_emf(loop.coil, 2.0);
  loop.world->step();
  EXPECT_EQ(c.induced_emf(loop.coil), 2.0);
  EXPECT_GT(loop.current(), 0.0);
  // A destroyed coil's command is dropped.
  c.set_induced_emf(loop.coil, 2.0);
  loop.world->destroy(loop.coil);
  loop.world->step();
  EXPECT_TRUE(std::isfinite(std::get<double>(loop.world->get(loop.wire, "current"))));
}

}  // namespace
}  // namespace alloy::electricity
