// The induction coupling's order (issue 13): a magnet on a spring through a
// shorted coil is an eddy-damped oscillator whose decay rate has a closed
// form, and the work-precision scene of a magnet flown through a closed coil
// must converge at second order in the step, with electricity's setting
// induction_order = 2 (the EMF takes the parts' velocity at the step's end,
// the force the current of the rigid body's kick; order 1, the default, is
// first order: 0.7 on the flown magnet). docs/electricity.md "The
// coupling's order".
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "resolvers/magnetism/magnet_parts.hpp"
#include "tests/scenes/analytic_scenes.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy {
namespace {

namespace an = scenes::analytic;

// The oscillator: a 50 g magnet on a 20 N/m spring (w0 = 20 rad/s), the
// work-precision scene's magnet and air-cored coil (analytic_scenes.hpp) with
// 8000 turns, of 160 Ohm and 10 mH (L/R = 62.5 us, short against the period).
// The coil's near field is a current sheet's (magnetic_forces' default): its
// flux gradient k = dPhi/dx on the axis is largest 2.27 cm before the coil's
// centre, 6.02 Wb/m (0.376 Wb/m for 500 turns; the pole pair's 6.26 Wb/m at
// 1.54 cm for 500 turns was its near-field artefact), so the decay rate,
// about k^2 / (2 m R) = 2.26 1/s, is close to the pole pair's 2.45.
constexpr double kTurns = 8000;
constexpr double kMass = 0.05, kStiffness = 20, kCoilR = 160, kCoilL = 0.01;
constexpr double kAmplitude = 0.0005;  // m: the coupling constant varies by < 0.06 % over it

/// Where the coupling constant k = dPhi/dx is largest on the coil's axis
/// (x < 0), and k there, from the sheet's closed form on the axis: its first
/// derivative is 0, so k is constant to second order in the swing.
std::pair<double, double> steepest() {
  return an::induction_steepest(kTurns);
}

/// The decay rate of the linear eddy-damped oscillator
///   m x'' + s x = k I,   L I' + R I = -k x'
/// (s the spring's stiffness): the real part of the complex roots of
///   m L p^3 + m R p^2 + (s L + k^2) p + s R = 0,
/// found by Newton's method from the L -> 0 answer, gamma = k^2 / (2 m R).
double closed_form_decay(double k) {
  using C = std::complex<double>;
  const double gamma = k * k / (2 * kMass * kCoilR);
  C p{-gamma, std::sqrt(kStiffness / kMass - gamma * gamma)};
  for (int i = 0; i < 50; ++i) {
    const C f = kMass * kCoilL * p * p * p + kMass * kCoilR * p * p +
                (kStiffness * kCoilL + k * k) * p + kStiffness * kCoilR;
    const C df =
        3.0 * kMass * kCoilL * p * p + 2.0 * kMass * kCoilR * p + (kStiffness * kCoilL + k * k);
    p -= f / df;
  }
  return -p.real();
}

struct Oscillator {
  scenes::Sim sim;
  ObjectId magnet, coil;
  double centre = 0;  // the spring's rest position, m
};

/// A shorted coil at the origin, axis x; the magnet on a spring along the
/// axis at the coil's steepest point, let go `kAmplitude` beyond it.
void build(Oscillator& o, double centre) {
  World& w = *o.sim;
  const PropertyRegistry& reg = w.properties();
  const EnumValue box = *reg.enum_value(reg.id("shape"), "box");
  o.centre = centre;
  o.coil = w.create("coil");
  w.set(o.coil, "position", Vec3{0, 0, 0});
  w.set(o.coil, magnetism::prop::kMagnet,
        EnumValue{std::int32_t(magnetism::MagnetKind::Electromagnet)});
  w.set(o.coil, magnetism::prop::kTurns, kTurns);
  w.set(o.coil, magnetism::prop::kCoilFactor, an::kInductionCoilFactor);
  w.set(o.coil, magnetism::prop::kPoleSeparation, an::kInductionCoilPoles);
  w.set(o.coil, "inductance", kCoilL);
  w.set(o.coil, "resistance", kCoilR);
  const ObjectId wire = w.create("wire");
  w.set(wire, "wire_from", o.coil);
  w.set(wire, "wire_from_terminal", std::int64_t(0));
  w.set(wire, "wire_to", o.coil);
  w.set(wire, "wire_to_terminal", std::int64_t(1));
  w.set(wire, "resistance", 0.0);
  o.magnet = w.create("magnet");
  w.set(o.magnet, "position", Vec3{centre + kAmplitude, 0, 0});
  w.set(o.magnet, "shape", box);
  w.set(o.magnet, "size", Vec3{0.02, 0.01, 0.01});
  w.set(o.magnet, "mass", kMass);
  w.set(o.magnet, magnetism::prop::kMagnet,
        EnumValue{std::int32_t(magnetism::MagnetKind::Permanent)});
  w.set(o.magnet, magnetism::prop::kPoleStrength, an::kInductionQ);
  w.set(o.magnet, magnetism::prop::kPoleSeparation, an::kInductionPoles);
  // A spring of rest length 0.1 m to a point of the board 0.1 m along +x:
  // F = s (centre - x) along x.
  const ObjectId spring = w.create("spring");
  w.set(spring, "spring_a", o.magnet);
  w.set(spring, "spring_anchor_a", Vec3{});
  w.set(spring, "spring_anchor_b", Vec3{centre + 0.1, 0, 0});
  w.set(spring, "spring_stiffness", kStiffness);
  w.set(spring, "spring_rest_length", 0.1);
  w.set(spring, "spring_damping", 0.0);
}

/// The decay rate of the swing, 1/s: a least-squares line through the log
/// of its peaks (each refined by a parabola through three samples) over
/// `seconds`.
double measured_decay(double dt, double seconds, int order) {
  Oscillator o{scenes::Sim(an::world_def(dt, {.induction_order = order}, /*gravity=*/false))};
  build(o, steepest().first);
  World& w = *o.sim;
  std::vector<double> x;
  x.push_back(kAmplitude);
  const auto steps = std::uint64_t(std::llround(seconds / dt));
  for (std::uint64_t i = 0; i < steps; ++i) {
    w.step();
    x.push_back(o.sim.position(o.magnet).x - o.centre);
  }
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    if (!(x[i] > x[i - 1] && x[i] >= x[i + 1])) continue;
    const double curve = x[i - 1] - 2 * x[i] + x[i + 1];
    const double shift = curve != 0 ? 0.5 * (x[i - 1] - x[i + 1]) / curve : 0;
    const double t = (double(i) + shift) * dt;
    const double peak = x[i] - 0.25 * (x[i - 1] - x[i + 1]) * shift;
    const double y = std::log(peak);
    n += 1, st += t, sy += y, stt += t * t, sty += t * y;
  }
  EXPECT_GE(n, 8) << "dt " << dt << ": too few swings";
  return -(n * sty - st * sy) / (n * stt - st * st);
}

