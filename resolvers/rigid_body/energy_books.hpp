// The rigid body's energy books, whichever engine keeps them (docs/energy.md,
// "The rigid body"): ODE's (rigid_body_energy.cpp) and Box2D's
// (resolvers/rigid_body_box2d/box2d_energy.cpp) book the same accounts under
// the same names, so that the ledger's transfers pair up with the stages
// that queued the loads, and a swap of engines changes no account's meaning.
//
// Per substep an engine takes the kinetic energy before and after its drag
// (drag), after its collision impulses (restitution), and after its step.
// Each queued load's work is taken two ways: along the step's displacement
// (the transfer, which for a uniform field is minus the change of its
// potential) and along the mean velocity, h F . (v + v') / 2 (the kinetic
// energy the load alone gives under the semi-implicit step). The difference
// is the integrator's share; what the kinetic energy did not receive of the
// second is the contacts' and joints': a residue, not a measured force's
// work. The books close by construction.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/energy_ledger.hpp"
#include "runtime/math.hpp"

namespace alloy::rigid {

struct EnergyBooks {
  /// Sums since the last report, J.
  double drag = 0, restitution = 0, integration = 0, contacts = 0;
  std::vector<std::pair<std::string, double>> work;  // per transfer name
  /// Per transfer: booked along the mean velocity (the `magnetism` loads,
  /// paired with the circuits' trapezoidal EMF work) instead of along the
  /// step's displacement (a potential's loads, paired with its change).
  std::vector<bool> along_mean;
  /// A load of this substep: its body (the engine's index), force, torque,
  /// lever arm (from the body's centre of mass at the substep's start), its
  /// account (index into work), and where it acts, in the world at the
  /// start and in the body's frame (in the engine's units).
  struct Applied {
    std::uint32_t body;
    Vec3 force, torque, arm;
    std::uint32_t source;
    Vec3 at, local;
  };
  std::vector<Applied> applied;
  std::vector<Vec3> v0, w0;  // per body, at the substep's start (after drag and collisions)

  /// The transfer account of the loads queued by `stage`, named after the
  /// physics whose stage it is (rigid_body_from_gravity@moon -> gravity), so
  /// that the stage on the other side can report the same name.
  std::uint32_t account(const std::string& stage);
  /// Books a load's work over a substep of length h: `along_step` its work
  /// along the step's displacement (the transfer, but for the accounts
  /// booked along the mean), and along the mean of the body's velocities
  /// v0, w0 (at the substep's start) and v1, w1 (its end). Returns the
  /// second, for close_substep.
  double book_load(const Applied& a, double along_step, double h, Vec3 v1, Vec3 w1);
  /// Books a load's work along a move of its body with no velocity (a
  /// restitution pass's move to the time of impact, a sweep's move back):
  /// with the integrator's share, or nothing for an account booked along
  /// the mean velocity (such a move gives no kinetic energy).
  void book_move(const Applied& a, double moved) {
    if (along_mean[a.source]) return;
    work[a.source].second += moved;
    integration += moved;
  }
  /// Closes a substep: the loads' work along the mean velocity (book_load's
  /// sum) against the kinetic energy's change over the step (after drag and
  /// collisions to the end): what it did not receive is the contacts' and
  /// joints'.
  void close_substep(double along_mean, double kinetic_change) {
    contacts += along_mean - kinetic_change;
  }
  /// Hands the sums since the last report to the ledger, and starts again
  /// from zero; `kinetic` is the store's level now.
  void report(double kinetic, EnergyReport& out);
};

}  // namespace alloy::rigid
