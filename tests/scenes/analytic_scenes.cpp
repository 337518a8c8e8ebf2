// Analytic scenes for work-precision (see analytic_scenes.hpp): builders, the
// exact solutions or fine RK4 references, and the timed runs.
#include "tests/scenes/analytic_scenes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <map>
#include <numbers>
#include <tuple>

#include "resolvers/magnetism/flux_linkage.hpp"
#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes::analytic {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;  // gravity.uniform's default, m/s^2

// std::clock is this process's CPU time (clock_gettime of the process CPU
// clock on Linux): the scenes library does not depend on the bench library.
double cpu_now() {
  return double(std::clock()) / CLOCKS_PER_SEC;
}

std::uint64_t steps_for(double seconds, double dt) {
  return std::uint64_t(std::llround(seconds / dt));
}

/// Steps the world `n` times, calling `after(step_index)` after each (the
/// comparison with a precomputed reference: a few column reads, small
/// against a step, and the same for every method). Timed as a whole: a CPU
/// clock read per step would cost about as much as a small world's step.
template <class F>
void run_timed(World& w, std::uint64_t n, Result& r, F&& after) {
  // The world refuses a non-finite write and reports it as a "non_finite"
  // event (freezing the object): such a run's error would mean nothing.
  bool non_finite = false;
  w.add_observer([&](const Event& e) { non_finite = non_finite || e.type == "non_finite"; });
  w.start();
  const double t0 = cpu_now();
  for (std::uint64_t i = 1; i <= n; ++i) {
    w.step();
    after(i);
  }
  r.cpu_seconds = cpu_now() - t0;
  r.steps = n;
  r.sim_seconds = double(n) * w.dt();
  r.finite = !non_finite && std::isfinite(r.error);
}

// A column read by slot: cheap enough to sit in the per-step comparison.
template <class T>
const T& read(const World& w, ObjectId o, std::string_view property) {
  return w.view().column<T>(property)[o.index];
}

// --- quaternions (w, x, y, z), the world's convention -------------------------------

Quat conj(Quat q) {
  return {q.w, -q.x, -q.y, -q.z};
}
Quat normalised(Quat q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
/// Angle of the rotation taking a to b, rad, in [0, pi].
double rotation_between(Quat a, Quat b) {
  const Quat d = conj(a) * b;
  const double v = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  return 2 * std::atan2(v, std::abs(d.w));
}

// --- the tumbling box's reference: Euler's equations in the body frame ----------------

struct RigidState {
  Vec3 w;  // angular velocity, body frame
  Quat q;  // body to world
};

RigidState rigid_rate(const RigidState& s, Vec3 inertia) {
  const Vec3 w = s.w;
  const Vec3 dw{(inertia.y - inertia.z) / inertia.x * w.y * w.z,
                (inertia.z - inertia.x) / inertia.y * w.z * w.x,
                (inertia.x - inertia.y) / inertia.z * w.x * w.y};
  const Quat dq = s.q * Quat{0, w.x, w.y, w.z};
  return {dw, {0.5 * dq.w, 0.5 * dq.x, 0.5 * dq.y, 0.5 * dq.z}};
}

RigidState add(const RigidState& s, const RigidState& d, double h) {
  return {s.w + d.w * h,
          {s.q.w + d.q.w * h, s.q.x + d.q.x * h, s.q.y + d.q.y * h, s.q.z + d.q.z * h}};
}

RigidState rk4(const RigidState& s, Vec3 inertia, double h) {
  const RigidState k1 = rigid_rate(s, inertia);
  const RigidState k2 = rigid_rate(add(s, k1, h / 2), inertia);
  const RigidState k3 = rigid_rate(add(s, k2, h / 2), inertia);
  const RigidState k4 = rigid_rate(add(s, k3, h), inertia);
  RigidState out = s;
  out.w += (k1.w + 2.0 * k2.w + 2.0 * k3.w + k4.w) * (h / 6);
  out.q = normalised({s.q.w + (k1.q.w + 2 * k2.q.w + 2 * k3.q.w + k4.q.w) * h / 6,
                      s.q.x + (k1.q.x + 2 * k2.q.x + 2 * k3.q.x + k4.q.x) * h / 6,
                      s.q.y + (k1.q.y + 2 * k2.q.y + 2 * k3.q.y + k4.q.y) * h / 6,
                      s.q.z + (k1.q.z + 2 * k2.q.z + 2 * k3.q.z + k4.q.z) * h / 6});
  return out;
}

/// Substeps of at most h that divide dt exactly.
int substeps_within(double dt, double h) {
  return std::max(1, int(std::ceil(dt / h - 1e-9)));
}

// --- magnets -----------------------------------------------------------------------------

constexpr double kMagnetLength = 0.1, kMagnetPole = 20.0, kMagnetMass = 0.05, kMagnetStart = 0.12;

}  // namespace

bool rigid_substeps_supported() {
  const auto& k = rigid::RigidBodyConfig::keys();
  return std::find(k.begin(), k.end(), "substeps") != k.end();
}

