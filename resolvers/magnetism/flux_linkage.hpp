// Faraday's law on the pole model: the flux that links a coil, and its rate as
// the parts move, from the same poles and the same softened kernel that give
// the magnetic forces (pole_model.hpp), so that the work the field does on the
// parts and the energy the induced EMF moves in the circuits are one quantity
// seen from two sides (docs/magnetism.md "Induction").
//
// An electromagnet is a bar whose coil current I gives it poles +-q, q = k N I
// (k its coil_factor, N its turns), at c +- (d/2) a. Its interaction energy
// with every other pole p of strength q_p is
//
//   U = sum_p mu0/(4 pi) q q_p (1/s(N - p) - 1/s(S - p)),  s(r) = sqrt(|r|^2 + eps^2)
//     = -I Phi,   Phi = k N (psi(S) - psi(N)),   psi(x) = mu0/(4 pi) sum_p q_p / s(x - p)
//
// psi is mu0 times the magnetic scalar potential (T m), so psi(S) - psi(N) is
// the line integral of B from the coil's south pole to its north pole, and
// Phi ~ N A B_axial for a field uniform over the coil (k = A / d). Phi is the
// coil's flux linkage (Wb-turns) from every pole but its own, signed so that a
// positive current's own field links it positively (self-inductance > 0).
//
// The force on any other part from the coil's current is -grad U = I grad Phi,
// and the EMF induced in the coil (from terminal 0 to 1, the direction of
// positive current) is -dPhi/dt. Along a motion with velocities u:
// power into the parts from the coil = I dPhi/dt = -EMF I, the power the EMF
// takes out of the circuit. That is the energy balance, exact in continuous
// time, whatever the softening.
#pragma once

#include <cstdint>
#include <span>

#include "resolvers/magnetism/pole_model.hpp"
#include "runtime/math.hpp"

namespace alloy::magnetism {

/// psi(x) = mu0/(4 pi) sum q_p / sqrt(|x - p|^2 + eps^2) over every pole whose
/// body is not `exclude_body`, T*m: mu0 times the magnetic scalar potential.
double pole_potential(std::span<const Pole> poles, double softening, Vec3 x,
                      std::uint32_t exclude_body);

/// A coil as Faraday's law sees it: where its two poles are and how they move.
struct CoilGeometry {
  Vec3 centre;                   ///< m, world
  Vec3 axis;                     ///< unit vector from its south to its north pole (local +x)
  double separation = 0;         ///< pole separation d, m
  double linkage = 0;            ///< k N: pole strength per ampere, m (coil_factor x turns)
  Vec3 velocity;                 ///< of its centre, m/s
  Vec3 angular_velocity;         ///< rad/s, world
  std::uint32_t body = kNoBody;  ///< its own body index in `poles` (its poles are skipped)
  /// Its sheet's radius a, m (solenoid_radius(k, d)); 0: the pole pair only.
  double radius = 0;
  /// Per body index of `poles`: 1 where the sheet's near field applies
  /// (MagneticForces::sheet_bodies(): permanent magnets), the same bodies the
  /// forces correct; empty: none. A body's poles are north, then south.
  std::span<const std::uint8_t> sheet_bodies;
};

struct FluxLinkage {
  double flux = 0;  ///< Phi, Wb (weber-turns)
  double rate = 0;  ///< dPhi/dt along the present motion, pole strengths held, Wb/s
};

/// Phi and dPhi/dt of `coil` from `poles`, whose velocities are
/// `pole_velocity[i]` (m/s). With a radius and sheet bodies, the poles of those
/// bodies near the coil link the finite solenoid's flux (solenoid_field.hpp:
/// the pole pair plus the windowed sheet correction plus each pole pair's
/// string through the bore), the flux whose gradient the forces use.
/// Otherwise the pole pair's.
/// The rate is exact (the kernel's gradient, the sheet's), so
/// rate = sum over moving points of the flux's gradient times their velocity.
FluxLinkage coil_flux(std::span<const Pole> poles, std::span<const Vec3> pole_velocity,
                      double softening, const CoilGeometry& coil);

/// Mutual inductance of coils a and b, H: the flux linking a (coil_flux)
/// from b's poles carrying one ampere (+-k_b N_b at b's ends), with a's own
/// poles at theirs. The pole model makes it symmetric, M_ab = M_ba:
///   M = k_a N_a k_b N_b mu0/(4 pi) (1/s(S_a - N_b) - 1/s(S_a - S_b) - 1/s(N_a - N_b) + 1/s(N_a -
///   S_b)).
/// The EMF a change of b's current induces in a is -M dI_b/dt (the
/// electricity resolver solves it with the coils' companions); the motion
/// part, I_b dM/dt, is already in coil_flux's rate.
double mutual_inductance(const CoilGeometry& a, const CoilGeometry& b, double softening);

}  // namespace alloy::magnetism
