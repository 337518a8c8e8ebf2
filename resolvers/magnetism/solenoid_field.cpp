#include "resolvers/magnetism/solenoid_field.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "resolvers/magnetism/pole_model.hpp"

namespace alloy::magnetism {
namespace {

constexpr double kPi = std::numbers::pi;

// Gauss-Legendre nodes and weights on [0, 1], computed once (Newton on P_n).
// 20 points per graded piece (four pieces) keep the disk potential within
// 1e-9 of its closed form on the axis and its gradient within 1e-6 of the
// value's derivative off the rim (docs/magnetism.md "A coil's near field").
constexpr int kNodes = 20;
struct Rule {
  std::array<double, kNodes> x{}, w{};
};
const Rule& rule() {
  static const Rule r = [] {
    Rule out;
    for (int i = 0; i < kNodes; ++i) {
      double t = std::cos(kPi * (i + 0.75) / (kNodes + 0.5));
      double dp = 1;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = t;
        for (int k = 2; k <= kNodes; ++k) {
          const double p2 = ((2.0 * k - 1) * t * p1 - (k - 1.0) * p0) / k;
          p0 = p1, p1 = p2;
        }
        dp = kNodes * (t * p1 - p0) / (t * t - 1);
        const double step = p1 / dp;
        t -= step;
        if (std::abs(step) < 1e-16) break;
      }
      out.x[std::size_t(i)] = 0.5 * (1 - t);
      out.w[std::size_t(i)] = 1.0 / ((1 - t * t) * dp * dp);  // 2/((1-t^2)P'^2) on [-1,1], halved
    }
    return out;
  }();
  return r;
}

// K(m) and dK/dm for the parameter m = k^2 in [0, 1).
void elliptic_k(double m, double& k, double& dk) {
  if (m < 1e-6) {  // series: K = pi/2 (1 + m/4 + 9 m^2/64), exact to rounding here
    k = 0.5 * kPi * (1 + m / 4 + 9 * m * m / 64);
    dk = 0.5 * kPi * (0.25 + 9 * m / 32);
    return;
  }
  const double mod = std::sqrt(m);
  k = std::comp_ellint_1(mod);
  const double e = std::comp_ellint_2(mod);
  dk = (e - (1 - m) * k) / (2 * m * (1 - m));
}

// The quintic smoothstep's complement on [0, 1]: 1 at 0, 0 at 1, C2.
double fade(double s, double& ds) {
  if (s <= 0) return ds = 0, 1.0;
  if (s >= 1) return ds = 0, 0.0;
  ds = -30 * s * s * (1 - s) * (1 - s);
  return 1 - s * s * s * (10 - 15 * s + 6 * s * s);
}

// The window's zone, in radii: the box |z| <= l/2 + kEndMargin a, rho <=
// kSideMargin a, faded over kNearMargin a beyond it.
constexpr double kEndMargin = 2.0;
constexpr double kSideMargin = 2.0;
constexpr double kNearMargin = 3.0;

struct Local {
  double z = 0, rho = 0;
  Vec3 radial;  // unit, perpendicular to the axis (any when rho = 0)
};
Local local(const Solenoid& c, Vec3 p) {
  const Vec3 r = p - c.centre;
  Local out;
  out.z = dot(r, c.axis);
  const Vec3 perp = r - out.z * c.axis;
  out.rho = length(perp);
  if (out.rho > 0) out.radial = perp / out.rho;
  return out;
}

}  // namespace

double solenoid_radius(double coil_factor, double separation) {
  if (!(coil_factor > 0) || !(separation > 0)) return 0;
  return std::sqrt(coil_factor * separation / kPi);
}

double coil_sheet_radius(const MagnetColumns& c, std::uint32_t slot, double coil_factor,
                         double separation) {
  const double a = solenoid_radius(coil_factor, separation);
  if (const auto bulk = part_bulk(c, slot)) {
    const double half_width = 0.5 * std::min(bulk->extent.y, bulk->extent.z);
    if (!(a <= 1.05 * half_width)) return 0;
  }
  return a;
}