WorldDef world_def(double dt, const Method& m, bool gravity) {
  WorldDef def;
  def.dt = dt;
  auto& rb = def.settings["rigid_body"];
  rb.set("solver", m.solver);
  rb.set("iterations", std::int64_t(m.iterations));
  if (m.rigid_substeps != 1 && rigid_substeps_supported())
    rb.set("substeps", std::int64_t(m.rigid_substeps));
  if (!m.joint_projection) rb.set("joint_projection", false);
  def.settings["electricity"].set("substeps", std::int64_t(m.electricity_substeps));
  // Always named: the engine's default (2 since session 17) is not this
  // struct's (1, the sweeps' first-order rows).
  def.settings["electricity"].set("induction_order", std::int64_t(m.induction_order));
  if (!gravity) def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  if (m.engine != "rigid_body") def.use["rigid_body"] = m.engine;
  if (m.near_field >= 0) def.settings["magnetic_forces"].set("near_field", m.near_field != 0);
  return def;
}

Result run_free_fall(double dt, const Method& m, double seconds) {
  Sim s(world_def(dt, m));
  const FreeFall f = build_free_fall(*s, 10.0);
  Result r;
  run_timed(*s, steps_for(seconds, dt), r, [&](std::uint64_t i) {
    const double t = double(i) * dt;
    const double exact = f.start.y - 0.5 * kG * t * t;
    r.error = std::max(r.error, std::abs(read<Vec3>(*s, f.ball, "position").y - exact));
  });
  return r;
}

std::vector<double> pendulum_reference(double k, double theta0, double dt, std::size_t n,
                                       double h) {
  std::vector<double> out(n + 1);
  const int sub = substeps_within(dt, h);
  const double hs = dt / sub;
  double th = theta0, om = 0;
  out[0] = th;
  for (std::size_t i = 1; i <= n; ++i) {
    for (int j = 0; j < sub; ++j) {
      const double k1t = om, k1o = -k * std::sin(th);
      const double k2t = om + hs / 2 * k1o, k2o = -k * std::sin(th + hs / 2 * k1t);
      const double k3t = om + hs / 2 * k2o, k3o = -k * std::sin(th + hs / 2 * k2t);
      const double k4t = om + hs * k3o, k4o = -k * std::sin(th + hs * k3t);
      th += hs / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      om += hs / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    }
    out[i] = th;
  }
  return out;
}

Result run_pendulum(double dt, const Method& m, double theta0, double seconds) {
  Sim s(world_def(dt, m));
  const BarPendulum p = build_bar_pendulum(*s, 1.0, theta0);
  // Compound pendulum: I about the pivot, d from pivot to centre of mass.
  const double d = p.length / 2;
  const double inertia = p.mass * (p.length * p.length + p.width * p.width) / 12 + p.mass * d * d;
  const std::uint64_t n = steps_for(seconds, dt);
  const std::vector<double> ref = pendulum_reference(p.mass * kG * d / inertia, theta0, dt, n);
  Result r;
  run_timed(*s, n, r, [&](std::uint64_t i) {
    const Vec3 c = read<Vec3>(*s, p.bar, "position");
    r.error = std::max(r.error, std::abs(std::atan2(c.x, -c.y) - ref[i]));
  });
  return r;
}

Result run_tumbling_box(double dt, const Method& m, double seconds) {
  Sim s(world_def(dt, m, /*gravity=*/false));
  const Vec3 size{0.3, 0.2, 0.1};
  const double mass = 1.0;
  const Vec3 inertia{mass * (size.y * size.y + size.z * size.z) / 12,
                     mass * (size.x * size.x + size.z * size.z) / 12,
                     mass * (size.x * size.x + size.y * size.y) / 12};
  // Near the intermediate (y) axis: the small x and z parts grow at about
  // 2.9 /s and the box flips over about 2 s in; the run goes through it.
  const Vec3 w0{0.05, 6.0, 0.05};
  const ObjectId box = add_box(*s, {0, 0, 0}, size, mass, Quat{}, "box");
  s->set(box, "angular_velocity", w0);

  const std::uint64_t n = steps_for(seconds, dt);
  std::vector<Quat> ref(n + 1);
  RigidState st{w0, Quat{}};  // body frame = world frame at the start
  ref[0] = st.q;
  const int sub = substeps_within(dt, 1e-4);
  for (std::uint64_t i = 1; i <= n; ++i) {
    for (int j = 0; j < sub; ++j) st = rk4(st, inertia, dt / sub);
    ref[i] = st.q;
  }

  auto energy_momentum = [&](Quat q, Vec3 w_world) {
    const Vec3 wb = rotate(conj(q), w_world);
    const Vec3 lb{inertia.x * wb.x, inertia.y * wb.y, inertia.z * wb.z};
    return std::pair{0.5 * dot(wb, lb), rotate(q, lb)};
  };
  const auto [e0, l0] = energy_momentum(Quat{}, w0);
  Result r;
  r.energy_drift = r.momentum_drift = 0;
  run_timed(*s, n, r, [&](std::uint64_t i) {
    const Quat q = read<Quat>(*s, box, "orientation");
    r.error = std::max(r.error, rotation_between(q, ref[i]));
    const auto [e, l] = energy_momentum(q, read<Vec3>(*s, box, "angular_velocity"));
    r.energy_drift = std::max(r.energy_drift, std::abs(e - e0) / e0);
    r.momentum_drift = std::max(r.momentum_drift, length(l - l0) / length(l0));
  });
  return r;
}

