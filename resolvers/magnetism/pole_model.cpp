#include "resolvers/magnetism/pole_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace alloy::magnetism {

namespace {
std::vector<multipole::Source> tree_sources(std::span<const Pole> poles) {
  std::vector<multipole::Source> sources(poles.size());
  for (std::size_t i = 0; i < poles.size(); ++i)
    sources[i] = {poles[i].position, poles[i].strength, poles[i].body};
  return sources;
}
}  // namespace

void accumulate_pole_forces(std::span<const Pole> poles, double softening, std::span<Vec3> force,
                            const SummationOptions& options, multipole::Tree* workspace) {
  const std::size_t n = poles.size();
  if (options.use_tree(n)) {
    multipole::Tree local;
    multipole::Tree& tree = workspace ? *workspace : local;
    tree.build(tree_sources(poles), softening,
               {.theta = options.theta,
                .reuse = options.reuse,
                .fmm_order = options.method == Summation::Fmm ? options.fmm_order : 0,
                .fmm_single_near = true,
                .fmm_pair_orders = options.fmm_pair_orders});
    std::vector<Vec3> k(n);
    tree.evaluate_at_sources(k);
    for (std::size_t i = 0; i < n; ++i) force[i] += k[i] * (kMu0Over4Pi * poles[i].strength);
    return;
  }
  if (n >= kSimdDirectPoles) {
    std::vector<Vec3> k(n);
    multipole::direct_at_sources(tree_sources(poles), softening, k);
    for (std::size_t i = 0; i < n; ++i) force[i] += k[i] * (kMu0Over4Pi * poles[i].strength);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Pole& a = poles[i];
    if (a.strength == 0) continue;
    for (std::size_t j = i + 1; j < n; ++j) {
      const Pole& b = poles[j];
      if (b.body == a.body || b.strength == 0) continue;
      const Vec3 f = pole_pair_force(a.strength, a.position, b.strength, b.position, softening);
      force[j] += f;
      force[i] -= f;
    }
  }
}

void pole_fields(std::span<const Pole> poles, double softening, std::span<const Vec3> points,
                 std::span<const std::uint32_t> exclude_body, std::span<Vec3> field,
                 const SummationOptions& options, multipole::Tree* workspace) {
  constexpr double kInv4Pi = 1.0 / (4.0 * std::numbers::pi);
  // The tree pays for its build only over many points.
  if (options.use_tree(poles.size()) &&
      (options.method == Summation::Tree || points.size() >= 64)) {
    multipole::Tree local;
    multipole::Tree& tree = workspace ? *workspace : local;
    // Fields at points other than the poles: the tree's walk (the FMM sums at
    // its sources only), at the tree's own default when the FMM was chosen.
    tree.build(tree_sources(poles), softening,
               {.theta = options.method == Summation::Fmm ? kDefaultTheta : options.theta});
    for (std::size_t i = 0; i < points.size(); ++i)
      field[i] = tree.evaluate(points[i], exclude_body[i]) * kInv4Pi;
    return;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    Vec3 h{};
    for (const Pole& p : poles) {
      if (p.body == exclude_body[i] || p.strength == 0) continue;
      h += softened_kernel(points[i] - p.position, softening) * p.strength;
    }
    field[i] = h * kInv4Pi;
  }
}

double demagnetizing_factor(double p) {
  if (!(p > 0) || !std::isfinite(p)) return p > 0 ? 0.0 : 1.0;
  // Osborn (1945), the axial factor of a spheroid with semi-axes c (along the
  // axis) and a = b, p = c / a. Near p = 1 both branches lose digits; the
  // series 1/3 - 4/15 (p - 1) is accurate there to 1e-6.
  const double e = p - 1.0;
  if (std::abs(e) < 1e-3) return 1.0 / 3.0 - 4.0 / 15.0 * e;
  if (p > 1) {
    const double s = std::sqrt(p * p - 1.0);
    return (p / s * std::log(p + s) - 1.0) / (p * p - 1.0);
  }
  const double s = std::sqrt(1.0 - p * p);
  return (1.0 - p / s * std::acos(p)) / (1.0 - p * p);
}

Vec3 demagnetizing_factors(Vec3 semi_axes) {
  const double a[3] = {semi_axes.x, semi_axes.y, semi_axes.z};
  const double top = std::max({a[0], a[1], a[2]});
  if (!(std::min({a[0], a[1], a[2]}) > 0) || !std::isfinite(top))
    return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  // Scale-free: semi-axes relative to the largest; s = e^y, so the integrand
  // s f(s) is smooth in y and decays as e^y below the smallest axis squared
  // and as e^(-y/2) above the largest. Simpson's rule in y.
  double e[3];
  for (int i = 0; i < 3; ++i) e[i] = (a[i] / top) * (a[i] / top);
  const double y_lo = std::log(std::min({e[0], e[1], e[2]})) - 36.0, y_hi = 36.0;
  constexpr int kIntervals = 600;  // even
  const double dy = (y_hi - y_lo) / kIntervals;
  double sum[3] = {};
  for (int k = 0; k <= kIntervals; ++k) {
    const double w = (k == 0 || k == kIntervals) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    const double s = std::exp(y_lo + k * dy);
    const double r = std::sqrt((e[0] + s) * (e[1] + s) * (e[2] + s));
    for (int i = 0; i < 3; ++i) sum[i] += w * s / ((e[i] + s) * r);
  }
  // The three sum to 1 exactly for the ellipsoid; normalising removes the
  // quadrature's (tiny) common error and the tail beyond y_hi.
  const double total = sum[0] + sum[1] + sum[2];
  return {sum[0] / total, sum[1] / total, sum[2] / total};
}

