// The motor's back-EMF (resolvers/electricity/electricity_from_magnetism.hpp):
// in the scene as built, the EMF its spokes induce in the powered coil
// opposes the current (Lenz), and the power the coils' fields put into the
// rotor is the power the back-EMF takes out of the circuits (the coupling's
// energy balance, on the whole machine with its commutation).
#include <gtest/gtest.h>

#include <cmath>

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/electricity/electricity_from_magnetism.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "tests/motor/motor_support.hpp"

namespace alloy::motor::test {
namespace {

struct Balance {
  double speed = 0, back_emf = 0;         ///< mean rad/s; mean EMF along the current, V
  double mechanical = 0, electrical = 0;  ///< J over 2 s of steady running
  double mismatch() const { return std::abs(mechanical + electrical) / mechanical; }
};

Balance run(double dt) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(source("mods"));
  lua::LoadedScene loaded = lua::load_scene(source(kScene), registry, load);
  World& w = *loaded.world;
  w.set_dt(dt);
  w.start();
  std::vector<ObjectId> spokes;
  for (const char* name : {"spoke_N1", "spoke_N2", "spoke_N3", "spoke_N4", "spoke_S1", "spoke_S2",
                           "spoke_S3", "spoke_S4"})
    spokes.push_back(w.find(name));
  const ObjectId coils[2] = {w.find("upper_coil"), w.find("lower_coil")};
  const ObjectId axle = w.find("axle");
  auto& forces = dynamic_cast<magnetism::MagneticForces&>(*w.stage("magnetic_forces"));
  auto& circuits = dynamic_cast<electricity::ElectricityResolver&>(*w.stage("electricity"));
  const Vec3 centre = std::get<Vec3>(w.get(axle, "position"));

  double electrical = 0, mechanical = 0, back_emf = 0, speed = 0;
  int n = 0;
  const auto steady = std::uint64_t(std::llround(kSteadyFrom / dt));
  for (std::uint64_t s = 0; s < steady + std::llround(2.0 / dt); ++s) {
    const double omega = w.store().has(axle, w.properties().id("angular_velocity"))
                             ? std::get<Vec3>(w.get(axle, "angular_velocity")).z
                             : 0.0;
    w.step();
    if (s < steady) continue;
    // The coils' torque on the rotor (about the axle) in this step's load,
    // from the poles the step used: coil poles on spoke poles.
    const auto poles = forces.poles();
    double torque = 0;
    for (ObjectId spoke : spokes) {
      const magnetism::MagneticBody& b = *forces.find(spoke);
      for (std::uint32_t i = b.first_pole; i < b.first_pole + 2; ++i)
        for (ObjectId c : coils)
          if (const magnetism::MagneticBody* cb = forces.find(c); cb && cb->pole_count == 2)
            for (std::uint32_t j = cb->first_pole; j < cb->first_pole + 2; ++j) {
              const Vec3 f = magnetism::pole_pair_force(poles[j].strength, poles[j].position,
                                                        poles[i].strength, poles[i].position,
                                                        forces.softening());
              torque += cross(poles[i].position - centre, f).z;
            }
    }
    mechanical += torque * omega * dt;
    for (ObjectId c : coils) {
      const double emf = circuits.induced_emf(c), current = std::get<double>(w.get(c, "current"));
      electrical += emf * current * dt;
      if (std::abs(current) > 1e-3) back_emf += emf * (current > 0 ? 1 : -1);
    }
    speed += omega;
    ++n;
  }
  return {speed / n, back_emf / n, mechanical, electrical};
}

TEST(MotorBackEmf, OpposesTheCurrentAndBalancesTheCoilsWorkOnTheRotor) {
  for (double dt : {kSceneDt, kSceneDt / 2}) {
    const Balance b = run(dt);
    std::printf(
        "dt 1/%.0f: %.3f rad/s, back-EMF along the current %.4f V (k_e %.4f V s); coils' "
        "work on the rotor %.5f J, EMF's work on the circuits %.5f J (%.2f %% apart)\n",
        1 / dt, b.speed, b.back_emf, -b.back_emf / b.speed, b.mechanical, b.electrical,
        100 * b.mismatch());
    EXPECT_GT(b.speed, 3.0);
    EXPECT_LT(b.back_emf, 0) << "Lenz: a motor's EMF opposes its current";
    // Since the coupling is energy-consistent (the coil's force carries the
    // current the EMF is paid with, the EMF the flux change over the step,
    // both to second order: docs/magnetism.md "The coupling's timing") the
    // two sides differ by 4.73 % at 1/240 s and 1.30 % at 1/480 s, most of
    // it this test's own sampling (torque at the step's start times the
    // speed, EMF at its end times the current); the ledger's exact books
    // differ by 0.48 % and 0.026 % of the energy moved (tests/energy). Before,
    // with the force 1.5 steps behind the current: 21.4 % and 11.4 %.
    // Session 20 (the coil pulls with the current of the step's instant, the
    // EMF's mean is the flux's change over the step): 0.35 % and 0.42 %,
    // this sampling's floor at both steps (the ledger's books: 0.080 % and
    // 0.016 % of the energy moved), so the bound is 1 % at each, no halving.
    EXPECT_LT(b.mismatch(), 0.01);
  }
}

}  // namespace
}  // namespace alloy::motor::test