namespace {
constexpr double kOrbitG = 20, kOrbitM1 = 3, kOrbitM2 = 1, kOrbitD = 2;
}

double orbit_period() {
  return 2 * kPi * std::sqrt(kOrbitD * kOrbitD * kOrbitD / (kOrbitG * (kOrbitM1 + kOrbitM2)));
}

Result run_orbit(double dt, const Method& m, int orbits) {
  WorldDef def = world_def(dt, m);
  def.use = {{"gravity", "gravity.nbody"}};
  def.settings["gravity.nbody"].set("G", kOrbitG);
  def.settings["gravity.nbody"].set("softening", 0.0);
  Sim s(def);
  const double M = kOrbitM1 + kOrbitM2, d = kOrbitD;
  // Relative speed sqrt(G M / d), shared so that the total momentum is zero.
  const double vrel = std::sqrt(kOrbitG * M / d);
  const ObjectId a = add_sphere(*s, {-d * kOrbitM2 / M, 0, 0}, 0.05, kOrbitM1, "a");
  const ObjectId b = add_sphere(*s, {d * kOrbitM1 / M, 0, 0}, 0.05, kOrbitM2, "b");
  s->set(a, "velocity", Vec3{0, -vrel * kOrbitM2 / M, 0});
  s->set(b, "velocity", Vec3{0, vrel * kOrbitM1 / M, 0});
  auto energy = [&] {
    const Vec3 va = read<Vec3>(*s, a, "velocity"), vb = read<Vec3>(*s, b, "velocity");
    const double r = length(read<Vec3>(*s, b, "position") - read<Vec3>(*s, a, "position"));
    return 0.5 * kOrbitM1 * dot(va, va) + 0.5 * kOrbitM2 * dot(vb, vb) -
           kOrbitG * kOrbitM1 * kOrbitM2 / r;
  };
  const double e0 = 0.5 * kOrbitM1 * std::pow(vrel * kOrbitM2 / M, 2) +
                    0.5 * kOrbitM2 * std::pow(vrel * kOrbitM1 / M, 2) -
                    kOrbitG * kOrbitM1 * kOrbitM2 / d;
  const std::uint64_t n = steps_for(orbits * orbit_period(), dt);
  Result r;
  r.energy_drift = 0;
  run_timed(*s, n, r, [&](std::uint64_t i) {
    r.energy_drift = std::max(r.energy_drift, std::abs(energy() - e0) / std::abs(e0));
    if (i == n) {
      const double phase = 2 * kPi * double(i) * dt / orbit_period();
      const Vec3 exact{d * std::cos(phase), d * std::sin(phase), 0};
      const Vec3 sep = read<Vec3>(*s, b, "position") - read<Vec3>(*s, a, "position");
      r.error = length(sep - exact) / d;
    }
  });
  return r;
}

Result run_rl(double dt, const Method& m, double seconds) {
  Sim s(world_def(dt, m));
  World& w = *s;
  const double e = 6.0, rb = 0.1, rc = 5.9, l = 0.06, wire_r = 0.01;
  const double r_total = rb + rc + 2 * wire_r, tau = l / r_total;
  const ObjectId battery = w.create("battery");
  w.set(battery, "emf", e);
  w.set(battery, "internal_resistance", rb);
  const ObjectId coil = w.create("coil");
  w.set(coil, "inductance", l);
  w.set(coil, "resistance", rc);
  for (auto [name, from, ft, to, tt] :
       {std::tuple{"w1", battery, 1, coil, 0}, std::tuple{"w2", coil, 1, battery, 0}}) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
    w.set(id, "resistance", wire_r);
  }
  Result r;
  const double i_inf = e / r_total;
  run_timed(w, steps_for(seconds, dt), r, [&](std::uint64_t i) {
    const double t = double(i) * dt;
    const double exact = i_inf * (1 - std::exp(-t / tau));
    r.error = std::max(r.error, std::abs(read<double>(w, coil, "current") - exact) / i_inf);
  });
  return r;
}