namespace {
/// Aharoni's N_z of the prism with half sides a, b, c (pi D_z, divided by pi).
double prism_factor_z(double a, double b, double c) {
  const double r = std::sqrt(a * a + b * b + c * c), rab = std::sqrt(a * a + b * b),
               rbc = std::sqrt(b * b + c * c), rac = std::sqrt(a * a + c * c);
  const double abc = a * b * c;
  const double s = (b * b - c * c) / (2 * b * c) * std::log((r - a) / (r + a)) +
                   (a * a - c * c) / (2 * a * c) * std::log((r - b) / (r + b)) +
                   b / (2 * c) * std::log((rab + a) / (rab - a)) +
                   a / (2 * c) * std::log((rab + b) / (rab - b)) +
                   c / (2 * a) * std::log((rbc - b) / (rbc + b)) +
                   c / (2 * b) * std::log((rac - a) / (rac + a)) + 2 * std::atan(a * b / (c * r)) +
                   (a * a * a + b * b * b - 2 * c * c * c) / (3 * abc) +
                   (a * a + b * b - 2 * c * c) / (3 * abc) * r + c / (a * b) * (rac + rbc) -
                   (rab * rab * rab + rbc * rbc * rbc + rac * rac * rac) / (3 * abc);
  return s / std::numbers::pi;
}
}  // namespace

Vec3 prism_demagnetizing_factors(Vec3 h) {
  if (!(std::min({h.x, h.y, h.z}) > 0) || !std::isfinite(h.x + h.y + h.z))
    return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  // Each factor is N_z with the axes permuted so that its axis comes last.
  return {prism_factor_z(h.y, h.z, h.x), prism_factor_z(h.z, h.x, h.y),
          prism_factor_z(h.x, h.y, h.z)};
}

MeanFieldSamples mean_field_samples(const InducedPart& part) {
  MeanFieldSamples out;
  double s_min = std::numeric_limits<double>::infinity();
  for (double d : part.separation) s_min = std::min(s_min, 0.5 * d);
  double ends = 0;
  out.count = 1;
  for (int j = 0; j < 3; ++j) {
    const double s = 0.5 * part.separation[j];
    if (!(s > s_min)) continue;
    const double w = (1.0 - (s_min / s) * (s_min / s)) / 6.0;
    out.point[out.count] = part.centre + part.axes[j] * s;
    out.weight[out.count++] = w;
    out.point[out.count] = part.centre - part.axes[j] * s;
    out.weight[out.count++] = w;
    ends += 2 * w;
  }
  out.point[0] = part.centre;
  out.weight[0] = 1.0 - ends;
  return out;
}

Vec3 saturate_moment(Vec3 u, double m_sat) {
  if (!(m_sat > 0)) return u;
  const double r = length(u);
  if (!(r > 1e-8 * m_sat)) return u;  // tanh(x)/x = 1 to rounding
  return u * (m_sat * std::tanh(r / m_sat) / r);
}

namespace {
/// d saturate_moment / d u: g I + (sech^2 - g) u u^T / |u|^2, g = m_sat tanh(r/m_sat) / r.
Eigen::Matrix3d saturate_moment_jacobian(Vec3 u, double m_sat) {
  const double r = length(u);
  if (!(m_sat > 0) || !(r > 1e-8 * m_sat)) return Eigen::Matrix3d::Identity();
  const double t = std::tanh(r / m_sat), g = m_sat * t / r, sech2 = 1.0 - t * t;
  const Eigen::Vector3d n(u.x / r, u.y / r, u.z / r);
  return g * Eigen::Matrix3d::Identity() + (sech2 - g) * n * n.transpose();
}
Eigen::Vector3d eig(Vec3 v) {
  return {v.x, v.y, v.z};
}
Vec3 vec(const Eigen::Vector3d& v) {
  return {v[0], v[1], v[2]};
}
}  // namespace

