// Scenes with a known answer, for work-precision measurements: each is built
// through the world's editing API with every native plugin (as a Lua scene
// would be), run at a given step and solver setting, and compared along the
// way with its exact solution or with a fine RK4 of its equations of motion.
// bench/work_precision.cpp sweeps them; tests/bench asserts the orders of
// convergence they show.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/world.hpp"

namespace alloy::scenes::analytic {

/// The knobs a work-precision sweep turns besides the step.
struct Method {
  std::string solver =
      "quick";             ///< rigid_body solver: "quick" (dWorldQuickStep) or "step" (dWorldStep)
  int iterations = 40;     ///< QuickStep iterations
  int rigid_substeps = 1;  ///< rigid_body `substeps` (ignored when the resolver has no such key)
  int electricity_substeps = 4;  ///< electricity `substeps`
  int induction_order = 1;       ///< electricity `induction_order` (1 or 2)
  bool joint_projection = true;  ///< rigid_body `joint_projection` (false: ODE's hinges alone)
  /// The plugin that provides `rigid_body`: ODE's "rigid_body" or "rigid_body.box2d" (which
  /// brings its own contact set; the ODE settings above are then unused).
  std::string engine = "rigid_body";
  /// magnetic_forces `near_field`: -1 leaves it unnamed (the engine's default,
  /// on), 0 names it false (every coil its pole pair), 1 names it true.
  int near_field = -1;
};

/// Whether the rigid body resolver accepts a `substeps` setting.
bool rigid_substeps_supported();

/// A world definition at step `dt` with the method's settings; `gravity`
/// false sets uniform gravity to zero.
WorldDef world_def(double dt, const Method& method, bool gravity = true);

/// One run of a scene.
struct Result {
  double error = 0;        ///< the scene's error measure (see each scene)
  double cpu_seconds = 0;  ///< CPU time of the stepping loop (no set-up, no reference)
  double sim_seconds = 0;  ///< simulated time covered
  std::uint64_t steps = 0;
  /// Largest |E - E0| / |E0| over the run (run_swing: per period, at one
  /// phase); < 0: not measured.
  double energy_drift = -1;
  /// run_swing: largest |E - E0| / E_swing within the run; < 0: not measured.
  double energy_wobble = -1;
  double momentum_drift = -1;  ///< largest |L - L0| / |L0| (angular momentum); < 0: not measured
  bool finite = true;          ///< no non-finite value was written (nor is the error one)
  double stretch =
      -1;  ///< largest relative change of a joint's length over the run; < 0: not measured
  double measured = 0;  ///< the scene's measured quantity (a period, s; a ratio), for reports
  double exact = 0;     ///< its closed-form value
  double cost() const { return sim_seconds > 0 ? cpu_seconds / sim_seconds : 0; }
};

// --- the scenes ----------------------------------------------------------------------
// Each run_* builds a fresh world, starts it (untimed), steps it for its
// simulated time while comparing with the reference, and returns the result.

/// A 0.1 m ball dropped from rest at 10 m for `seconds`; error: the largest
/// |y - (y0 - g t^2 / 2)| over the run, m. Semi-implicit Euler's error is
/// g t dt / 2: first order.
Result run_free_fall(double dt, const Method& m, double seconds = 1.0);

/// The 1 m bar pendulum of rigid_scenes (planar bar on a hinge) released at
/// theta0 rad; error: the largest |theta - theta_ref| over the run, rad, where
/// theta_ref is a fine RK4 of theta'' = -(m g d / I) sin theta.
Result run_pendulum(double dt, const Method& m, double theta0, double seconds = 5.0);

/// A free 0.3 x 0.2 x 0.1 m box (I1 < I2 < I3) spun near its intermediate
/// axis with no gravity: it flips over (Dzhanibekov) about 2 s in. Error: the largest rotation
/// angle between its orientation and a fine RK4 of Euler's equations with the
/// quaternion, rad; energy and angular-momentum drift of the run.
Result run_tumbling_box(double dt, const Method& m, double seconds = 3.0);

/// Two spheres (3 kg and 1 kg, 2 m apart, G = 20) on a circular orbit about
/// their centre of mass under gravity.nbody; error: |r - r_Kepler| / |r| of
/// the separation after `orbits` orbits; energy drift over the run.
Result run_orbit(double dt, const Method& m, int orbits = 2);
/// The orbit's period, s.
double orbit_period();

/// A battery (6 V, 0.1 Ohm) wired to a coil (60 mH, 5.9 Ohm) with 10 mOhm
/// wires (tau = 10 ms); error: the largest |I - E/R (1 - e^(-t/tau))| over
/// the run, relative to E/R. The rise decides the error; the run goes on to
/// `seconds` so that the cost is timed over more than a handful of steps.
Result run_rl(double dt, const Method& m, double seconds = 0.5);

/// Two permanent bar magnets (10 x 2 x 2 cm, 20 A*m poles) on the x axis with
/// like poles facing, no gravity: one has no mass (it stays), the other
/// (50 g, 12 cm away) is pushed away along x. Error: the largest |x - x_ref|
/// over the run, m, where x_ref is a fine RK4 of m x'' = F(x) with F the pole
/// model's softened force law written out here.
Result run_magnets(double dt, const Method& m, double seconds = 1.0);

/// The magnet and the air-cored coil of the induction scenes (run_induction,
/// tests/coupled): the magnet's poles +-kInductionQ, kInductionPoles apart;
/// the coil's coil_factor and pole separation, whose current sheet has radius
/// sqrt(k d / pi) = 2.76 cm (docs/magnetism.md "A coil's near field").
constexpr double kInductionQ = 100, kInductionPoles = 0.017;               // A m, m
constexpr double kInductionCoilFactor = 0.06, kInductionCoilPoles = 0.04;  // m, m
constexpr double kInductionTurns = 4000;                                   ///< run_induction's coil

/// The flux linkage (Wb) of that coil (centre at the origin, axis +x,
/// `turns` turns) from the magnet with its centre at x on the axis, north
/// towards +x, written out from closed forms: with `near_field` the sheet's
/// flux on the axis, sum over the poles of mu0 N q / (2 l) (G(l/2 - z) -
/// G(l/2 + z)), G(u) = |u| - sqrt(u^2 + a^2), plus the magnet's own flux
/// mu0 (N / l) q L through the turns its segment crosses (L the length of
/// the segment inside the winding), blended into the pole pair's softened
/// flux over the engine's near zone (solenoid_field.hpp); without, the pole
/// pair's (flux_linkage.hpp).
double induction_flux(double x, double turns, bool near_field = true);
/// d induction_flux / dx (Wb/m), a central difference of it.
double induction_gradient(double x, double turns, bool near_field = true);
/// Where |induction_gradient| is largest on the axis at x < 0 (a scan at
/// 10 um), and the gradient there: {x, dPhi/dx}.
std::pair<double, double> induction_steepest(double turns, bool near_field = true);

/// Induction (issue 13): a 0.5 kg magnet (the above) flies at 0.5 m/s along
/// the axis of a fixed coil of `turns` turns (L = 10 mH, closed on itself:
/// 3.01 Ohm) from 0.4 m before its centre and through it; the EMF -dPhi/dt
/// drives a current whose field brakes the magnet (with 4000 turns to 0.17
/// m/s). It starts that far off so that the current's start (the EMF of the
/// first step, ramped from 0: first order in the step) stays well under the
/// coupling's error; from 0.2 m it was 1.7e-4 of the peak at 1/1920 s. Reference: fine
/// RK4 of the coupled ODE m v' = I dPhi/dx, L I' + R I = -dPhi/dx v, Phi =
/// induction_flux (the sheet's unless the method names near_field false).
/// Error: largest |I - I_ref| / max |I_ref| at the steps' ends. Also sets
/// `measured` to the magnet's speed at the end and `exact` to the
/// reference's; `current`, when given, receives the coil's current after
/// each step.
Result run_induction(double dt, const Method& m, double seconds = 1.2,
                     double turns = kInductionTurns, std::vector<double>* current = nullptr);

// --- closed-form cases (issue 12) ------------------------------------------------------
// Each returns the error against a closed form; the tests in
// tests/resolvers/rigid_body/closed_form_test.cpp hold them at 1/240 s and
// check that they converge.

/// Two 10 cm steel-like balls (restitution 1, no gravity, no friction) meet
/// head on at 1 m/s: `ratio` kg moving onto 1 kg at rest. Error: the largest
/// |v' - v'_exact| of the two, m/s, 0.3 s after the start (the impact is at
/// 0.1 s). Closed form v1' = (r - 1) / (r + 1), v2' = 2 r / (r + 1).
Result run_elastic_pair(double dt, const Method& m, double ratio);

/// Newton's cradle without strings: 5 touching steel balls (r = 2.5 cm,
/// restitution 1) in a row, no gravity, the first 1 cm away moving at 1 m/s.
/// Error: the largest |v_i - v_exact_i| after 0.2 s, m/s, where the exact
/// answer is (0, 0, 0, 0, 1); energy drift of the kinetic energy.
Result run_cradle(double dt, const Method& m);

/// A 0.1 m ball dropped 1 m onto a static floor with restitution e. Error:
/// |h1 / h0 - e^2| / e^2 of the first rebound's height h1 (measured = h1 / h0).
Result run_bounce(double dt, const Method& m, double e);

/// A pendulum released from rest at theta0 rad: `lever` true, a 2 cm steel
/// ball (2 cm radius) hinged 1 m from its centre (a small body on a long lever); false, the
/// 1 m bar of rigid_scenes. Planar, as the kit's parts. Error: the relative
/// period error |T - T_exact| / T_exact, T from the upward zero crossings
/// over `periods` periods and T_exact = 4 sqrt(I / (m g d)) K(sin(theta0 / 2));
/// stretch: the largest |pivot-to-centre distance - d| / d (not `planar`:
/// also the centre's distance from the plane z = 0 over d, and the tilt of
/// the body's z axis, rad: the hinge then holds its axis by itself);
/// energy_drift: the largest |E_k - E_0| / (k E_swing) of the energies E_k
/// at the k-th upward pass through the bottom (E_swing = m g d (1 - cos
/// theta0)): the drift per period; energy_wobble: the largest |E - E0| /
/// E_swing at any step, the step's O(h) swing of the energy about its mean.
Result run_swing(double dt, const Method& m, bool lever, double theta0, int periods = 2,
                 bool planar = true);
/// The exact period of run_swing's pendulum, s.
double swing_period(bool lever, double theta0);

/// A chain of 5 light links (10 g, 10 cm, hinged end to end) holding a 10 kg
/// ball (1000:1), hanging from the play area and released 60 degrees from
/// the vertical. Error (and stretch): the largest gap summed over the
/// hinges, relative to the chain's length, over 3 s; energy_drift: the
/// largest change of the bodies' energy from its value after the first
/// step, over the ball's swing m g L (1 - cos 60 degrees).
Result run_heavy_chain(double dt, const Method& m);

// --- references (exposed for tests) -----------------------------------------------------

/// theta at times 0, dt, ..., n dt of theta'' = -k sin theta, theta(0) = theta0,
/// theta'(0) = 0, by RK4 with at most `h` per substep.
std::vector<double> pendulum_reference(double k, double theta0, double dt, std::size_t n,
                                       double h = 1e-4);

/// The axial force on the free magnet at centre x from the fixed one at the
/// origin (like poles facing), N: the pole model's four pole pairs.
double magnet_force(double x);

/// The complete elliptic integral of the first kind K(k), by the
/// arithmetic-geometric mean.
double elliptic_k(double k);

}  // namespace alloy::scenes::analytic

namespace alloy::scenes::analytic {

// --- rolling (issue 12, the kit's cylinder) ----------------------------------------------

/// The slope of run_rolling, rad (20 degrees).
inline constexpr double kRollSlope = 0.3490658503988659;

/// A planar part of radius 5 cm released from rest on a static 20 degree
/// slope (friction 0.5, enough to roll without slipping), rolling for 1 s:
/// `cylinder` true, a disk (shape cylinder, 2 cm thick, axis out of the play
/// area), a = 2/3 g sin(theta); false, a ball (shape sphere), 5/7 g sin(theta).
/// measured: the mean acceleration along the slope over the run (its speed
/// down the slope at the end over the time) divided by g sin(theta); exact:
/// 2/3 or 5/7; error: |measured / exact - 1|. stretch: the largest slip of
/// the rim, |v + w x r| / |v| at the contact, over the last half of the run.
Result run_rolling(double dt, const Method& m, bool cylinder);

}  // namespace alloy::scenes::analytic