double magnet_force(double x) {
  // Written out from docs/magnetism.md rather than called, so that the
  // reference does not share a slip with the resolver: poles +q and -q at
  // +-s/2 along each bar's axis, force q1 q2 mu0/(4 pi) r / (r^2 + eps^2)^1.5.
  const double s = magnetism::kMagneticLengthRatio * kMagnetLength;
  const double eps = magnetism::MagneticForces::kDefaultSoftening;
  const double mu = 1.25663706212e-6 / (4 * kPi);
  // Fixed bar, axis +x: north at +s/2, south at -s/2. Free bar, axis -x
  // (turned half round): north at x - s/2, south at x + s/2.
  const std::array<std::pair<double, double>, 2> fixed = {
      {{s / 2, kMagnetPole}, {-s / 2, -kMagnetPole}}};
  const std::array<std::pair<double, double>, 2> free = {
      {{x - s / 2, kMagnetPole}, {x + s / 2, -kMagnetPole}}};
  double f = 0;
  for (const auto& [xf, qf] : fixed)
    for (const auto& [xm, qm] : free) {
      const double r = xm - xf;
      f += mu * qf * qm * r / std::pow(r * r + eps * eps, 1.5);
    }
  return f;
}

Result run_magnets(double dt, const Method& m, double seconds) {
  Sim s(world_def(dt, m, /*gravity=*/false));
  World& w = *s;
  const PropertyRegistry& reg = w.properties();
  auto magnet = [&](const std::string& name, double x, double angle) {
    const ObjectId id = w.create(name);
    w.set(id, "position", Vec3{x, 0, 0});
    w.set(id, "orientation", Quat::from_angle_z(angle));
    w.set(id, "shape", *reg.enum_value(reg.id("shape"), "box"));
    w.set(id, "size", Vec3{kMagnetLength, 0.02, 0.02});
    w.set(id, magnetism::prop::kMagnet, EnumValue{std::int32_t(magnetism::MagnetKind::Permanent)});
    w.set(id, magnetism::prop::kPoleStrength, kMagnetPole);
    return id;
  };
  magnet("fixed", 0, 0);  // no mass: the rigid body does not move it
  const ObjectId mover = magnet("free", kMagnetStart, kPi);
  w.set(mover, "mass", kMagnetMass);

  const std::uint64_t n = steps_for(seconds, dt);
  std::vector<double> ref(n + 1);
  {
    const int sub = substeps_within(dt, 1e-5);
    const double h = dt / sub;
    double x = kMagnetStart, v = 0;
    ref[0] = x;
    auto acc = [](double p) { return magnet_force(p) / kMagnetMass; };
    for (std::uint64_t i = 1; i <= n; ++i) {
      for (int j = 0; j < sub; ++j) {
        const double k1x = v, k1v = acc(x);
        const double k2x = v + h / 2 * k1v, k2v = acc(x + h / 2 * k1x);
        const double k3x = v + h / 2 * k2v, k3v = acc(x + h / 2 * k2x);
        const double k4x = v + h * k3v, k4v = acc(x + h * k3x);
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
        v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      }
      ref[i] = x;
    }
  }
  Result r;
  run_timed(w, n, r, [&](std::uint64_t i) {
    r.error = std::max(r.error, std::abs(read<Vec3>(w, mover, "position").x - ref[i]));
  });
  return r;
}

// --- induction (issue 13) ---------------------------------------------------------------

namespace {

constexpr double kInductionMass = 0.5, kInductionV0 = 0.5, kInductionX0 = -0.4;
constexpr double kCoilL = 0.01, kCoilR = 3.0, kLoopWireR = 0.01;

/// The near zone's window on the axis at z (the coil's frame): 1 within l/2
/// + 2a of the centre, fading to 0 over 3 more radii with the quintic
/// smoothstep's complement, as solenoid_field.cpp's near_window has it.
double near_zone(double z, double a, double l) {
  const double s = (std::abs(z) - (l / 2 + 2 * a)) / (3 * a);
  if (s <= 0) return 1;
  if (s >= 1) return 0;
  return 1 - s * s * s * (10 - 15 * s + 6 * s * s);
}

}  // namespace

double induction_flux(double x, double turns, bool near_field) {
  const double l = kInductionCoilPoles, eps = magnetism::MagneticForces::kDefaultSoftening;
  const double a = std::sqrt(kInductionCoilFactor * l / kPi);
  const double mu0 = 4 * kPi * magnetism::kMu0Over4Pi;
  // Per unit pole at z on the axis: the pole pair's potential difference
  // between the coil's ends, softened like the force law ...
  auto pair = [&](double z) {
    auto inverse = [&](double end) { return 1 / std::sqrt((end - z) * (end - z) + eps * eps); };
    return kInductionCoilFactor * turns * magnetism::kMu0Over4Pi *
           (inverse(-l / 2) - inverse(l / 2));
  };
  // ... and the sheet's: each turn's flux through its disk, q mu0 Omega /
  // (4 pi), integrated over the winding, Omega(u) = 2 pi sign(u) (1 - |u| /
  // sqrt(u^2 + a^2)) for a turn u beyond the pole along the axis.
  auto g = [&](double u) { return std::abs(u) - std::sqrt(u * u + a * a); };
  auto sheet = [&](double z) { return mu0 * turns / (2 * l) * (g(l / 2 - z) - g(l / 2 + z)); };
  double phi = 0;
  for (const auto& [z, q] : {std::pair{x + kInductionPoles / 2, kInductionQ},
                             std::pair{x - kInductionPoles / 2, -kInductionQ}}) {
    const double w = near_field ? near_zone(z, a, l) : 0.0;
    phi += q * (pair(z) + w * (sheet(z) - pair(z)));
  }
  if (near_field) {  // the magnet's own flux through the turns its segment crosses
    const double inside =
        std::min(x + kInductionPoles / 2, l / 2) - std::max(x - kInductionPoles / 2, -l / 2);
    phi += mu0 * turns / l * kInductionQ * std::max(inside, 0.0);
  }
  return phi;
}

