#include "resolvers/magnetism/pole_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

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
    tree.build(tree_sources(poles), softening, {.theta = options.theta});
    std::vector<Vec3> k(n);
    tree.evaluate_at_sources(k);
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
    tree.build(tree_sources(poles), softening, {.theta = options.theta});
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

InductionResult solve_induction(std::span<const Pole> fixed_poles, std::span<const InducedBar> bars,
                                double softening, const SummationOptions& options) {
  const std::size_t n = bars.size();
  InductionResult out;
  out.strength.assign(n, 0.0);
  if (n == 0) return out;

  // Three axial samples per bar: its south end, its centre, its north end.
  std::vector<Vec3> points(3 * n);
  std::vector<std::uint32_t> exclude(3 * n);
  for (std::size_t b = 0; b < n; ++b)
    for (int k = 0; k < 3; ++k) {
      points[3 * b + k] = bars[b].centre + bars[b].axis * ((k - 1) * 0.5 * bars[b].separation);
      exclude[3 * b + k] = bars[b].body;
    }

  // Axial field from the fixed poles (permanent magnets, electromagnets).
  std::vector<Vec3> h_fixed(3 * n);
  pole_fields(fixed_poles, softening, points, exclude, h_fixed, options);
  Eigen::VectorXd h(n), gain(n), qsat(n);
  for (std::size_t b = 0; b < n; ++b) {
    double a = 0;
    for (int k = 0; k < 3; ++k) a += kAxialSampleWeights[k] * dot(bars[b].axis, h_fixed[3 * b + k]);
    h[b] = a;
    gain[b] = bars[b].gain;
    qsat[b] = bars[b].saturation;
  }

  // Coupling: axial field at bar b from bar c magnetised with unit strength.
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t c = 0; c < n; ++c) {
    const BarPoles pc = bar_poles(bars[c].centre, bars[c].axis, bars[c].separation);
    const Pole unit[2] = {{pc.north, 1.0, bars[c].body}, {pc.south, -1.0, bars[c].body}};
    for (std::size_t b = 0; b < n; ++b) {
      if (b == c || bars[b].body == bars[c].body) continue;
      Vec3 hk[3];
      pole_fields(unit, softening, std::span(points).subspan(3 * b, 3),
                  std::span(exclude).subspan(3 * b, 3), hk);
      double a = 0;
      for (int k = 0; k < 3; ++k) a += kAxialSampleWeights[k] * dot(bars[b].axis, hk[k]);
      g(b, c) = a;
    }
  }

  auto sat = [&](const Eigen::VectorXd& u) {
    Eigen::VectorXd s(n);
    for (std::size_t b = 0; b < n; ++b) s[b] = saturate(u[b], qsat[b]);
    return s;
  };
  auto residual = [&](const Eigen::VectorXd& s) -> Eigen::VectorXd {
    return s - sat(gain.cwiseProduct(h + g * s));
  };

  const Eigen::VectorXd uncoupled = sat(gain.cwiseProduct(h));
  Eigen::VectorXd s = uncoupled;
  Eigen::VectorXd r = residual(s);
  // Tolerance relative to the largest pole the fixed field alone would induce.
  const double scale = std::max(uncoupled.cwiseAbs().maxCoeff(), 1e-300);
  const double tol = 1e-11 * scale;
  constexpr int kMaxIterations = 30;
  bool converged = r.cwiseAbs().maxCoeff() <= tol;
  for (int it = 0; it < kMaxIterations && !converged; ++it) {
    const Eigen::VectorXd u = gain.cwiseProduct(h + g * s);
    Eigen::MatrixXd jac = Eigen::MatrixXd::Identity(n, n);
    for (std::size_t b = 0; b < n; ++b)
      jac.row(b) -= saturate_slope(u[b], qsat[b]) * gain[b] * g.row(b);
    const Eigen::VectorXd ds = jac.partialPivLu().solve(-r);
    // Backtracking keeps Newton from jumping across the saturation knee.
    double lambda = 1.0;
    const double r0 = r.norm();
    Eigen::VectorXd s_new, r_new;
    for (int k = 0; k < 12; ++k, lambda *= 0.5) {
      s_new = s + lambda * ds;
      r_new = residual(s_new);
      if (r_new.allFinite() && r_new.norm() < r0) break;
    }
    if (!r_new.allFinite() || !(r_new.norm() < r0)) {
      // No descent: either rounding already dominates (accept) or the coupled
      // problem has no nearby solution (give up).
      converged = r.cwiseAbs().maxCoeff() <= 1e-7 * scale;
      break;
    }
    s = s_new;
    r = r_new;
    out.iterations = it + 1;
    converged = r.cwiseAbs().maxCoeff() <= tol;
  }
  out.converged = converged && s.allFinite();
  const Eigen::VectorXd& result = out.converged ? s : uncoupled;
  for (std::size_t b = 0; b < n; ++b) out.strength[b] = result[b];
  return out;
}

}  // namespace alloy::magnetism
