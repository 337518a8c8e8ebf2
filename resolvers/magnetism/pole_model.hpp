// The magnetic pole model (Gilbert model), free of any world or property: the
// physics of docs/magnetism.md in plain functions, so that it can be tested
// against closed forms, and its summation chosen (direct or tree) without
// touching the stages.
//
// A magnetic part is a bar whose magnetisation is represented by two point
// poles of strength +q (north) and -q (south) on its local x axis. A pole of
// strength q (A*m) at p makes the field
//
//   H(x) = q / (4 pi) * K(x - p),   B = mu0 H,   K(r) = r / (|r|^2 + eps^2)^(3/2)
//
// and a pole q2 at x feels F = mu0 q2 H(x). K is the Plummer-softened inverse
// square: for |r| >> eps it is r_hat / |r|^2 exactly, it stays finite (at most
// 2 / (3 sqrt(3) eps^2)) when poles touch, and it is the gradient of the
// potential 1 / sqrt(|r|^2 + eps^2), so softened forces still conserve energy
// and obey Newton's third law pair by pair.
#pragma once

#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "resolvers/common/fmm.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "runtime/math.hpp"

namespace alloy::magnetism {

/// Vacuum permeability, N/A^2 (CODATA 2018).
inline constexpr double kMu0 = 1.25663706212e-6;
/// mu0 / (4 pi), N/A^2: the constant of the pole force law.
inline constexpr double kMu0Over4Pi = kMu0 / (4.0 * std::numbers::pi);
/// Saturation magnetisation of soft iron, A/m (mu0 Ms = 2.15 T).
inline constexpr double kIronSaturationMagnetization = 1.71e6;
/// Effective poles of a bar magnet sit about L/12 inside its ends, so the
/// default pole separation is this fraction of the bar's length.
inline constexpr double kMagneticLengthRatio = 0.85;
/// Soft iron's induced poles sit on its faces: a uniformly magnetised body's
/// pole density is M.n on its surface, and the field of a nearby pole draws
/// it to the near face. Its far field is the same either way (the moment is
/// solved first and spread over the separation).
inline constexpr double kInducedLengthRatio = 1.0;

/// One point pole.
struct Pole {
  Vec3 position;           ///< world position, m
  double strength = 0;     ///< A*m; > 0 north (drawn red), < 0 south (drawn green)
  std::uint32_t body = 0;  ///< index of the part it belongs to; a part never acts on itself
};

/// The softened inverse-square kernel K(r) = r / (|r|^2 + eps^2)^(3/2), 1/m^2 along r.
inline Vec3 softened_kernel(Vec3 r, double softening) {
  const double s2 = dot(r, r) + softening * softening;
  if (s2 <= 0) return {};  // coincident poles with no softening: no direction, no force
  return r * (1.0 / (s2 * std::sqrt(s2)));
}

/// Force on pole 2 (strength q2 at x2) from pole 1 (q1 at x1), N. Like poles repel.
inline Vec3 pole_pair_force(double q1, Vec3 x1, double q2, Vec3 x2, double softening) {
  return softened_kernel(x2 - x1, softening) * (kMu0Over4Pi * q1 * q2);
}

/// Where the poles of a bar are: +q at centre + (d/2) axis, -q at centre - (d/2) axis.
struct BarPoles {
  Vec3 north, south;
};
inline BarPoles bar_poles(Vec3 centre, Vec3 axis, double separation) {
  const Vec3 half = axis * (0.5 * separation);
  return {centre + half, centre - half};
}

// --- summation -----------------------------------------------------------------
// Every pole-pair sum of the resolver goes through these two functions: the
// direct O(P^2) sum, or the Barnes-Hut tree of resolvers/common/multipole_tree.hpp
// (O(P log P), error set by theta; docs/magnetism.md "Summation").

enum class Summation : std::uint8_t {
  Direct,  ///< every pair, exactly
  Tree,    ///< Barnes-Hut octree, cells expanded to the octupole
  /// Direct below kFmmAutoPoles poles; from there the FMM, checked against
  /// the direct sum on a sample of parts (kAutoCheckEvery, magnetic_forces.hpp),
  /// and the tree (Direct below kTreeCrossoverPoles) where the check finds the
  /// FMM's error above SummationOptions::tolerance.
  Auto,
  /// The fast multipole method (multipole/fmm.hpp): cell-to-cell expansions of
  /// order fmm_order, theta its separation parameter. Faster than the tree on
  /// spread-out magnets, far less accurate on packed blocks at the same
  /// settings (docs/magnetism.md "Fast summation"): opt-in.
  Fmm,
};

/// Number of poles from which the tree is faster than the direct sum at the
/// default tolerance, measured by bench/scaling.cpp --magnets (docs/performance.md
/// "Magnetic forces": the blocked tree with SIMD near field against the SIMD
/// direct sum crosses near 1,100 magnets, 2,200 poles; issue 16 asks for 500).
inline constexpr std::size_t kTreeCrossoverPoles = 2200;
/// Number of poles from which Auto takes the FMM (with its check) instead of
/// the direct sum: the FMM at its defaults is faster than the SIMD direct sum
/// from 370-450 magnets (bench/scaling.cpp --magnets, session 17-18).
inline constexpr std::size_t kFmmAutoPoles = 800;
/// From this many poles the direct sum runs on the SIMD kernel
/// (multipole::direct_at_sources); below it, on the scalar loop that takes each
/// pair once, whose bits the bundled scenes' golden hashes hold.
inline constexpr std::size_t kSimdDirectPoles = 256;

/// Default opening angle: the tree's at the default tolerance of 1e-3
/// (theta_for_tolerance in magnetic_forces.hpp; docs/magnetism.md "Summation").
inline constexpr double kDefaultTheta = 0.35;
/// The FMM's defaults (Summation::Fmm): the fastest measured setting whose
/// RMS relative force error on random magnets stays below 1e-3 from 400 to
/// 10,000 magnets (2e-4 to 6e-4, leaves of 64; theta 0.8 and order 4 is 1.5x
/// faster at 10,000 but 2.5e-3 at 2,000; session 16), but several percent on
/// a packed block of aligned bars, which needs theta 0.4 and order 6 for
/// 5e-4 (bench/scaling.cpp --magnets; docs/magnetism.md "Fast summation").
/// Opt-in for that reason.
inline constexpr double kFmmTheta = 0.7;
inline constexpr int kFmmOrder = 5;

/// Auto's check runs at most every this many updates (magnetic_forces.hpp,
/// kAutoCheckMove and kAutoCheckMargin, give the whole rule).
inline constexpr std::uint32_t kAutoCheckEvery = 8;

struct SummationOptions {
  Summation method = Summation::Direct;
  double theta = kDefaultTheta;
  /// Refit the tree of the previous call instead of building it afresh when
  /// the poles are the same ones (multipole::TreeOptions::reuse); off by
  /// default because the result then depends on the tree's history.
  bool reuse = false;
  /// Summation::Fmm: the expansions' order (1 to multipole::kMaxFmmOrder).
  int fmm_order = kFmmOrder;
  /// Summation::Fmm: each translation at the lowest order its pair's
  /// separation allows (multipole::FmmOptions::pair_orders; session 19).
  bool fmm_pair_orders = true;
  /// Auto: the RMS relative error of the parts' forces the FMM may make (the
  /// setting `tolerance`); above it, as the sampled check measures it, the
  /// evaluation is redone on the tree.
  double tolerance = 1e-3;
  /// Auto: the check runs at least every this many updates (1: every update,
  /// as until session 18; the bench's previous method).
  std::uint32_t check_every = kAutoCheckEvery;
  /// Whether `method` sums `poles` poles with the tree (or the FMM).
  bool use_tree(std::size_t poles) const {
    return method == Summation::Tree || method == Summation::Fmm ||
           (method == Summation::Auto && poles >= kTreeCrossoverPoles);
  }
};

/// Adds to `force[i]` the force on pole i from every pole of another body, N.
/// Direct: each pair is evaluated once and applied with opposite signs, so the
/// sum of all forces is zero to rounding. Tree: each pole's force is summed on
/// its own, so the sum is zero only to the tree's error. `workspace` (optional)
/// keeps the tree's memory between calls.
void accumulate_pole_forces(std::span<const Pole> poles, double softening, std::span<Vec3> force,
                            const SummationOptions& options = {},
                            multipole::Tree* workspace = nullptr);

/// H at each point from every pole whose body differs from `exclude_body[i]`, A/m.
/// `exclude_body[i]` may be kNoBody to include every pole.
inline constexpr std::uint32_t kNoBody = 0xffffffffu;
static_assert(kNoBody == multipole::kNoGroup);
void pole_fields(std::span<const Pole> poles, double softening, std::span<const Vec3> points,
                 std::span<const std::uint32_t> exclude_body, std::span<Vec3> field,
                 const SummationOptions& options = {}, multipole::Tree* workspace = nullptr);

// --- induced poles (soft iron) ------------------------------------------------------

/// Demagnetising factor along the symmetry axis of a spheroid of aspect ratio
/// p = length / diameter (exact for ellipsoids; 1/3 for a sphere, -> 0 for a
/// long needle, -> 1 for a flat disc magnetised through its face).
double demagnetizing_factor(double aspect_ratio);

/// Apparent susceptibility of a body of intrinsic susceptibility chi and
/// demagnetising factor n: M = chi / (1 + n chi) * H_applied. It is bounded by
/// 1/n, which is why a long bar magnetises far more than a short lump.
inline double apparent_susceptibility(double chi, double n) {
  return chi / (1.0 + n * chi);
}

/// Smooth saturation: linear with slope 1 for |q| << q_sat, tends to +-q_sat.
inline double saturate(double q_linear, double q_saturation) {
  if (!(q_saturation > 0)) return q_linear;
  return q_saturation * std::tanh(q_linear / q_saturation);
}
/// d saturate / d q_linear.
inline double saturate_slope(double q_linear, double q_saturation) {
  if (!(q_saturation > 0)) return 1.0;
  const double t = std::tanh(q_linear / q_saturation);
  return 1.0 - t * t;
}

/// Demagnetising factors (N_x, N_y, N_z) of an ellipsoid with semi-axes
/// (a, b, c) along its principal axes, by quadrature of the ellipsoid's
/// integral N_i = (abc/2) int_0^inf ds / ((a_i^2 + s) sqrt((a^2+s)(b^2+s)(c^2+s))).
/// They sum to 1; a sphere's are 1/3 each, a needle's (0, 1/2, 1/2). A box is
/// given the factors of the ellipsoid with the same axis ratios (an
/// approximation: docs/magnetism.md "Soft iron"). Non-positive or non-finite
/// semi-axes give the sphere's.
Vec3 demagnetizing_factors(Vec3 semi_axes);

/// Demagnetising factors (N_x, N_y, N_z) of a rectangular prism with half
/// sides (a, b, c), uniformly magnetised: Aharoni's closed form (J. Appl.
/// Phys. 83, 3432, 1998), the magnetometric factors (the volume mean of the
/// demagnetising field). They sum to 1; a cube's are 1/3 each. For a square
/// bar they lie within a few per cent of the spheroid of the same length and
/// cross-section (2.5 : 1 : 1, 0.164 against 0.160), which is what the
/// kit's bars were given before the iron was isotropic. Non-positive or
/// non-finite sides give the cube's.
Vec3 prism_demagnetizing_factors(Vec3 half_sides);

/// A soft-iron part as the induction solve sees it: its principal axes, its
/// apparent susceptibility along each (shape-limited), and where its mean field
/// is sampled. Isotropic iron has the same intrinsic chi along every axis; its
/// shape (demagnetising factors) makes the apparent chi differ, which is what
/// turns a bar across a field.
struct InducedPart {
  Vec3 centre;   ///< m, world
  Vec3 axes[3];  ///< unit principal axes in the world (the part's local x, y, z)
  double susceptibility[3] =
      {};  ///< apparent chi along each axis, chi / (1 + N_i chi); 0: rigid along it
  double separation[3] = {};  ///< pole separation along each axis, m (> 0)
  double volume = 0;          ///< m^3
  double saturation = 0;      ///< largest moment Ms V, A*m^2 (<= 0: none)
  std::uint32_t body = 0;     ///< body index, as in Pole::body
};

/// The points at which a part's mean field is sampled, and their weights
/// (they sum to 1). The volume average of a field free of sources inside the
/// part is its value at the centre plus (1/10) sum_j a_j^2 d^2H/dx_j^2 for an
/// ellipsoid of semi-axes a_j; since the field's Laplacian is zero, only the
/// excess of each axis over the shortest one matters. So: the centre, and the
/// two ends of each axis longer than the shortest, at +-separation/2, weighted
/// (1 - (s_min / s_j)^2) / 6 each: a sphere is sampled at its centre alone (the
/// exact mean, by the mean-value property, and the same however it is turned);
/// a long bar by Simpson's rule along its axis (weights 1/6, 4/6, 1/6).
struct MeanFieldSamples {
  Vec3 point[7];
  double weight[7] = {};
  int count = 0;
};
MeanFieldSamples mean_field_samples(const InducedPart& part);

/// Smooth saturation of a moment: u if |u| << m_sat, tends to m_sat u/|u|.
Vec3 saturate_moment(Vec3 linear, double saturation);

/// Result of the induction solve.
struct InductionResult {
  std::vector<Vec3> moment;  ///< induced moment of each part, A*m^2, world
  int iterations = 0;        ///< Newton iterations used
  bool converged = true;     ///< false: the uncoupled estimate was kept
};

/// Solves the induced moments m of soft-iron parts consistently:
///
///   m_b = sat_b( V_b chi_b H_b(m) ),   chi_b = sum_i chi_bi e_bi e_bi^T,
///   H_b(m) = mean field over b (mean_field_samples) from the fixed poles and
///            from every other part's moment,
///
/// by Newton's method on the dense system of 3n unknowns (parts are few: tens
/// in a kit scene), starting from the uncoupled estimate (parts ignore one
/// another). For the coupling, a part's moment is carried by three pole pairs
/// along its principal axes (exact to the dipole and the quadrupole; the
/// forces use one pair along the moment, magnetic_forces.cpp). If Newton fails
/// to converge (strongly coupled parts beyond the model's validity) the
/// uncoupled estimate is returned and `converged` is false. `options` sums the
/// fixed poles' field (the part-part coupling stays dense).
InductionResult solve_induction(std::span<const Pole> fixed_poles,
                                std::span<const InducedPart> parts, double softening,
                                const SummationOptions& options = {});

}  // namespace alloy::magnetism