double induction_gradient(double x, double turns, bool near_field) {
  const double h = 1e-7;
  return (induction_flux(x + h, turns, near_field) - induction_flux(x - h, turns, near_field)) /
         (2 * h);
}

std::pair<double, double> induction_steepest(double turns, bool near_field) {
  double best = 0, at = 0;
  for (int i = 1; i <= 10000; ++i) {
    const double x = -1e-5 * i;
    const double g = induction_gradient(x, turns, near_field);
    if (std::abs(g) > std::abs(best)) best = g, at = x;
  }
  return {at, best};
}

Result run_induction(double dt, const Method& m, double seconds, double turns,
                     std::vector<double>* current_out) {
  Sim s(world_def(dt, m, /*gravity=*/false));
  World& w = *s;
  const PropertyRegistry& reg = w.properties();
  const EnumValue box = *reg.enum_value(reg.id("shape"), "box");
  const ObjectId coil = w.create("coil");
  w.set(coil, "position", Vec3{0, 0, 0});
  w.set(coil, magnetism::prop::kMagnet,
        EnumValue{std::int32_t(magnetism::MagnetKind::Electromagnet)});
  w.set(coil, magnetism::prop::kTurns, turns);
  w.set(coil, magnetism::prop::kCoilFactor, kInductionCoilFactor);
  w.set(coil, magnetism::prop::kPoleSeparation, kInductionCoilPoles);
  w.set(coil, "inductance", kCoilL);
  w.set(coil, "resistance", kCoilR);
  const ObjectId wire = w.create("wire");
  w.set(wire, "wire_from", coil);
  w.set(wire, "wire_from_terminal", std::int64_t(0));
  w.set(wire, "wire_to", coil);
  w.set(wire, "wire_to_terminal", std::int64_t(1));
  w.set(wire, "resistance", kLoopWireR);
  const ObjectId magnet = w.create("magnet");
  w.set(magnet, "position", Vec3{kInductionX0, 0, 0});
  w.set(magnet, "shape", box);
  w.set(magnet, "size", Vec3{0.02, 0.01, 0.01});
  w.set(magnet, "mass", kInductionMass);
  w.set(magnet, "velocity", Vec3{kInductionV0, 0, 0});
  w.set(magnet, magnetism::prop::kMagnet,
        EnumValue{std::int32_t(magnetism::MagnetKind::Permanent)});
  w.set(magnet, magnetism::prop::kPoleStrength, kInductionQ);
  w.set(magnet, magnetism::prop::kPoleSeparation, kInductionPoles);

  const std::uint64_t n = steps_for(seconds, dt);
  const double r_loop = kCoilR + kLoopWireR;
  // The reference depends on dt, seconds, the turns and the flux model
  // only: kept between calls (the work-precision bench repeats a run many
  // times for its timing). The sheet's unless the scene turns it off.
  const bool near_field = m.near_field != 0;
  struct Reference {
    std::vector<double> current;
    double peak = 0, v_end = 0;
  };
  static std::map<std::tuple<double, double, double, bool>, Reference> cache;
  Reference& cached = cache[{dt, seconds, turns, near_field}];
  std::vector<double>& ref = cached.current;
  double& peak = cached.peak;
  double& v_end = cached.v_end;
  if (ref.empty()) {
    ref.assign(n + 1, 0.0);
    // State (x, v, I); the field's force on the magnet is I dPhi/dx, the
    // EMF -dPhi/dx v (flux_linkage.hpp: the same coupling, both ways).
    const int sub = substeps_within(dt, 2e-6);
    const double h = dt / sub;
    std::array<double, 3> y{kInductionX0, kInductionV0, 0.0};
    auto f = [&](const std::array<double, 3>& z) {
      const double g = induction_gradient(z[0], turns, near_field);
      return std::array<double, 3>{z[1], z[2] * g / kInductionMass,
                                   (-g * z[1] - r_loop * z[2]) / kCoilL};
    };
    auto add = [](std::array<double, 3> a, const std::array<double, 3>& b, double k) {
      for (int j = 0; j < 3; ++j) a[j] += k * b[j];
      return a;
    };
    for (std::uint64_t i = 1; i <= n; ++i) {
      for (int j = 0; j < sub; ++j) {
        const auto k1 = f(y), k2 = f(add(y, k1, h / 2)), k3 = f(add(y, k2, h / 2)),
                   k4 = f(add(y, k3, h));
        for (int c = 0; c < 3; ++c) y[c] += h / 6 * (k1[c] + 2 * k2[c] + 2 * k3[c] + k4[c]);
      }
      ref[i] = y[2];
      peak = std::max(peak, std::abs(y[2]));
    }
    v_end = y[1];
  }
  Result r;
  run_timed(w, n, r, [&](std::uint64_t i) {
    const double current = std::get<double>(w.get(coil, "current"));
    r.error = std::max(r.error, std::abs(current - ref[i]));
    if (current_out) current_out->push_back(current);
  });
  r.error /= peak;
  r.measured = read<Vec3>(w, magnet, "velocity").x;
  r.exact = v_end;
  return r;
}

