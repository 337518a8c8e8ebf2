// The (Electricity <- Magnetism) interaction: Faraday's law. Every step, for
// each electromagnet that is also a coil of a circuit (carries `inductance`),
// the flux linking it from every other magnetic part (permanent magnets,
// other electromagnets, magnetised iron: the poles of the `magnetic_forces`
// set) and its rate along the parts' present motion (flux_linkage.hpp); the
// EMF -dPhi/dt is queued on the electricity resolver, which adds it to the
// coil's branch in its next advance. With magnetism_from_electricity (the
// current makes the coil a magnet) and rigid_body_from_magnetism (the
// magnet's force moves the parts) it closes the loop of a motor and a
// generator: the work the coil's field does on the parts is the energy the
// EMF takes from the circuit (Lenz).
//
// The EMF is queued for the end of the coming step, the parts moved on to
// it (docs/magnetism.md "The coupling's timing"). The rigid body's velocity
// after its step is the one that moved the parts over it (semi-implicit
// Euler): the velocity half a step back, not the present one. Held for the
// coming step it puts the EMF 1.5 steps behind the motion, an error of
// 1.5 dt a in every velocity, first order in the step (the induction row's
// order 0.7). So each part's acceleration is estimated from its velocity of
// the last step (a = (v_n - v_(n-1)) / dt, kept here and saved with the
// stage) and the parts move on with v + a dt over the step, ending at
// v + 1.5 a dt: second order. The estimate is used only when the velocity
// changed in each of the last two steps (the rigid body advanced in both:
// with `every = {rigid_body = n}` the velocity jumps once in n steps and the
// EMF keeps the present velocity, as before) and the acceleration is within
// half of the step before's (not a contact's impulse or a hand's push).
//
// Soft iron (induction order 2): the iron's moments change as the parts
// move, and that change is in the EMF: the step's flux change adds the
// flux of the iron's poles solved again at the poses predicted for the
// step's start and end, at the currents of now, the coils' own share at
// half (MagneticForces::emf_iron_poles; docs/magnetism.md "Induction
// through soft iron"). The iron's inductance stays out of the circuit.
//
// Contract:
//   reads    the magnetic_forces derived set (its poles), magnet, turns,
//            coil_factor, pole_separation, inductance, position, orientation,
//            velocity, angular_velocity and the shape (for the defaults);
//            mass, static, pinned and the coil's resistance (the
//            strong-coupling check, below)
//   emits    induction_coupling_strong (once per coil and part)
//   target   electricity (set_induced_emf, set_mutual_inductance)
//   needs    magnet
// The coil's own current is not a source here: its self-inductance is the
// circuit's `inductance`. Changes of other coils' currents (a transformer)
// enter as each pair's mutual inductance (flux_linkage.hpp), queued with
// set_mutual_inductance and solved implicitly by electricity.
#pragma once

#include <optional>
#include <vector>

#include "resolvers/magnetism/flux_linkage.hpp"
#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"

namespace alloy::electricity {
class ElectricityResolver;
}

namespace alloy::magnetism {

class ElectricityFromMagnetism : public Interaction {
 public:
  /// Plugin name.
  static constexpr const char* kName = "electricity_from_magnetism";

  ElectricityFromMagnetism(electricity::ElectricityResolver& target, const MagneticForces& forces)
      : target_(target), forces_(forces) {}
  void apply(const WorldView& world) override;
  /// The velocities of the last two applies (the acceleration's history).
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  /// One coil's flux linkage and rate as of the last apply.
  struct CoilFlux {
    ObjectId id;
    FluxLinkage linkage;
  };
  /// Every coil of the last apply (tests, tools).
  const std::vector<CoilFlux>& coils() const { return coils_; }
  /// The coil `id` as of the last apply, or nullptr.
  const CoilFlux* find(ObjectId id) const;
  /// A pair of coils and their mutual inductance, as queued in the last apply.
  struct CoilPair {
    ObjectId a, b;
    double mutual_inductance;  ///< H
  };
  const std::vector<CoilPair>& mutual_inductances() const { return mutuals_; }

  /// A part's velocity as one apply saw it.
  struct Seen {
    ObjectId id;             ///< the part (null: none recorded in this slot)
    std::uint64_t step = 0;  ///< WorldView::step() of that apply
    Vec3 velocity;           ///< m/s
    Vec3 spin;               ///< rad/s
    bool changed = false;    ///< the velocity differed from the apply one step before
    bool rated = false;      ///< changed in this step and the one before: `acceleration` is set
    Vec3 acceleration;       ///< (velocity - the step before's) / dt, m/s^2 (when rated)
    Vec3 angular;            ///< the same of the spin, rad/s^2
  };
  /// A part's motion over the coming step, as the EMF takes it.
  struct Motion {
    Vec3 velocity, spin;         ///< now (the rigid body's, after its step)
    Vec3 acceleration, angular;  ///< estimated from the last step (0 without history)
    bool changed = false;        ///< the velocity differs from the apply one step before
  };
  /// The motion of `slot` (its velocity `v`, spin `w` now) at step `step`:
  /// records it (once per step; a second apply in the same step, the
  /// priming after a restore, reads the same history) and estimates the
  /// acceleration from the step before. `record` false: estimates only (a
  /// fresh stage's priming apply).
  Motion motion(ObjectId id, std::uint64_t step, double dt, Vec3 v, Vec3 w, bool record = true);

