// The motor (mods/motor) as a DC motor: its steady speed is set by the
// back-EMF its spokes induce in the coils, so it follows the DC-motor model,
// w = V / k - R (T + T0) / k^2 (motor_support.hpp): the no-load speed grows
// as V / k, the speed falls on a straight line with the load, and the current
// it draws turning is far below the current it draws held still. The model
// is fitted to the rotor's speeds alone (mechanics), and checked against
// what the circuit says (electricity): the fitted R is the loop's resistance
// as built, and the fitted k is (V - I R) / w from the measured current; and
// (V - I R) / w against the coils' torque constant read from the flux code
// at every angle, k(theta) (motor_support.hpp), which no run enters.
#include <gtest/gtest.h>

#include <cstdio>

#include "tests/motor/motor_support.hpp"

namespace alloy::motor::test {
namespace {

/// No load but the bearing's own dry friction (2 mN m) at three batteries;
/// the bearing braked to 4 and 7 mN m (near 10 mN m it stalls where the
/// commutated torque is weakest) at the scene's 6 V. Each point 6 s at the
/// scene's step, measured from 2 s (motor_support.hpp).
const std::vector<DcPoint>& points() {
  return scene_dc_points();
}

/// The scene's k(theta) on a 0.5 degree grid (<k> is the same to 1e-4 on
/// grids of 1 and 0.25 degrees).
const TorqueConstant& torque_constant() {
  static const TorqueConstant t = measure_torque_constant(0.5);
  return t;
}

TEST(MotorDcModel, SpeedFollowsTheModelFittedFromTheMechanicsAlone) {
  const DcFit f = fit_dc_model(points());
  const double R_loop = loop_resistance();
  std::printf(
      "fit: k %.4f V s, R %.1f ohm (loop as built %.1f), T0 %.2f mN m; no-load speed "
      "at 6 V %.3f rad/s, stall torque %.2f mN m\n",
      f.k, f.R, R_loop, 1e3 * f.T0, f.no_load_speed(6), 1e3 * f.stall_torque(6));
  for (const DcPoint& p : points()) {
    const double k_electrical = (p.emf - p.current * R_loop) / p.speed;
    std::printf(
        "  %.1f V, load %.1f mN m: %.3f rad/s (model %.3f), %.2f mA, (V - I R) / w = "
        "%.4f V s\n",
        p.emf, 1e3 * p.load, p.speed, f.speed(p.emf, p.load), 1e3 * p.current, k_electrical);
    EXPECT_GT(p.speed, 1.0) << "it turns";
    // Every point on the model's plane, within 5 %.
    EXPECT_NEAR(p.speed, f.speed(p.emf, p.load), 0.05 * p.speed);
    // The circuit agrees: the back-EMF k w is what the battery has left
    // after the loop's drop, with the k the rotor's speeds give. Measured
    // 5 to 9 % above it with induction_order 1: (V - I R) / w also holds the
    // coil's inductive drop, L I / (a spoke's passage) at each hand-over.
    // With order 2 (the scene's since session 17) the EMF is no longer 1.5
    // steps late, the fit's k rises to 1.124 V s and (V - I R) / w is -0.4 %
    // to +1.6 % of it (1.120 to 1.142 V s): the lower bound, which was f.k,
    // is 1 % under it.
    EXPECT_GT(k_electrical, 0.99 * f.k) << p.emf << " V, " << p.load << " N m";
    EXPECT_LT(k_electrical, 1.10 * f.k) << p.emf << " V, " << p.load << " N m";
  }
  // The R the speeds give is the loop's resistance, coil and all.
  EXPECT_NEAR(f.R, R_loop, 0.05 * R_loop);
  // Small losses: the motor loses a few mN m in itself.
  EXPECT_GT(f.T0, 0);
  EXPECT_LT(f.T0, 0.2 * f.stall_torque(6));
}

TEST(MotorDcModel, TheCircuitsBackEmfConstantIsTheMeanOfTheCoilsTorqueConstant) {
  // Over a turn the battery's emf is the back-EMF, the loop's drop and the
  // coils' inductive drop, V = <k w> + R I + L <di/dt>, and the time mean of
  // k(theta) w is the mean of k over the angle times the mean speed
  // (the integral of k w dt is the integral of k dtheta): so
  // (V - I R) / w = <k>, up to the inductive drop at the hand-overs, where
  // one coil's current ends and the other's starts. <k> comes from the flux
  // the spokes link with the coils at rest, rotor turned step by step; the
  // speeds and currents from the running motor.
  const TorqueConstant& t = torque_constant();
  const double R_loop = loop_resistance();
  std::printf("k(theta): <k> %.4f V s, from %.3f to %.3f, var(k) / <k>^2 = %.3f\n", t.mean,
              *std::min_element(t.k.begin(), t.k.end()), *std::max_element(t.k.begin(), t.k.end()),
              t.dc_resistance_factor() - 1);
  // The drive: anticlockwise at every angle but the hand-overs, where the
  // coil that is on would turn round (k passes through 0 there).
  for (double k : t.k) EXPECT_GT(k, 0);
  for (const DcPoint& p : points()) {
    const double k_electrical = (p.emf - p.current * R_loop) / p.speed;
    // Measured 1.120 to 1.142 V s against <k> = 1.131 (-1.0 to +1.0 %).
    EXPECT_NEAR(k_electrical, t.mean, 0.03 * t.mean) << p.emf << " V, " << p.load << " N m";
  }
}

TEST(MotorDcModel, DrawsFarLessCurrentTurningThanHeldStill) {
  const double R_loop = loop_resistance();
  for (const DcPoint& p : points()) {
    if (p.load > 0.002) continue;
    const double stall_current = p.emf / R_loop;
    EXPECT_GT(p.current, 0);
    EXPECT_LT(p.current, stall_current / 3)
        << p.emf << " V: " << p.current << " A turning, " << stall_current << " A held";
  }
}

}  // namespace
}  // namespace alloy::motor::test