double disk_potential(double a, double rho, double z, double* d_rho, double* d_z) {
  // D = int_0^a r g(r) dr, g = 4 K(m) / sqrt(A), A = (rho + r)^2 + z^2,
  // m = 4 rho r / A (the ring's potential). Pieces [0, s] and [s, a] with
  // s = min(rho, a), each graded toward s (r = s +- span u^2) where the
  // integrand is steepest (near the plane it has a log at r = rho).
  const Rule& q = rule();
  double sum = 0, s_rho = 0, s_z = 0;
  const double split = std::clamp(rho, 0.0, a);
  auto piece = [&](double from, double to) {  // graded toward `from`
    const double span = to - from;
    if (span == 0) return;
    for (int i = 0; i < kNodes; ++i) {
      const double u = q.x[std::size_t(i)];
      const double r = from + span * u * u;
      const double jac = 2 * std::abs(span) * u * q.w[std::size_t(i)];
      const double big_a = (rho + r) * (rho + r) + z * z;
      if (!(big_a > 0)) continue;
      const double m = std::min(4 * rho * r / big_a, 1 - 1e-15);
      double k, dk;
      elliptic_k(m, k, dk);
      const double root = std::sqrt(big_a);
      const double g = 4 * k / root;
      sum += jac * r * g;
      if (d_rho || d_z) {
        // dg/dx = 4 (K'(m) dm/dx / sqrt(A) - K dA/dx / (2 A^1.5))
        const double m_z = -2 * z * m / big_a;
        const double m_rho = 4 * r / big_a - 2 * m * (rho + r) / big_a;
        s_z += jac * r * 4 * (dk * m_z / root - k * z / (big_a * root));
        s_rho += jac * r * 4 * (dk * m_rho / root - k * (rho + r) / (big_a * root));
      }
    }
  };
  // Within a few |z| of r = rho the integrand changes on the scale |z|:
  // a piece of that width on each side, graded toward rho, the rest beyond.
  const double near = std::max(8 * std::abs(z), 1e-12);
  const double inner = std::max(split - near, 0.0), outer = std::min(split + near, a);
  piece(split, inner);
  piece(inner, 0.0);
  piece(split, outer);
  piece(outer, a);
  if (d_rho) *d_rho = s_rho;
  if (d_z) *d_z = s_z;
  return sum;
}

PoleLinkage pair_linkage(const Solenoid& c, double softening, Vec3 p) {
  const double linkage = kPi * c.radius * c.radius * c.turns_per_metre;
  const BarPoles ends = bar_poles(c.centre, c.axis, c.length);
  const Vec3 rs = ends.south - p, rn = ends.north - p;
  const double e2 = softening * softening;
  const double ss = std::sqrt(dot(rs, rs) + e2), sn = std::sqrt(dot(rn, rn) + e2);
  PoleLinkage out;
  if (!(ss > 0) || !(sn > 0)) return out;
  out.flux = linkage * kMu0Over4Pi * (1 / ss - 1 / sn);
  // d/dp 1/s(x - p) = (x - p) / s^3
  out.gradient = linkage * kMu0Over4Pi * (rs / (ss * ss * ss) - rn / (sn * sn * sn));
  return out;
}

PoleLinkage sheet_linkage(const Solenoid& c, Vec3 p) {
  const Local at = local(c, p);
  const double h = 0.5 * c.length;
  double dr_s, dz_s, dr_n, dz_n;
  const double ds = disk_potential(c.radius, at.rho, at.z + h, &dr_s, &dz_s);
  const double dn = disk_potential(c.radius, at.rho, at.z - h, &dr_n, &dz_n);
  const double scale = c.turns_per_metre * kMu0Over4Pi;
  PoleLinkage out;
  out.flux = scale * (ds - dn);
  out.gradient = scale * ((dr_s - dr_n) * at.radial + (dz_s - dz_n) * c.axis);
  return out;
}