// --- closed-form cases (issue 12) -------------------------------------------------------

namespace {

constexpr double kSteel = 7850;  // kg/m^3

double sphere_mass(double r, double density = kSteel) {
  return density * 4.0 / 3.0 * kPi * r * r * r;
}

/// A frictionless ball with the given restitution.
ObjectId add_ball(World& w, Vec3 at, double r, double mass, double restitution,
                  const std::string& name) {
  const ObjectId b = add_sphere(w, at, r, mass, name);
  w.set(b, "restitution", restitution);
  w.set(b, "friction", 0.0);
  return b;
}

}  // namespace

double elliptic_k(double k) {
  double a = 1, b = std::sqrt(1 - k * k);
  for (int i = 0; i < 40 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double an = (a + b) / 2;
    b = std::sqrt(a * b), a = an;
  }
  return kPi / (2 * a);
}

Result run_elastic_pair(double dt, const Method& m, double ratio) {
  Sim s(world_def(dt, m, /*gravity=*/false));
  const double r = 0.05;
  const ObjectId a = add_ball(*s, {-0.2, 0, 0}, r, ratio, 1.0, "a");
  const ObjectId b = add_ball(*s, {0, 0, 0}, r, 1.0, 1.0, "b");
  s->set(a, "velocity", Vec3{1, 0, 0});
  const double va = (ratio - 1) / (ratio + 1), vb = 2 * ratio / (ratio + 1);
  Result r_;
  const std::uint64_t n = steps_for(0.3, dt);
  run_timed(*s, n, r_, [&](std::uint64_t i) {
    if (i != n) return;
    const Vec3 ua = read<Vec3>(*s, a, "velocity"), ub = read<Vec3>(*s, b, "velocity");
    r_.error = std::max(length(ua - Vec3{va, 0, 0}), length(ub - Vec3{vb, 0, 0}));
    r_.measured = ub.x, r_.exact = vb;
    const double p0 = ratio, e0 = 0.5 * ratio;
    const double e1 = 0.5 * ratio * dot(ua, ua) + 0.5 * dot(ub, ub);
    r_.energy_drift = std::abs(e1 - e0) / e0;
    r_.momentum_drift = std::abs(ratio * ua.x + ub.x - p0) / p0;
  });
  return r_;
}

Result run_cradle(double dt, const Method& m) {
  Sim s(world_def(dt, m, /*gravity=*/false));
  const double r = 0.025, mass = sphere_mass(r);
  std::vector<ObjectId> balls;
  for (int i = 0; i < 5; ++i) {
    // The first 1 cm from the second; the others touching.
    const double x = i == 0 ? -(2 * r + 0.01) : 2 * r * (i - 1);
    balls.push_back(add_ball(*s, {x, 0, 0}, r, mass, 1.0, "ball" + std::to_string(i)));
  }
  s->set(balls[0], "velocity", Vec3{1, 0, 0});
  Result res;
  const std::uint64_t n = steps_for(0.2, dt);
  run_timed(*s, n, res, [&](std::uint64_t i) {
    if (i != n) return;
    double e = 0;
    for (std::size_t k = 0; k < balls.size(); ++k) {
      const Vec3 v = read<Vec3>(*s, balls[k], "velocity");
      const Vec3 exact{k + 1 == balls.size() ? 1.0 : 0.0, 0, 0};
      res.error = std::max(res.error, length(v - exact));
      e += 0.5 * mass * dot(v, v);
    }
    res.measured = read<Vec3>(*s, balls.back(), "velocity").x, res.exact = 1;
    res.energy_drift = std::abs(e / (0.5 * mass) - 1);
  });
  return res;
}

Result run_bounce(double dt, const Method& m, double e) {
  Sim s(world_def(dt, m));
  const Bounce b = build_bounce(*s, 1.0, e);
  bool rebounded = false, done = false;
  double top = -1;
  Result res;
  run_timed(*s, steps_for(2.5, dt), res, [&](std::uint64_t) {
    if (done) return;
    const double vy = read<Vec3>(*s, b.ball, "velocity").y;
    const double y = read<Vec3>(*s, b.ball, "position").y - b.radius;
    if (!rebounded && vy > 0) rebounded = true;
    if (!rebounded) return;
    if (vy < 0) done = true;
    top = std::max(top, y);
  });
  res.measured = top / b.drop, res.exact = e * e;
  res.error = std::abs(res.measured / res.exact - 1);
  return res;
}