InductionResult solve_induction(std::span<const Pole> fixed_poles,
                                std::span<const InducedPart> parts, double softening,
                                const SummationOptions& options) {
  const std::size_t n = parts.size();
  InductionResult out;
  out.moment.assign(n, Vec3{});
  if (n == 0) return out;

  // The mean-field sample points of every part.
  std::vector<MeanFieldSamples> samples(n);
  std::vector<Vec3> points;
  std::vector<std::uint32_t> exclude;
  std::vector<std::size_t> first(n);
  for (std::size_t b = 0; b < n; ++b) {
    samples[b] = mean_field_samples(parts[b]);
    first[b] = points.size();
    for (int k = 0; k < samples[b].count; ++k) {
      points.push_back(samples[b].point[k]);
      exclude.push_back(parts[b].body);
    }
  }
  auto mean = [&](std::size_t b, std::span<const Vec3> h) {
    Vec3 m{};
    for (int k = 0; k < samples[b].count; ++k)
      m += h[first[b] + std::size_t(k)] * samples[b].weight[k];
    return m;
  };

  // Mean field from the fixed poles (permanent magnets, electromagnets), and
  // each part's linear response V chi (3 x 3, world).
  std::vector<Vec3> h_fixed(points.size());
  pole_fields(fixed_poles, softening, points, exclude, h_fixed, options);
  Eigen::VectorXd h(3 * n);
  std::vector<Eigen::Matrix3d> response(n);
  for (std::size_t b = 0; b < n; ++b) {
    h.segment<3>(3 * b) = eig(mean(b, h_fixed));
    response[b].setZero();
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d e = eig(parts[b].axes[i]);
      response[b] += parts[b].volume * parts[b].susceptibility[i] * e * e.transpose();
    }
  }

  // Coupling: the mean field at b from c's moment, carried by a pole pair
  // along each of c's principal axes (unit moment along e_cj: poles +-1/d_cj).
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  std::vector<Vec3> hk(points.size());
  for (std::size_t c = 0; c < n; ++c)
    for (int j = 0; j < 3; ++j) {
      if (parts[c].susceptibility[j] == 0) continue;  // never magnetised along it
      const double d = parts[c].separation[j];
      const BarPoles pc = bar_poles(parts[c].centre, parts[c].axes[j], d);
      const Pole unit[2] = {{pc.north, 1.0 / d, parts[c].body},
                            {pc.south, -1.0 / d, parts[c].body}};
      for (std::size_t b = 0; b < n; ++b) {
        if (b == c || parts[b].body == parts[c].body) continue;
        const auto span = std::span(points).subspan(first[b], std::size_t(samples[b].count));
        const auto out_span = std::span(hk).subspan(first[b], span.size());
        pole_fields(unit, softening, span, std::span(exclude).subspan(first[b], span.size()),
                    out_span);
        g.block<3, 3>(3 * b, 3 * c) += eig(mean(b, hk)) * eig(parts[c].axes[j]).transpose();
      }
    }

  auto linear = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    const Eigen::VectorXd field = h + g * x;
    Eigen::VectorXd u(3 * n);
    for (std::size_t b = 0; b < n; ++b) u.segment<3>(3 * b) = response[b] * field.segment<3>(3 * b);
    return u;
  };
  auto sat = [&](const Eigen::VectorXd& u) -> Eigen::VectorXd {
    Eigen::VectorXd m(3 * n);
    for (std::size_t b = 0; b < n; ++b)
      m.segment<3>(3 * b) = eig(saturate_moment(vec(u.segment<3>(3 * b)), parts[b].saturation));
    return m;
  };
  auto residual = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd { return x - sat(linear(x)); };

  const Eigen::VectorXd uncoupled = sat(linear(Eigen::VectorXd::Zero(3 * n)));
  Eigen::VectorXd x = uncoupled;
  Eigen::VectorXd r = residual(x);
  // Tolerance relative to the largest moment the fixed field alone would induce.
  const double scale = std::max(uncoupled.cwiseAbs().maxCoeff(), 1e-300);
  const double tol = 1e-11 * scale;
  constexpr int kMaxIterations = 30;
  bool converged = r.cwiseAbs().maxCoeff() <= tol;
  for (int it = 0; it < kMaxIterations && !converged; ++it) {
    const Eigen::VectorXd u = linear(x);
    Eigen::MatrixXd jac = Eigen::MatrixXd::Identity(3 * n, 3 * n);
    for (std::size_t b = 0; b < n; ++b)
      jac.middleRows<3>(3 * b) -=
          saturate_moment_jacobian(vec(u.segment<3>(3 * b)), parts[b].saturation) * response[b] *
          g.middleRows<3>(3 * b);
    const Eigen::VectorXd dx = jac.partialPivLu().solve(-r);
    // Backtracking keeps Newton from jumping across the saturation knee.
    double lambda = 1.0;
    const double r0 = r.norm();
    Eigen::VectorXd x_new, r_new;
    for (int k = 0; k < 12; ++k, lambda *= 0.5) {
      x_new = x + lambda * dx;
      r_new = residual(x_new);
      if (r_new.allFinite() && r_new.norm() < r0) break;
    }
    if (!r_new.allFinite() || !(r_new.norm() < r0)) {
      // No descent: either rounding already dominates (accept) or the coupled
      // problem has no nearby solution (give up).
      converged = r.cwiseAbs().maxCoeff() <= 1e-7 * scale;
      break;
    }
    x = x_new;
    r = r_new;
    out.iterations = it + 1;
    converged = r.cwiseAbs().maxCoeff() <= tol;
  }
  out.converged = converged && x.allFinite();
  const Eigen::VectorXd& result = out.converged ? x : uncoupled;
  for (std::size_t b = 0; b < n; ++b) out.moment[b] = vec(result.segment<3>(3 * b));
  return out;
}

}  // namespace alloy::magnetism