Window near_window(const Solenoid& c, Vec3 p) {
  const Local at = local(c, p);
  const double a = c.radius;
  const double over_z = std::abs(at.z) - (0.5 * c.length + kEndMargin * a);
  const double over_r = at.rho - kSideMargin * a;
  Window out;
  if (!(a > 0)) return out;
  if (over_z <= 0 && over_r <= 0) return out.value = 1, out;
  const double dz = std::max(over_z, 0.0), dr = std::max(over_r, 0.0);
  const double dist = std::sqrt(dz * dz + dr * dr);
  const double margin = kNearMargin * a;
  if (dist >= margin) return out;
  double ds;
  out.value = fade(dist / margin, ds);
  const Vec3 grad_dist = (dz * (at.z < 0 ? -1.0 : 1.0) * c.axis + dr * at.radial) / dist;
  out.gradient = (ds / margin) * grad_dist;
  return out;
}

PoleLinkage near_correction(const Solenoid& c, double softening, Vec3 p) {
  PoleLinkage out;
  const Window w = near_window(c, p);
  if (w.value == 0) return out;
  const PoleLinkage sheet = sheet_linkage(c, p), pair = pair_linkage(c, softening, p);
  const double diff = sheet.flux - pair.flux;
  out.flux = w.value * diff;
  out.gradient = w.value * (sheet.gradient - pair.gradient) + diff * w.gradient;
  return out;
}

StringLinkage string_linkage(const Solenoid& c, Vec3 south, Vec3 north) {
  StringLinkage out;
  if (!(c.radius > 0)) return out;
  const Vec3 rs = south - c.centre, rn = north - c.centre;
  const double zs = dot(rs, c.axis), zn = dot(rn, c.axis);
  const Vec3 ps = rs - zs * c.axis, pn = rn - zn * c.axis;  // perpendicular parts
  const double dz = zn - zs;
  const Vec3 dp = pn - ps;
  const double h = 0.5 * c.length, a = c.radius;
  // The parameter interval t in [0, 1] of the segment south + t (north -
  // south) inside the bore, each end tagged with what bounds it.
  enum class Bound { End, Cap, Wall };
  struct Limit {
    double t;
    Bound kind;
    double cap;  // the cap's z, for Bound::Cap
  };
  Limit lo{0, Bound::End, 0}, hi{1, Bound::End, 0};
  auto tighten = [&](Limit l0, Limit l1) {
    if (l0.t > lo.t) lo = l0;
    if (l1.t < hi.t) hi = l1;
  };
  if (std::abs(dz) < 1e-300) {
    if (!(std::abs(zs) < h)) return out;
  } else {
    Limit c0{(-h - zs) / dz, Bound::Cap, -h}, c1{(h - zs) / dz, Bound::Cap, h};
    if (c0.t > c1.t) std::swap(c0, c1);
    tighten(c0, c1);
  }
  const double alpha = dot(dp, dp), beta = dot(ps, dp), gamma = dot(ps, ps) - a * a;
  if (alpha < 1e-300) {
    if (!(gamma < 0)) return out;
  } else {
    const double disc = beta * beta - alpha * gamma;
    if (!(disc > 0)) return out;
    const double root = std::sqrt(disc);
    tighten({(-beta - root) / alpha, Bound::Wall, 0}, {(-beta + root) / alpha, Bound::Wall, 0});
  }
  if (!(hi.t > lo.t)) return out;
  // d t / d north and d t / d south for each limit (header: exact gradient).
  auto dt = [&](const Limit& l, Vec3& d_north, Vec3& d_south) {
    d_north = {}, d_south = {};
    if (l.kind == Bound::Cap) {  // t = (c - zs) / dz
      d_north = (-l.t / dz) * c.axis;
      d_south = ((l.t - 1) / dz) * c.axis;
    } else if (l.kind == Bound::Wall) {  // |ps + t dp|^2 = a^2
      const Vec3 at = ps + l.t * dp;
      const double slope = dot(at, dp);
      if (slope == 0) return;
      d_north = (-l.t / slope) * at;
      d_south = (-(1 - l.t) / slope) * at;
    }
  };
  Vec3 lo_n, lo_s, hi_n, hi_s;
  dt(lo, lo_n, lo_s);
  dt(hi, hi_n, hi_s);
  const double span = hi.t - lo.t;
  const double scale = kMu0 * c.turns_per_metre;
  out.overlap = dz * span;
  out.flux = scale * out.overlap;
  out.grad_north = scale * (span * c.axis + dz * (hi_n - lo_n));
  out.grad_south = scale * (-span * c.axis + dz * (hi_s - lo_s));
  return out;
}