  /// The strong-coupling check (docs/energy.md "Limits"): a closed coil and a
  /// free magnetic part whose per-step loop gain
  ///   g = (G^2 / m) dt (1 - exp(-R dt / L)) / R
  /// reaches kStrongCouplingGain, G the flux gradient along the part's
  /// translation (Wb/m), 1/m the sum of the free parts' inverse masses, R and L
  /// the coil's own resistance and inductance (a lower bound on the loop's
  /// resistance, so the gain is an upper bound). g is the velocity the part
  /// loses in one step from the current its own velocity induces, as a
  /// fraction of that velocity (G^2/(m R) dt when L/R << dt, G^2 dt^2/(m L)
  /// when L/R >> dt): the coupling, one step late by the method, overshoots
  /// and creates energy as it nears 1 (measured, a 15 g magnet dropped into
  /// a closed 3 Ohm coil: thrown back up at g = 0.67 at 1/240 s; braked
  /// without rising at 0.58 and 0.34, 1/1293 and 1/1920 s). Reported once per coil and part, as the
  /// event `induction_coupling_strong` (a = the coil, b = the part; values gain, gradient Wb/m,
  /// mass kg, resistance Ohm, inductance H, dt s, and dt_suggested s, the step that brings the gain
  /// to kStrongCouplingGain / 2).
  static constexpr double kStrongCouplingGain = 0.5;
  struct StrongCoupling {
    ObjectId coil, part;
    double gain = 0;  ///< the largest g seen for the pair
  };
  /// The pairs reported so far (tests, tools), with the largest gain seen.
  const std::vector<StrongCoupling>& strong_couplings() const { return strong_; }
  /// The largest per-step gain of any closed coil and free part, this run.
  double largest_coupling_gain() const { return largest_gain_; }
  /// A step's chord of the flux that misses the trapezoid of its rates by
  /// more than half the larger and more than this share of the flux is a
  /// jump of the flux model, not motion (docs/magnetism.md "The coupling's
  /// timing", session 20): that step's EMF is the ramp of rates alone.
  static constexpr double kFluxJump = 0.05;
  /// ... and by more than this, Wb (below it the fluxes are rounding: a part
  /// at rest, a coil far away; an EMF of 2.4e-10 V at 1/240 s).
  static constexpr double kFluxJumpFloor = 1e-12;
  /// Steps x coils whose flux jumped (the ramp alone was sent), this run.
  std::uint64_t flux_jumps() const { return flux_jumps_; }

 private:
  electricity::ElectricityResolver& target_;
  const MagneticForces& forces_;
  std::vector<CoilFlux> coils_;
  std::vector<CoilPair> mutuals_;
  std::vector<Vec3> pole_velocity_;
  std::vector<Vec3> pole_velocity_end_;  // the poles' velocities one step on (scratch)
  std::vector<Pole> moved_poles_;        // the poles one step on (scratch)
  std::vector<Pole> predicted_poles_;    // the poles where the last apply put them (scratch)
  // With soft iron (scratch): the poles' fixed shares now, and the induced
  // poles the EMF integrates at the step's predicted start and end
  // (MagneticForces::emf_iron_poles).
  std::vector<Pole> fixed_now_, iron_start_, iron_end_;
  // Per slot: the last apply's velocities and the ones of the apply before.
  std::vector<Seen> latest_, earlier_;
  /// Where an apply (induction_order 2) moved the parts on to for the
  /// coming step's end: the poles' positions and their parts, and each
  /// coil's centre and axis. The next apply takes the step's flux change
  /// from there, not from where the parts really are, so that the circuit's
  /// integrated EMF follows the parts' predicted path without a gap between
  /// steps (docs/magnetism.md "The coupling's timing"). The last apply's,
  /// and the one before (a repeated apply, the priming after a restore,
  /// starts from that one, as the first did). Saved with the stage.
  struct Prediction {
    std::uint64_t step = 0;  ///< WorldView::step() of the apply that made it
    bool made = false;
    std::vector<Vec3> pole_position;
    std::vector<std::uint32_t> pole_body;
    std::vector<ObjectId> bodies;
    struct Coil {
      ObjectId id;
      Vec3 centre, axis;
    };
    std::vector<Coil> coils;
    /// Each body's predicted pose (only with soft iron: the iron is solved
    /// again at the poses, MagneticForces::emf_iron_poles).
    std::vector<MagneticForces::PartPose> poses;
  };
  Prediction prediction_, earlier_prediction_;
  bool first_apply_ = true;  // no apply yet (nor a restored history)
  std::optional<MagnetColumns::Ids> ids_;
  PropertyRef inductance_{"inductance"}, velocity_{"velocity"}, spin_{"angular_velocity"};
  PropertyRef mass_{"mass"}, static_{"static"}, pinned_{"pinned"}, resistance_{"resistance"};
  std::vector<StrongCoupling> strong_;
  std::uint64_t flux_jumps_ = 0;
  double largest_gain_ = 0;
  /// Checks coil `coil` (geometry `g`, its own inductance `inductance`)
  /// against every free part with poles; emits the event for a new pair.
  void check_coupling(const WorldView& world, ObjectId coil, const CoilGeometry& g,
                      double inductance);
};

/// Registers electricity_from_magnetism (after the magnetism and electricity
/// plugins, whose set and resolver it joins).
void register_electricity_from_magnetism(PluginRegistry& registry);

}  // namespace alloy::magnetism