namespace {

struct SwingBody {
  double mass, d, inertia;  // kg; pivot to centre, m; about the pivot, kg m^2
};

SwingBody swing_body(bool lever) {
  if (lever) {
    const double r = 0.02, mass = sphere_mass(r), d = 1.0;
    return {mass, d, mass * (d * d + 0.4 * r * r)};
  }
  BarPendulum p;
  const double d = p.length / 2;
  return {p.mass, d, p.mass * (p.length * p.length + p.width * p.width) / 12 + p.mass * d * d};
}

}  // namespace

double swing_period(bool lever, double theta0) {
  const SwingBody sb = swing_body(lever);
  return 4 * std::sqrt(sb.inertia / (sb.mass * kG * sb.d)) * elliptic_k(std::sin(theta0 / 2));
}

Result run_swing(double dt, const Method& m, bool lever, double theta0, int periods, bool planar) {
  Sim s(world_def(dt, m));
  const SwingBody sb = swing_body(lever);
  ObjectId body;
  if (lever) {
    const double angle = -kPi / 2 + theta0;
    body =
        add_sphere(*s, {sb.d * std::cos(angle), sb.d * std::sin(angle), 0}, 0.02, sb.mass, "ball");
    s->set(body, "planar", planar);
    add_hinge(*s, body, {}, {0, 0, 0}, {0, 0, 1}, "pivot");
  } else {
    body = build_bar_pendulum(*s, 1.0, theta0).bar;
    s->set(body, "planar", planar);
  }
  const double exact = swing_period(lever, theta0);
  const double e_swing = sb.mass * kG * sb.d * (1 - std::cos(theta0));
  auto energy = [&] {
    const Vec3 x = read<Vec3>(*s, body, "position"), v = read<Vec3>(*s, body, "velocity");
    const Vec3 w = read<Vec3>(*s, body, "angular_velocity");
    const double i_centre = sb.inertia - sb.mass * sb.d * sb.d;
    return 0.5 * sb.mass * dot(v, v) + 0.5 * i_centre * dot(w, w) + sb.mass * kG * x.y;
  };
  const double e0 = -sb.mass * kG * sb.d * std::cos(theta0);
  std::vector<double> crossings, crossing_energy;
  double prev = theta0, prev_e = e0;
  Result r;
  r.stretch = 0;
  double wobble = 0;
  run_timed(*s, steps_for((periods + 0.3) * exact, dt), r, [&](std::uint64_t i) {
    const Vec3 c = read<Vec3>(*s, body, "position");
    const double a = std::atan2(c.x, -c.y);  // from hanging straight down
    // Upward (increasing) zero crossings, interpolated within the step.
    const double e = energy();
    if (prev < 0 && a >= 0) {
      const double f = prev / (prev - a);  // of the step, where it crossed
      crossings.push_back((double(i) - 1 + f) * dt);
      crossing_energy.push_back(prev_e + f * (e - prev_e));
    }
    prev = a;
    prev_e = e;
    r.stretch = std::max(r.stretch, std::abs(length(c) / sb.d - 1));
    if (!planar) {
      // Off the play area the hinge holds the plane too: the centre's
      // distance from it, and the tilt of the body's z axis (rad).
      const Vec3 z = rotate(read<Quat>(*s, body, "orientation"), Vec3{0, 0, 1});
      r.stretch = std::max({r.stretch, std::abs(c.z) / sb.d, length(cross(z, Vec3{0, 0, 1}))});
    }
    wobble = std::max(wobble, std::abs(e - e0) / e_swing);
  });
  if (crossings.size() >= 2) {
    r.measured = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
    r.error = std::abs(r.measured / exact - 1);
  } else {
    r.error = 1;  // never swung through: as wrong as it gets
  }
  r.exact = exact;
  // The drift: the energy at the same phase of the swing (passing the bottom
  // upwards) period after period, per period. Within a period the energy
  // also swings by O(h) about its mean (r.energy_wobble): the semi-implicit
  // Euler step conserves a nearby energy, not this one.
  r.energy_drift = 0;
  for (std::size_t k = 1; k < crossing_energy.size(); ++k)
    r.energy_drift = std::max(
        r.energy_drift, std::abs(crossing_energy[k] - crossing_energy[0]) / e_swing / double(k));
  if (crossing_energy.size() < 2) r.energy_drift = 1;
  r.energy_wobble = wobble;
  return r;
}