namespace {
// a's sheet linking b's pole pair (one ampere in b: poles +-k_b N_b) and
// string, per ampere in a, with the pole pair outside the zone.
double one_way(const Solenoid& a, const Solenoid& b, double softening) {
  const double q = kPi * b.radius * b.radius * b.turns_per_metre;  // k_b N_b
  const BarPoles ends = bar_poles(b.centre, b.axis, b.length);
  const double pair = q * (pair_linkage(a, softening, ends.north).flux -
                           pair_linkage(a, softening, ends.south).flux);
  const double near = q * (near_correction(a, softening, ends.north).flux -
                           near_correction(a, softening, ends.south).flux);
  return pair + near + q * string_linkage(a, ends.south, ends.north).flux;
}
}  // namespace

double sheet_mutual_inductance(const Solenoid& a, const Solenoid& b, double softening) {
  return 0.5 * (one_way(a, b, softening) + one_way(b, a, softening));
}

double sheet_self_inductance(const Solenoid& c) {
  // The sheet's own flux per ampere: its magnetisation n inside the bore
  // (mu0 n^2 pi a^2 l) less the end disks' own field through the turns,
  // mu0 n^2 / (2 pi) (S0 - W(l)): S0 = 16 pi a^3 / 3 a disk's integral of
  // 1/|x - x'| over itself, W(l) the same between two coaxial disks l apart
  // (rings of the one in the other's potential).
  const double a = c.radius, n = c.turns_per_metre, l = c.length;
  const Rule& q = rule();
  double w = 0;
  for (int i = 0; i < kNodes; ++i) {
    // graded toward the rim, where D varies fastest for small l
    const double u = q.x[std::size_t(i)];
    const double r = a * (1 - u * u);
    w += 2 * a * u * q.w[std::size_t(i)] * 2 * kPi * r * disk_potential(a, r, l);
  }
  const double s0 = 16 * kPi * a * a * a / 3;
  return kMu0 * n * n * (kPi * a * a * l - (s0 - w) / (2 * kPi));
}

void add_near_forces(std::span<const NearCoil> coils, std::span<const Pole> poles,
                     std::span<const std::uint8_t> sheet_body, double softening,
                     std::span<Vec3> pole_force, std::span<Vec3> body_force,
                     std::span<Vec3> body_torque) {
  auto applies = [&](std::size_t i) {
    const std::uint32_t b = poles[i].body;
    return b < sheet_body.size() && sheet_body[b] != 0 && poles[i].strength != 0;
  };
  for (const NearCoil& c : coils) {
    if (c.strength == 0 || !(c.sheet.radius > 0)) continue;
    Vec3 reaction{}, moment{};
    auto push = [&](std::size_t i, Vec3 f) {
      pole_force[i] += f;
      reaction -= f;
      moment -= cross(poles[i].position - c.sheet.centre, f);
    };
    for (std::size_t i = 0; i < poles.size(); ++i) {
      if (poles[i].body == c.body || !applies(i)) continue;
      const PoleLinkage g = near_correction(c.sheet, softening, poles[i].position);
      if (g.flux != 0 || g.gradient != Vec3{})
        push(i, (c.strength * poles[i].strength) * g.gradient);
      // A body's pole pair (north, then south): its string through the bore.
      if (i + 1 < poles.size() && poles[i + 1].body == poles[i].body && poles[i].strength > 0 &&
          poles[i + 1].strength == -poles[i].strength) {
        const StringLinkage s = string_linkage(c.sheet, poles[i + 1].position, poles[i].position);
        if (s.overlap != 0) {
          const double qq = c.strength * poles[i].strength;
          push(i, qq * s.grad_north);
          push(i + 1, qq * s.grad_south);
        }
      }
    }
    if (c.body < body_force.size()) body_force[c.body] += reaction;
    if (c.body < body_torque.size()) body_torque[c.body] += moment;
  }
}

}  // namespace alloy::magnetism