TEST(InductionOrder, AnEddyDampedOscillatorDecaysAtTheClosedFormRate) {
  const auto [centre, k] = steepest();
  const double exact = closed_form_decay(k);
  const double short_coil = k * k / (2 * kMass * kCoilR);
  std::printf("steepest point x = %.5f m, k = %.4f Wb/m; decay rate %.6f 1/s (L -> 0: %.6f)\n",
              centre, k, exact, short_coil);
  ASSERT_GT(exact, 0.5);  // a few e-foldings in the run
  double previous = INFINITY;
  for (int rate : {240, 480, 960}) {
    const double gamma = measured_decay(1.0 / rate, 3.0, 2);
    const double error = std::abs(gamma / exact - 1);
    std::printf("dt 1/%d: decay rate %.6f 1/s, %.4f %% off the closed form\n", rate, gamma,
                100 * error);
    // Measured (session 20, the sheet's k, 8000 turns): 2.58, 0.536,
    // 0.123 % at 1/240, 1/480 and 1/960 s, falling 4.8 and 4.4 times a
    // halving (session 16, the pole pair's k, 500 turns: 2.47, 0.52,
    // 0.117 %). With the coupling of sessions 14-15: 3.87, 1.32, 0.566 %
    // (first order; it fails this test).
    if (rate == 960) {
      EXPECT_LT(error, 0.002);
    }
    if (rate > 240) {
      EXPECT_LT(error, 0.3 * previous) << "dt 1/" << rate << ": not second order";
    }
    previous = error;
  }
}

TEST(InductionOrder, TheFlownMagnetsCurrentConvergesAtSecondOrder) {
  // The work-precision scene (bench/work_precision.cpp --induction) at the
  // default 4 substeps: halving the step must divide the current's error
  // by more than 3 (order > 1.58). Order 1 (sessions 14-16) gave 0.17,
  // 0.12, 0.074 of the peak at 1/480, 1/960, 1/1920 s (order 0.5 to 0.7).
  // With the coil as a current sheet (4000 turns, from 0.4 m; session 20):
  // 0.0012, 0.00030, 0.000077 (order 2.0).
  double previous = INFINITY;
  for (int rate : {480, 960, 1920}) {
    const an::Result r = an::run_induction(1.0 / rate, {.induction_order = 2});
    ASSERT_TRUE(r.finite);
    std::printf("dt 1/%d: largest current error %.5f of the peak\n", rate, r.error);
    if (rate > 480) {
      EXPECT_LT(r.error, previous / 3) << "dt 1/" << rate;
    }
    previous = r.error;
  }
  EXPECT_LT(previous, 0.01);
}

TEST(InductionOrder, ARestoredWorldKeepsTheAccelerationHistory) {
  // electricity_from_magnetism keeps each part's velocity of the last two
  // steps (the acceleration the EMF moves the parts on with) and saves it:
  // a world restored from a snapshot must go on bit for bit as the one that
  // took it.
  const double dt = 1.0 / 480;
  const int order = 2;
  Oscillator o{scenes::Sim(an::world_def(dt, {.induction_order = order}, /*gravity=*/false))};
  build(o, steepest().first);
  World& w = *o.sim;
  w.run(37);
  const Snapshot snap = w.snapshot();
  std::vector<double> first, second;
  for (int i = 0; i < 20; ++i) {
    w.step();
    first.push_back(std::get<double>(w.get(o.coil, "current")));
  }
  w.restore(snap);
  for (int i = 0; i < 20; ++i) {
    w.step();
    second.push_back(std::get<double>(w.get(o.coil, "current")));
  }
  ASSERT_NE(first[0], 0.0);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(first[i], second[i]) << "step " << i;
}

TEST(InductionOrder, AnInductionOrderOtherThan1Or2IsRefusedByName) {
  WorldDef def = an::world_def(1.0 / 240, {}, /*gravity=*/false);
  def.settings["electricity"].set("induction_order", std::int64_t(3));
  Oscillator o{scenes::Sim(def)};
  try {
    build(o, -0.015);
    o.sim->step();
    FAIL() << "induction_order 3 was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("induction_order"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace alloy