Result run_heavy_chain(double dt, const Method& m) {
  Sim s(world_def(dt, m));
  constexpr int kLinks = 5;
  const double link = 0.1, theta0 = kPi / 3;
  const Vec3 dir{std::sin(theta0), -std::cos(theta0), 0};  // down the chain
  const double angle = std::atan2(dir.y, dir.x);
  std::vector<ObjectId> links;
  ObjectId prev;
  for (int i = 0; i < kLinks; ++i) {
    const ObjectId l = add_box(*s, (i + 0.5) * link * dir, {link, 0.01, 0.01}, 0.01,
                               Quat::from_angle_z(angle), "link" + std::to_string(i));
    s->set(l, "planar", true);
    add_hinge(*s, l, prev, i * link * dir, {0, 0, 1});
    links.push_back(prev = l);
  }
  const double total = kLinks * link;
  const ObjectId ball = add_sphere(*s, total * dir, 0.05, 10.0, "ball");
  s->set(ball, "planar", true);
  add_hinge(*s, ball, prev, total * dir, {0, 0, 1});
  // The energy of every body (planar: the turn about z), against the
  // weight's swing m g L (1 - cos theta0) as scale.
  std::vector<ObjectId> all = links;
  all.push_back(ball);
  auto energy = [&] {
    double e = 0;
    for (const ObjectId b : all) {
      const double m = read<double>(*s, b, "mass");
      const Vec3 v = read<Vec3>(*s, b, "velocity"), w = read<Vec3>(*s, b, "angular_velocity");
      const double i_z = b == ball ? 0.4 * m * 0.05 * 0.05 : m * (link * link + 0.01 * 0.01) / 12;
      e += 0.5 * m * dot(v, v) + 0.5 * i_z * w.z * w.z + m * kG * read<Vec3>(*s, b, "position").y;
    }
    return e;
  };
  const double swing = 10.0 * kG * total * (1 - std::cos(theta0));
  double e0 = 0;
  bool first = true;
  Result r;
  r.stretch = 0;
  r.energy_drift = 0;
  run_timed(*s, steps_for(3.0, dt), r, [&](std::uint64_t) {
    const double e = energy();
    if (first) e0 = e, first = false;
    r.energy_drift = std::max(r.energy_drift, std::abs(e - e0) / swing);
    // Each joint's gap: where one link's end is against where the next begins.
    double gaps = 0;
    Vec3 end{0, 0, 0};
    for (const ObjectId l : links) {
      const Vec3 c = read<Vec3>(*s, l, "position");
      const Vec3 half = rotate(read<Quat>(*s, l, "orientation"), Vec3{link / 2, 0, 0});
      gaps += length(c - half - end);
      end = c + half;
    }
    gaps += length(read<Vec3>(*s, ball, "position") - end);
    r.stretch = std::max(r.stretch, gaps / total);
  });
  r.error = r.stretch;
  return r;
}

}  // namespace alloy::scenes::analytic

// --- rolling (issue 12, the kit's cylinder) ----------------------------------------------

namespace alloy::scenes::analytic {

Result run_rolling(double dt, const Method& m, bool cylinder) {
  Sim s(world_def(dt, m));
  constexpr double r = 0.05, thickness = 0.02, seconds = 1.0;
  const double theta = kRollSlope;
  // Down the slope, and out of it (the slope's top face turned by -theta).
  const Vec3 down{std::cos(theta), -std::sin(theta), 0}, out{std::sin(theta), std::cos(theta), 0};
  const ObjectId slope = s->create("slope");
  s->set(slope, "shape", std::string("box"));
  s->set(slope, "size", Vec3{6, 0.2, 1});
  s->set(slope, "position", Vec3{});
  s->set(slope, "orientation", Quat::from_angle_z(-theta));
  s->set(slope, "static", true);
  // Touching the slope, 2 m up it.
  const Vec3 start = out * (0.1 + r) - down * 2.0;
  ObjectId part;
  if (cylinder) {
    part = s->create("disk");
    s->set(part, "shape", std::string("cylinder"));
    s->set(part, "radius", r);
    s->set(part, "length", thickness);
    s->set(part, "density", 7800.0);
    s->set(part, "position", start);
  } else {
    part = add_sphere(*s, start, r, 7800.0 * 4.0 / 3.0 * kPi * r * r * r, "ball");
  }
  s->set(part, "planar", true);
  const std::uint64_t n = steps_for(seconds, dt);
  Result res;
  res.stretch = 0;
  run_timed(*s, n, res, [&](std::uint64_t i) {
    if (2 * i < n) return;
    const Vec3 v = read<Vec3>(*s, part, "velocity"), w = read<Vec3>(*s, part, "angular_velocity");
    const Vec3 rim = v + cross(w, out * -r);  // the contact point's velocity
    res.stretch = std::max(res.stretch, length(rim) / std::max(length(v), 1e-12));
  });
  const double speed = dot(read<Vec3>(*s, part, "velocity"), down);
  res.measured = speed / (double(n) * dt) / (kG * std::sin(theta));
  res.exact = cylinder ? 2.0 / 3.0 : 5.0 / 7.0;
  res.error = std::abs(res.measured / res.exact - 1);
  return res;
}

}  // namespace alloy::scenes::analytic
