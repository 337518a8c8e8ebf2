// A coil's near field as a finite solenoid (docs/magnetism.md "A coil's near
// field").
//
// Far away a coil is its pole pair (flux_linkage.hpp): +-k N I at the ends of
// its axis, d apart. That pair is the far field of a current sheet of N turns
// on radius a and length l = d with pi a^2 = k d: the sheet is a uniformly
// magnetised cylinder (M = n I, n = N / l), whose H is the field of two end
// disks of pole density +-n I, and whose B inside the bore is mu0 (H + n I).
// The pole pair collapses each disk to its centre and drops the n I inside, so
// inside the bore its field points backwards and a magnet there links flux of
// the wrong sign.
//
// The flux a coil links per ampere from a point pole q at p, counting each
// turn's flux through its flat disk (solid angle Omega), is
//
//   q psi_sheet(p),  psi_sheet(p) = (n / l_unit) int mu0 Omega / (4 pi) dz
//                                 = n mu0/(4 pi) (D_south(p) - D_north(p))
//
// D(p) = int_disk dA / |p - x| the potential of a unit-density end disk (the
// solid angle is the disk potential's axial derivative). psi_sheet is smooth
// in p; its gradient is H / I (the disks' field), not B / I. A magnet (a pole
// pair q at N_b, -q at S_b: a line of dipoles from S_b to N_b) also carries its
// own B through every turn whose disk its segment crosses: the "string" term
//
//   q mu0 n L(S_b, N_b),  L = the segment's signed length along the coil's axis
//                             inside the bore (radius a, |z| < l / 2).
//
// Its gradient is q mu0 n (chi(N_b) - chi(S_b)) along the axis (chi: inside the
// bore), which turns each pole's H force into its B force. Pole sum plus
// strings is the B-flux of the magnet through the turns: a magnet on the axis
// inside a long coil links mu0 n m, as it should.
//
// As a correction on the pole pair: within a near zone around the coil (the
// bore and a margin off its ends and side) a pole's per-ampere flux is
// psi_pair + w (psi_sheet - psi_pair), w a C2 window that is 1 in the zone and
// 0 beyond its margin; the strings are added unwindowed (they vanish unless a
// segment enters the bore, well inside the zone). Every gradient here is the
// exact gradient of the value (the window's included), so force = I grad Phi
// and the energy the EMF moves equals the work the force does.
#pragma once

#include <cstdint>
#include <span>

#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "runtime/math.hpp"

namespace alloy::magnetism {

/// A coil as a current sheet, in the world frame.
struct Solenoid {
  Vec3 centre;                 ///< m, world: the middle of the winding
  Vec3 axis;                   ///< unit vector from its south to its north end
  double length = 0;           ///< l, m: the pole separation
  double radius = 0;           ///< a, m: sqrt(k l / pi) for coil factor k
  double turns_per_metre = 0;  ///< n = N / l, 1/m
};

/// The sheet's radius from the pole model's coil factor k (m) and pole
/// separation d (m): pi a^2 = k d, so the sheet's end disks carry the pole
/// pair's strength and its far field is the pair's. 0 when either is not > 0.
double solenoid_radius(double coil_factor, double separation);

/// The sheet radius of the electromagnet at `slot` (coil factor k, pole
/// separation d): solenoid_radius(k, d), unless the part has a shape whose
/// half-width across its axis is less than that (by 5 %): then k carries an
/// iron core's enhancement (the kit's cored coils: k = (A + chi A_core) / d),
/// the coil is not a current sheet of that radius, and 0 keeps its pole pair.
double coil_sheet_radius(const MagnetColumns& c, std::uint32_t slot, double coil_factor,
                         double separation);

/// D = int over the disk (radius a, centre 0, normal z) of dA / |p - x| at the
/// point (rho, z), m; with its partial derivatives d/drho and d/dz (unitless)
/// when the pointers are given. Quadrature in the ring radius (each ring's
/// potential in closed form, complete elliptic integrals), split and graded at
/// r = rho so that a point near the disk's plane stays accurate.
double disk_potential(double a, double rho, double z, double* d_rho = nullptr,
                      double* d_z = nullptr);

/// A per-ampere, per-unit-pole flux and its gradient in the pole's position.
struct PoleLinkage {
  double flux = 0;  ///< Wb / (A * A m)
  Vec3 gradient;    ///< d flux / d p, Wb / (A * A m * m)
};

/// The pole pair's per-ampere flux from a unit pole at p (softened like the
/// force law), psi_pair = k N mu0/(4 pi) (1/s(S - p) - 1/s(N - p)).
PoleLinkage pair_linkage(const Solenoid& coil, double softening, Vec3 p);

/// The sheet's per-ampere flux from a unit pole at p (unsoftened), psi_sheet.
PoleLinkage sheet_linkage(const Solenoid& coil, Vec3 p);

/// The near-zone window at p: 1 within 2a of the axis and l/2 + 2a of the
/// centre along it, fading (C2) to 0 over 3 more radii beyond that box.
struct Window {
  double value = 0;  ///< w in [0, 1]
  Vec3 gradient;     ///< dw / dp, 1/m
};
Window near_window(const Solenoid& coil, Vec3 p);

/// w (psi_sheet - psi_pair) at p and its gradient; exactly 0 (and cheap)
/// outside the zone.
PoleLinkage near_correction(const Solenoid& coil, double softening, Vec3 p);

/// The string term of a pole pair from `south` to `north`, per ampere per unit
/// pole strength: mu0 n L and its gradients in the two ends.
struct StringLinkage {
  double flux = 0;     ///< Wb / (A * A m)
  Vec3 grad_north;     ///< d flux / d north
  Vec3 grad_south;     ///< d flux / d south
  double overlap = 0;  ///< L, m: signed axial length of the segment inside the bore
};
StringLinkage string_linkage(const Solenoid& coil, Vec3 south, Vec3 north);

/// Mutual inductance of two coils as sheets, H, symmetric: the mean of a's
/// sheet linking b's poles and strings and b's sheet linking a's (each with
/// the pole pair outside the zone). Positive for coaxial coils wound the same
/// way at every overlap.
double sheet_mutual_inductance(const Solenoid& a, const Solenoid& b, double softening);

/// Self-inductance of a coil as the same model sees it (its own poles and
/// string in its own sheet), H: mu0 n^2 pi a^2 l minus the end disks' share.
double sheet_self_inductance(const Solenoid& coil);

/// A coil whose sheet acts on the poles near it (magnetic_forces): the sheet
/// with turns_per_metre 1 / (pi a^2), so that `strength` (the coil's own pole
/// strength k N I, A m) stands for the current.
struct NearCoil {
  Solenoid sheet;
  double strength = 0;     ///< A m
  std::uint32_t body = 0;  ///< the coil's body index in the poles
};

/// The near-field correction's forces: on each pole of a body with
/// sheet_body[body] != 0 (its north pole first, its south next) from every
/// coil in `coils`, strength q_coil q_pole grad(near_correction) plus the
/// string's, added to pole_force; each coil's reaction (force, and torque about
/// its sheet's centre) added to body_force / body_torque at its body. The
/// correction's energy is -strength sum (q w (psi_sheet - psi_pair) + strings),
/// so these are its exact negative gradient.
void add_near_forces(std::span<const NearCoil> coils, std::span<const Pole> poles,
                     std::span<const std::uint8_t> sheet_body, double softening,
                     std::span<Vec3> pole_force, std::span<Vec3> body_force,
                     std::span<Vec3> body_torque);

}  // namespace alloy::magnetism
