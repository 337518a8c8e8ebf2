#include "resolvers/magnetism/magnetic_forces.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <tuple>

#include "resolvers/common/direct_kernel.hpp"
#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/solenoid_field.hpp"

namespace alloy::magnetism {

double sampled_force_error(std::span<const Pole> poles, std::span<const MagneticBody> bodies,
                           std::span<const Vec3> approx, double softening) {
  std::vector<std::uint32_t> with_poles;
  for (std::uint32_t b = 0; b < bodies.size(); ++b)
    if (bodies[b].pole_count > 0) with_poles.push_back(b);
  const std::size_t m = with_poles.size(), parts = std::min(m, kAutoCheckParts);
  if (parts == 0) return 0;
  std::vector<double> sx(poles.size()), sy(poles.size()), sz(poles.size()), sq(poles.size()),
      sg(poles.size());
  for (std::size_t i = 0; i < poles.size(); ++i) {
    sx[i] = poles[i].position.x, sy[i] = poles[i].position.y, sz[i] = poles[i].position.z;
    sq[i] = poles[i].strength, sg[i] = double(poles[i].body);
  }
  std::vector<std::uint32_t> target;  // pole indices
  for (std::size_t k = 0; k < parts; ++k) {
    const MagneticBody& b = bodies[with_poles[k * m / parts]];
    for (std::uint32_t i = b.first_pole; i < b.first_pole + b.pole_count; ++i) target.push_back(i);
  }
  const std::size_t t = target.size();
  std::vector<double> tx(t), ty(t), tz(t), tg(t), fx(t, 0.0), fy(t, 0.0), fz(t, 0.0);
  for (std::size_t j = 0; j < t; ++j) {
    const Pole& p = poles[target[j]];
    tx[j] = p.position.x, ty[j] = p.position.y, tz[j] = p.position.z, tg[j] = double(p.body);
  }
  multipole::direct_accumulate({.x = tx.data(),
                                .y = ty.data(),
                                .z = tz.data(),
                                .g = tg.data(),
                                .fx = fx.data(),
                                .fy = fy.data(),
                                .fz = fz.data(),
                                .n = t},
                               {.x = sx.data(),
                                .y = sy.data(),
                                .z = sz.data(),
                                .q = sq.data(),
                                .g = sg.data(),
                                .n = poles.size()},
                               softening * softening);
  double num = 0, den = 0;
  for (std::size_t j = 0; j < t;) {
    const std::uint32_t body = poles[target[j]].body;
    Vec3 exact{}, fast{};
    for (; j < t && poles[target[j]].body == body; ++j) {
      exact += Vec3{fx[j], fy[j], fz[j]} * (kMu0Over4Pi * poles[target[j]].strength);
      fast += approx[target[j]];
    }
    num += dot(fast - exact, fast - exact);
    den += dot(exact, exact);
  }
  if (den == 0) return num == 0 ? 0 : INFINITY;
  return std::sqrt(num / den);
}

double iron_coenergy_ratio(double ratio) {
  // m = m_s tanh(x) for a linear moment m_s x, so x = atanh(|m| / m_s); the
  // co-energy mu0 int_0^H m dh is mu0 m_s^2 / (chi V) ln cosh x and m . H is
  // m_s^2 / (chi V) x tanh x. Below x = 1e-4 the series 1/2 + x^2/12 is exact
  // to rounding; at full saturation the co-energy is all of m . H.
  if (!(ratio > 0)) return 0.5;
  if (!(ratio < 1)) return 1.0;
  const double x = std::atanh(ratio);
  if (x < 1e-4) return 0.5 + x * x / 12;
  return std::log(std::cosh(x)) / (x * std::tanh(x));
}

double theta_for_tolerance(double tolerance) {
  // (theta, RMS relative force error) on the packed block of 25 x 20 x 20
  // bars, blocked tree with leaves of 64 (bench/scaling.cpp --magnets).
  static constexpr double kMeasured[][2] = {{0.15, 1.0e-5}, {0.20, 4.4e-5}, {0.25, 1.6e-4},
                                            {0.30, 3.1e-4}, {0.35, 7.9e-4}, {0.40, 1.9e-3},
                                            {0.50, 4.6e-3}, {0.60, 1.1e-2}, {0.70, 3.8e-2}};
  const double tol = std::clamp(tolerance, 1e-5, 0.1);
  double theta = kMeasured[0][0];
  for (const auto& [t, e] : kMeasured)
    if (e <= tol) theta = t;
  return theta;
}

const MagneticBody* MagneticForces::find(ObjectId id) const {
  if (id.index >= body_of_slot_.size() || body_of_slot_[id.index] == kNoBody) return nullptr;
  const MagneticBody& b = bodies_[body_of_slot_[id.index]];
  return b.id == id ? &b : nullptr;
}

std::vector<MagneticForces::PartPose> MagneticForces::poses() const {
  std::vector<PartPose> out(frames_.size());
  for (std::size_t b = 0; b < frames_.size(); ++b) {
    out[b].centre = frames_[b].centre;
    for (int i = 0; i < 3; ++i) out[b].axes[i] = frames_[b].axes[i];
  }
  return out;
}

Vec3 MagneticForces::field(Vec3 point) const {
  Vec3 h;
  const std::uint32_t none = kNoBody;
  // One point: the direct sum is cheaper than building a tree.
  pole_fields(poles_, softening_, std::span(&point, 1), std::span(&none, 1), std::span(&h, 1));
  return h * kMu0;
}

bool MagneticForces::due_check() const {
  if (checked_at_.size() != poles_.size() || since_check_ >= summation_.check_every) return true;
  // The share of parts that moved far: one magnet snapping onto another (tens
  // of m/s) does not change the error of thousands, a block assembling does.
  std::size_t parts = 0, moved = 0;
  for (const MagneticBody& b : bodies_) {
    if (b.pole_count != 2) continue;
    ++parts;
    const std::uint32_t i = b.first_pole;
    const Vec3 n = poles_[i].position, s = poles_[i + 1].position;
    const double limit2 = kAutoCheckMove * kAutoCheckMove * dot(n - s, n - s);
    const Vec3 dn = n - checked_at_[i], ds = s - checked_at_[i + 1];
    if (!(dot(dn, dn) <= limit2) || !(dot(ds, ds) <= limit2)) ++moved;
  }
  return !(double(moved) <= kAutoCheckMovedShare * double(parts));
}

std::vector<InducedPart> MagneticForces::induced_parts(const std::vector<Frame>& at) const {
  std::vector<InducedPart> parts(models_.size());
  for (std::uint32_t b = 0; b < iron_of_.size(); ++b) {
    if (iron_of_[b] < 0) continue;
    const SoftIronModel& m = models_[std::size_t(iron_of_[b])];
    InducedPart& p = parts[std::size_t(iron_of_[b])];
    p.centre = at[b].centre;
    for (int i = 0; i < 3; ++i) p.axes[i] = at[b].axes[i];
    p.susceptibility[0] = m.susceptibility.x, p.susceptibility[1] = m.susceptibility.y,
    p.susceptibility[2] = m.susceptibility.z;
    p.separation[0] = m.separation.x, p.separation[1] = m.separation.y,
    p.separation[2] = m.separation.z;
    p.volume = m.volume;
    p.saturation = m.saturation;
    p.body = b;
  }
  return parts;
}

std::vector<Pole> MagneticForces::fixed_poles(const std::vector<Frame>& at,
                                              const std::vector<double>& q) const {
  std::vector<Pole> out;
  for (std::uint32_t b = 0; b < q.size(); ++b) {
    if (q[b] == 0) continue;
    const BarPoles p = bar_poles(at[b].centre, at[b].axes[0], at[b].separation);
    out.push_back({p.north, q[b], b});
    out.push_back({p.south, -q[b], b});
  }
  return out;
}

// Every body's one pole pair: a magnet's or a coil's along its x axis (a
// coil's core adds its axial moment to it); free iron's along its moment,
// spread over the part's chord in that direction, so that a sphere's poles
// do not depend on how it is turned.
std::vector<MagneticForces::PolePair> MagneticForces::pole_pairs(
    const std::vector<Frame>& at, const std::vector<double>& q,
    const std::vector<Vec3>& moment) const {
  std::vector<PolePair> out(q.size());
  for (std::uint32_t b = 0; b < q.size(); ++b) {
    const Frame& f = at[b];
    out[b] = {f.axes[0], f.separation, q[b]};
    if (iron_of_[b] < 0) continue;
    const SoftIronModel& m = models_[std::size_t(iron_of_[b])];
    const Vec3 mb = moment[std::size_t(iron_of_[b])];
    if (m.axial_only) {
      out[b].strength += dot(mb, f.axes[0]) / f.separation;
      continue;
    }
    const double size = length(mb);
    if (!(size > 0) || !std::isfinite(size)) continue;
    const Vec3 u = mb / size;
    const double d = m.separation_along({dot(u, f.axes[0]), dot(u, f.axes[1]), dot(u, f.axes[2])});
    out[b] = {u, d, size / d};
  }
  return out;
}

std::vector<double> MagneticForces::magnets_only(const std::vector<double>& q) const {
  std::vector<double> out(q.size(), 0.0);
  for (std::size_t b = 0; b < q.size(); ++b)
    if (permanent_[b]) out[b] = q[b];
  return out;
}

void MagneticForces::append_induced_poles(const std::vector<Frame>& at,
                                          const std::vector<Vec3>& moment, double scale,
                                          std::vector<Pole>& out) const {
  const std::vector<double> none(at.size(), 0.0);
  const std::vector<PolePair> pairs = pole_pairs(at, none, moment);
  for (std::uint32_t b = 0; b < at.size(); ++b) {
    if (iron_of_[b] < 0 || pairs[b].strength == 0 || !std::isfinite(pairs[b].strength)) continue;
    const BarPoles p = bar_poles(at[b].centre, pairs[b].axis, pairs[b].separation);
    out.push_back({p.north, scale * pairs[b].strength, b});
    out.push_back({p.south, -scale * pairs[b].strength, b});
  }
}

void MagneticForces::emf_iron_poles(std::span<const PartPose> poses, std::vector<Pole>& out) const {
  out.clear();
  if (models_.empty() || poses.size() != frames_.size()) return;
  std::vector<Frame> at = frames_;
  for (std::size_t b = 0; b < at.size(); ++b) {
    at[b].centre = poses[b].centre;
    for (int i = 0; i < 3; ++i) at[b].axes[i] = poses[b].axes[i];
  }
  const std::vector<InducedPart> parts = induced_parts(at);
  const InductionResult with_currents =
      solve_induction(fixed_poles(at, fixed_strength_), parts, softening_, summation_);
  const std::vector<double> magnets = magnets_only(fixed_strength_);
  if (magnets == fixed_strength_) {  // no coil carries a current: one solve
    append_induced_poles(at, with_currents.moment, 1.0, out);
    return;
  }
  // The mean of the moments with the coils' currents and without them, as
  // two half-strength pairs (free iron's pair follows its moment, so the
  // two need not lie on one line): the flux whose change along the motion,
  // at the currents of now, makes the circuits pay for the work the iron's
  // forces do beyond the fall of its store in the magnets' field
  // (docs/magnetism.md "Induction through soft iron").
  append_induced_poles(at, with_currents.moment, 0.5, out);
  if (std::all_of(magnets.begin(), magnets.end(), [](double q) { return q == 0; }))
    return;  // no magnet: the moments without the currents are 0
  const InductionResult bare =
      solve_induction(fixed_poles(at, magnets), parts, softening_, summation_);
  append_induced_poles(at, bare.moment, 0.5, out);
}

void MagneticForces::update(const WorldView& world) {
  ++updates_;
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(world);
  const MagnetColumns c = MagnetColumns::bind(world, *ids_);
  const PropertyStore& store = world.store();

  bodies_.clear();
  poles_.clear();
  body_of_slot_.assign(store.slot_count(), kNoBody);
  sheet_body_.clear();

  // 1. Gather the parts: their frames, the fixed poles of magnets and coils,
  //    and the soft iron (free parts and coils' cores) whose moment depends
  //    on the field.
  std::vector<Frame>& frames = frames_;
  std::vector<double>& fixed_strength = fixed_strength_;  // per body: the magnet's or coil's own q
  std::vector<std::int32_t>& iron_of = iron_of_;  // per body: index in models / parts, or -1
  std::vector<SoftIronModel>& models = models_;
  frames.clear(), fixed_strength.clear(), iron_of.clear(), models.clear(), permanent_.clear();
  // Reserved: growing `frames` (104-byte records) by doubling copied them
  // element by element, a third of this function's own time at 10,000 parts
  // (perf, session 18).
  const std::size_t n_members = c.magnet.members().size();
  // A coil driven by a circuit is as strong as the circuit's current now:
  // the force of this update is the rigid body's kick at this instant, and
  // the current of this instant is the one the circuit's books pay the
  // induced EMF with (docs/magnetism.md "The coupling's timing"). Without
  // the setting, or with rates (the multi-rate hold) or a coil time
  // constant (the paper's "rapidly but not instantly"), the magnetism
  // resolver's pole strength, commanded a step before.
  std::optional<ColumnView<double>> circuit_current;
  if (coils_from_current_ && !rates_)
    if (const auto id = world.properties().find(prop::kCurrent))
      circuit_current = world.column<double>(*id);
  frames.reserve(n_members), fixed_strength.reserve(n_members), iron_of.reserve(n_members);
  bodies_.reserve(n_members), poles_.reserve(2 * n_members);
  for (std::uint32_t slot : c.magnet.members()) {
    const auto d = pole_separation(c, slot);
    if (!c.position.has(slot) || !d || !(*d > 0)) continue;  // the resolver's build names these
    const Vec3 centre = c.position[slot];
    const Quat o = c.orientation.value_or(slot, Quat{});
    Frame f{centre, {rotate(o, {1, 0, 0}), rotate(o, {0, 1, 0}), rotate(o, {0, 0, 1})}, *d};
    for (Vec3& a : f.axes) a = a / length(a);
    if (!is_finite(centre) || !is_finite(f.axes[0]) || !is_finite(f.axes[1]) ||
        !is_finite(f.axes[2]))
      continue;  // not ours to repair; never spread it

    body_of_slot_[slot] = std::uint32_t(bodies_.size());
    bodies_.push_back({.id = store.id_at(slot)});
    frames.push_back(f);
    fixed_strength.push_back(0.0);
    iron_of.push_back(-1);
    const MagnetKind kind = c.kind(slot);
    permanent_.push_back(kind == MagnetKind::Permanent ? 1 : 0);
    sheet_body_.push_back(near_field_ && kind == MagnetKind::Permanent ? 1 : 0);
    if (kind != MagnetKind::SoftIron) {
      double q = c.pole_strength.value_or(slot, 0.0);
      if (kind == MagnetKind::Electromagnet && circuit_current && circuit_current->has(slot) &&
          !(c.coil_time_constant.value_or(slot, 0.0) > 0))
        q = coil_factor(c, slot).value_or(0.0) * c.turns.value_or(slot, 0.0) *
            (*circuit_current)[slot];
      if (q != 0 && std::isfinite(q)) fixed_strength.back() = q;
    }
    if (kind == MagnetKind::SoftIron ||
        (kind == MagnetKind::Electromagnet && c.susceptibility.has(slot)))
      if (auto m = soft_iron_model(c, slot);
          m && (m->susceptibility.x > 0 || m->susceptibility.y > 0 || m->susceptibility.z > 0)) {
        iron_of.back() = std::int32_t(models.size());
        models.push_back(*m);
      }
  }
  const auto n_bodies = std::uint32_t(bodies_.size());
  auto induced_parts = [&](const std::vector<Frame>& at) { return this->induced_parts(at); };
  auto fixed_poles = [&](const std::vector<Frame>& at, const std::vector<double>& q) {
    return this->fixed_poles(at, q);
  };
  auto pole_pairs = [&](const std::vector<Frame>& at, const std::vector<double>& q,
                        const std::vector<Vec3>& moment) {
    return this->pole_pairs(at, q, moment);
  };

  // A free iron part's pole pair follows its induced moment, not the part, so
  // the pair's forces in a non-uniform field have a moment about the centre
  // that no turning of the part can change: a sphere on a frictionless pin
  // spun up for ever (its energy in the field does not depend on how it is
  // turned, so the torque must vanish), and a capsule about its own axis
  // likewise. The torque about every axis the part is symmetric about is
  // dropped; a box keeps the pair's torque (its chords, and so its energy,
  // do depend on how it is turned).
  auto keep_symmetric = [&](std::uint32_t b, const Frame& f, Vec3 torque) {
    if (iron_of[b] < 0) return torque;
    const SoftIronModel& m = models[std::size_t(iron_of[b])];
    if (m.axial_only) return torque;
    switch (m.bulk.shape) {
      case PartBulk::Shape::Sphere:
        return Vec3{};
      case PartBulk::Shape::Capsule:
        return torque - dot(torque, f.axes[0]) * f.axes[0];
      case PartBulk::Shape::Box:
      default:
        return torque;
    }
  };

  // 2. The moments the field induces in the iron, consistently with one another.
  //    Without iron there is nothing to solve: the fixed poles (one record
  //    per pole, 20,000 for 10,000 magnets) are only gathered for iron.
  const std::vector<InducedPart> parts = induced_parts(frames);
  const InductionResult induced =
      solve_induction(parts.empty() ? std::vector<Pole>{} : fixed_poles(frames, fixed_strength),
                      parts, softening_, summation_);
  if (!induced.converged && induction_converged_)
    world.emit({.type = "magnetic_induction_unconverged",
                .text = "soft-iron parts too strongly coupled for the pole model; using the "
                        "field of the magnets alone"});
  induction_iterations_ = induced.iterations;
  induction_converged_ = induced.converged;
  const std::vector<PolePair> pairs = pole_pairs(frames, fixed_strength, induced.moment);
  induced_moment_ = induced.moment;

  // 3. Every pole, grouped by part, north first.
  induced_share_.assign(n_bodies, 0.0);
  for (std::uint32_t b = 0; b < n_bodies; ++b) {
    bodies_[b].pole_strength = pairs[b].strength;
    // What of the strength the field induced: all of a soft-iron part's; a
    // cored coil's core beyond what its own current magnetises (the energy
    // books keep it apart from the coil's own, which its circuit pays for).
    if (iron_of[b] >= 0) {
      induced_share_[b] = pairs[b].strength - fixed_strength[b];
    }
    bodies_[b].first_pole = std::uint32_t(poles_.size());
    if (pairs[b].strength == 0) continue;
    const BarPoles p = bar_poles(frames[b].centre, pairs[b].axis, pairs[b].separation);
    poles_.push_back({p.north, pairs[b].strength, b});
    poles_.push_back({p.south, -pairs[b].strength, b});
    bodies_[b].pole_count = 2;
  }

  // A coil's near field as a finite solenoid (solenoid_field.hpp): a
  // correction on its pole pair for the permanent magnets' poles near it,
  // exactly zero beyond its zone. Coils with a current of their own only.
  auto near_coils = [&](const std::vector<Frame>& at, const std::vector<double>& q) {
    std::vector<NearCoil> out;
    for (std::uint32_t b = 0; b < n_bodies; ++b) {
      const std::uint32_t slot = bodies_[b].id.index;
      if (!near_field_ || q[b] == 0 || c.kind(slot) != MagnetKind::Electromagnet) continue;
      const auto k = coil_factor(c, slot);
      const double a = k ? coil_sheet_radius(c, slot, *k, at[b].separation) : 0.0;
      if (!(a > 0) || !std::isfinite(a)) continue;
      out.push_back(
          {{at[b].centre, at[b].axes[0], at[b].separation, a, 1 / (std::numbers::pi * a * a)},
           q[b],
           b});
    }
    return out;
  };

  // 4. Forces on poles, then force and torque about each part's centre.
  std::vector<Vec3> pole_force(poles_.size());
  // Auto (the default): from kFmmAutoPoles poles the FMM, which is the
  // fastest there on spread-out parts but several percent off on a packed
  // block of aligned bars (their near forces cancel; docs/magnetism.md "Fast
  // summation"). Its error is therefore measured against the direct sum on a
  // sample of parts (when kAutoCheckEvery says), and where it exceeds the
  // tolerance the evaluation is redone on the tree, whose theta is set for
  // that block.
  SummationOptions step = summation_;
  checked_ = false;
  if (summation_.method == Summation::Auto && poles_.size() >= kFmmAutoPoles) {
    step.method = Summation::Fmm;
    step.theta = kFmmTheta;
    accumulate_pole_forces(poles_, softening_, pole_force, step, &tree_);
    if (due_check()) {
      checked_ = true;
      ++checks_;
      last_check_error_ = sampled_force_error(poles_, bodies_, pole_force, softening_);
      since_check_ = 0;
      checked_at_.clear();
      if (last_check_error_ <= kAutoCheckMargin * summation_.tolerance)
        for (const Pole& p : poles_) checked_at_.push_back(p.position);
    }
    ++since_check_;
    if (!(last_check_error_ <= summation_.tolerance)) {
      step = summation_;
      std::fill(pole_force.begin(), pole_force.end(), Vec3{});
      accumulate_pole_forces(poles_, softening_, pole_force, step, &tree_);
    }
  } else {
    last_check_error_ = NAN;
    checked_at_.clear();
    accumulate_pole_forces(poles_, softening_, pole_force, step, &tree_);
  }
  used_method_ = !step.use_tree(poles_.size())   ? Summation::Direct
                 : step.method == Summation::Fmm ? Summation::Fmm
                                                 : Summation::Tree;
  used_tree_ = used_method_ != Summation::Direct;
  std::vector<Vec3> coil_force(n_bodies), coil_torque(n_bodies);
  add_near_forces(near_coils(frames, fixed_strength), poles_, sheet_body_, softening_, pole_force,
                  coil_force, coil_torque);
  for (std::uint32_t b = 0; b < n_bodies; ++b) {
    MagneticBody& body = bodies_[b];
    body.force += coil_force[b];
    body.torque += coil_torque[b];
    for (std::uint32_t i = body.first_pole; i < body.first_pole + body.pole_count; ++i) {
      body.force += pole_force[i];
      body.torque += cross(poles_[i].position - frames[b].centre, pole_force[i]);
    }
    body.torque = keep_symmetric(b, frames[b], body.torque);
    if (!is_finite(body.force) || !is_finite(body.torque)) {
      world.emit({.type = "magnetic_force_nonfinite",
                  .a = body.id,
                  .text = "magnetic force on the part is not finite; applying none"});
      body.force = {};
      body.torque = {};
    }
  }
  if (!rates_) return;

  // 5. Rates along the present motion: the same evaluation with every part
  //    moved on by kRateTime at its velocity and angular velocity (the
  //    induced moments solved again there, the fixed strengths held), as a
  //    forward difference. All parts move at once, so a pair of moving parts
  //    gets the rate of their mutual force, and the parts of one rigid
  //    assembly keep their relative places (their mutual forces cancel in the
  //    assembly's load as they do in its value).
  const auto velocity_id = world.properties().find("velocity");
  const auto spin_id = world.properties().find("angular_velocity");
  // The electromagnets' pole-strength rates (magnetism with rates = true):
  // a coil whose current is rising moves its poles' strength on as well.
  const auto q_rate = pole_strength_rate_.column<double>(world);
  std::vector<double> strength_rate(n_bodies, 0.0);
  bool any = false;
  for (std::uint32_t b = 0; b < n_bodies; ++b) {
    const std::uint32_t slot = bodies_[b].id.index;
    if (c.kind(slot) == MagnetKind::SoftIron || !q_rate.has(slot)) continue;
    const double r = q_rate[slot];
    if (r != 0 && std::isfinite(r)) strength_rate[b] = r, any = true;
  }
  if ((!velocity_id || !spin_id) && !any) return;  // nothing moves
  constexpr double kRateTime = 1e-5;  // s: micrometres at kit speeds, well inside the softening
  std::vector<Frame> moved = frames;
  if (velocity_id && spin_id) {
    const auto velocity = world.column<Vec3>(*velocity_id);
    const auto spin = world.column<Vec3>(*spin_id);
    for (std::uint32_t b = 0; b < n_bodies; ++b) {
      const std::uint32_t slot = bodies_[b].id.index;
      const Vec3 v = velocity.value_or(slot, Vec3{});
      const Vec3 w = spin.value_or(slot, Vec3{});
      if (!is_finite(v) || !is_finite(w) || (v == Vec3{} && w == Vec3{})) continue;
      any = true;
      moved[b].centre = frames[b].centre + kRateTime * v;
      for (int i = 0; i < 3; ++i) {
        const Vec3 axis = frames[b].axes[i] + kRateTime * cross(w, frames[b].axes[i]);
        moved[b].axes[i] = axis / length(axis);
      }
    }
  }
  if (!any) return;
  std::vector<double> fixed_moved_strength = fixed_strength;
  for (std::uint32_t b = 0; b < n_bodies; ++b)
    fixed_moved_strength[b] += kRateTime * strength_rate[b];
  const std::vector<InducedPart> parts_moved = induced_parts(moved);
  const InductionResult induced_moved = solve_induction(
      parts_moved.empty() ? std::vector<Pole>{} : fixed_poles(moved, fixed_moved_strength),
      parts_moved, softening_, summation_);
  const std::vector<PolePair> pairs_moved = pole_pairs(
      moved, fixed_moved_strength,
      induced_moved.converged || !induced.converged ? induced_moved.moment : induced.moment);
  std::vector<Pole> poles_moved;
  std::vector<std::uint32_t> first_moved(n_bodies, 0), count_moved(n_bodies, 0);
  poles_moved.reserve(poles_.size() + 2);
  for (std::uint32_t b = 0; b < n_bodies; ++b) {
    first_moved[b] = std::uint32_t(poles_moved.size());
    if (pairs_moved[b].strength == 0 || (bodies_[b].pole_count == 0 && strength_rate[b] == 0))
      continue;
    const BarPoles p = bar_poles(moved[b].centre, pairs_moved[b].axis, pairs_moved[b].separation);
    poles_moved.push_back({p.north, pairs_moved[b].strength, b});
    poles_moved.push_back({p.south, -pairs_moved[b].strength, b});
    count_moved[b] = 2;
  }
  std::vector<Vec3> force_moved(poles_moved.size());
  accumulate_pole_forces(poles_moved, softening_, force_moved, step, &tree_);
  std::vector<Vec3> coil_force_moved(n_bodies), coil_torque_moved(n_bodies);
  add_near_forces(near_coils(moved, fixed_moved_strength), poles_moved, sheet_body_, softening_,
                  force_moved, coil_force_moved, coil_torque_moved);
  for (std::uint32_t b = 0; b < n_bodies; ++b) {
    MagneticBody& body = bodies_[b];
    if (count_moved[b] == 0 ||
        (body.pole_count != 0 && body.force == Vec3{} && body.torque == Vec3{}))
      continue;
    Vec3 f = coil_force_moved[b], t = coil_torque_moved[b];
    for (std::uint32_t i = first_moved[b]; i < first_moved[b] + count_moved[b]; ++i) {
      f += force_moved[i];
      t += cross(poles_moved[i].position - moved[b].centre, force_moved[i]);
    }
    t = keep_symmetric(b, moved[b], t);
    const Vec3 df = (f - body.force) / kRateTime, dt = (t - body.torque) / kRateTime;
    if (is_finite(df) && is_finite(dt)) body.force_rate = df, body.torque_rate = dt;
  }
}

double MagneticForces::permanent_work_across_a_change(std::span<const Pole> poles,
                                                      std::span<const std::uint32_t> first,
                                                      std::span<const std::uint8_t> kinds) const {
  // The poles of the permanent magnets present at both reports, paired by
  // their part (its id) and their order within it (north, then south).
  auto key_less = [](const std::pair<ObjectId, std::uint32_t>& a,
                     const std::pair<ObjectId, std::uint32_t>& b) {
    return std::tie(a.first.index, a.first.generation, a.second) <
           std::tie(b.first.index, b.first.generation, b.second);
  };
  std::vector<std::pair<std::pair<ObjectId, std::uint32_t>, std::size_t>> now;
  for (std::size_t i = 0; i < poles.size(); ++i) {
    const std::uint32_t b = poles[i].body;
    if (kinds[b] != 1) continue;
    now.push_back({{bodies_[b].id, std::uint32_t(i - first[b])}, i});
  }
  std::sort(now.begin(), now.end(),
            [&](const auto& a, const auto& b) { return key_less(a.first, b.first); });
  const double eps2 = softening_ * softening_;
  // Positions then and now of the matched poles, their strengths then, and
  // a part number each (pairs within one part do no work on it).
  struct Matched {
    Vec3 then, now;
    double q;
    std::uint32_t part;
  };
  std::vector<Matched> m;
  for (std::size_t i = 0; i < reported_poles_.size(); ++i) {
    const std::uint32_t b = reported_poles_[i].body;
    if (b >= reported_kinds_.size() || reported_kinds_[b] != 1 || !reported_shares_[i].permanent)
      continue;
    const std::pair<ObjectId, std::uint32_t> k{reported_bodies_[b],
                                               std::uint32_t(i - reported_first_pole_[b])};
    const auto it =
        std::lower_bound(now.begin(), now.end(), k,
                         [&](const auto& e, const auto& key) { return key_less(e.first, key); });
    if (it == now.end() || key_less(k, it->first)) continue;
    m.push_back({reported_poles_[i].position, poles[it->second].position, reported_shares_[i].fixed,
                 reported_bodies_[b].index});
  }
  double work = 0;  // the fall of the pairs' energy at the strengths then
  for (std::size_t i = 0; i < m.size(); ++i)
    for (std::size_t j = i + 1; j < m.size(); ++j) {
      if (m[i].part == m[j].part) continue;
      const Vec3 r0 = m[j].then - m[i].then, r1 = m[j].now - m[i].now;
      work += kMu0Over4Pi * m[i].q * m[j].q *
              (1 / std::sqrt(dot(r0, r0) + eps2) - 1 / std::sqrt(dot(r1, r1) + eps2));
    }
  return work;
}

void MagneticForces::report_energy(const WorldView& view, EnergyReport& out) {
  // Pairs are booked by share:
  //   permanent x permanent   here, a store: mu0/4pi q_i q_j / sqrt(r^2 + eps^2)
  //   coil's own x anything   by electricity: the EMF at held strengths
  //   the iron's share from the coils' currents x anything: by electricity,
  //                           the EMF of the iron's moments' change
  //   permanent x the magnets' own induced share,
  //   that share x itself     here, soft iron's (below)
  // Direct, O(poles^2), and only while a ledger is kept.
  std::vector<std::uint8_t> kinds(bodies_.size(), 0);
  if (ids_) {
    const MagnetColumns c = MagnetColumns::bind(view, *ids_);
    const PropertyStore& store = view.store();
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      const ObjectId id = bodies_[b].id;
      if (!store.alive(id) || !c.magnet.has(id.index)) continue;
      const MagnetKind k = c.kind(id.index);
      kinds[b] = k == MagnetKind::Permanent ? 1 : k == MagnetKind::SoftIron ? 2 : 0;
    }
  }
  // The books' poles: the permanent magnets' and, for each iron part, the
  // pair of the moment the magnets alone induce there (every coil's current
  // off). The iron's share that the coils' currents add is the circuits':
  // the EMF makes them pay for its work (emf_iron_poles; docs/energy.md
  // "Session 21"), so its pairs are not booked here.
  std::vector<Vec3> bare = induced_moment_;
  if (!models_.empty()) {
    const std::vector<double> magnets = magnets_only(fixed_strength_);
    if (std::all_of(magnets.begin(), magnets.end(), [](double q) { return q == 0; }))
      bare.assign(bare.size(), Vec3{});  // no magnet: nothing magnetised without the currents
    else if (magnets != fixed_strength_)
      bare = solve_induction(fixed_poles(frames_, magnets), induced_parts(frames_), softening_,
                             summation_)
                 .moment;
  }
  std::vector<Pole> book;
  std::vector<Share> shares;
  std::vector<std::uint32_t> first(bodies_.size(), 0);
  std::vector<double> ratio(bodies_.size(), 0.0);
  {
    std::vector<Pole> iron;
    append_induced_poles(frames_, bare, 1.0, iron);
    std::size_t next_iron = 0;
    for (std::uint32_t b = 0; b < bodies_.size(); ++b) {
      first[b] = std::uint32_t(book.size());
      if (permanent_[b])
        for (std::uint32_t i = bodies_[b].first_pole;
             i < bodies_[b].first_pole + bodies_[b].pole_count; ++i) {
          book.push_back(poles_[i]);
          shares.push_back({poles_[i].strength, 0.0, kinds[b] == 1});
        }
      for (; next_iron < iron.size() && iron[next_iron].body == b; ++next_iron) {
        book.push_back(iron[next_iron]);
        shares.push_back({0.0, iron[next_iron].strength, false});
      }
      if (iron_of_[b] >= 0) {
        const SoftIronModel& m = models_[std::size_t(iron_of_[b])];
        const double size = length(bare[std::size_t(iron_of_[b])]);
        ratio[b] = m.saturation > 0 && std::isfinite(size) ? size / m.saturation : 0.0;
      }
    }
  }
  const double eps2 = softening_ * softening_;
  // The energy of the pairs of two parts in `which` (1: permanent x
  // permanent, 2: those with an induced share), strengths from `q`,
  // positions from `x`.
  auto energy = [&](std::span<const Share> q, std::span<const Pole> x, int which) {
    double u = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      for (std::size_t j = i + 1; j < x.size(); ++j) {
        if (x[j].body == x[i].body) continue;
        double qq = 0;
        if (which == 1) {
          if (q[i].permanent && q[j].permanent) qq = q[i].fixed * q[j].fixed;
        } else {
          qq = q[i].induced * q[j].induced;
          if (q[i].permanent) qq += q[i].fixed * q[j].induced;
          if (q[j].permanent) qq += q[j].fixed * q[i].induced;
        }
        if (qq == 0) continue;
        const Vec3 r = x[j].position - x[i].position;
        u += kMu0Over4Pi * qq / std::sqrt(dot(r, r) + eps2);
      }
    return u;
  };
  const double permanent = energy(shares, book, 1);
  out.store("permanent magnets' interaction", permanent);
  // Soft iron's store: the co-energy of its induced moments in the permanent
  // magnets' field, U = sum_b rho_b E_b, E_b the interaction of b's induced
  // share with the permanent poles (-mu0 m_b . H_b on the pole pair's line),
  // rho = 1/2 for linear iron (U = -1/2 m . B: the force at held strengths
  // does -dU, since m follows H), less as it saturates (iron_coenergy_ratio).
  double iron_store = 0;
  for (std::size_t i = 0; i < book.size(); ++i) {
    if (shares[i].induced == 0) continue;
    double e = 0;
    for (std::size_t j = 0; j < book.size(); ++j) {
      if (!shares[j].permanent || book[j].body == book[i].body) continue;
      const Vec3 r = book[j].position - book[i].position;
      e += shares[i].induced * shares[j].fixed / std::sqrt(dot(r, r) + eps2);
    }
    iron_store += kMu0Over4Pi * e * iron_coenergy_ratio(ratio[book[i].body]);
  }
  out.store("soft iron's field (co-energy in the magnets' field)", iron_store);
  // The work along the motion since the last report, at the strengths of the
  // last report, when the parts and their poles are the same.
  bool same = reported_ && reported_poles_.size() == book.size() &&
              reported_bodies_.size() == bodies_.size() && reported_kinds_ == kinds;
  for (std::size_t b = 0; same && b < bodies_.size(); ++b)
    same = reported_bodies_[b] == bodies_[b].id;
  for (std::size_t i = 0; same && i < book.size(); ++i)
    same = reported_poles_[i].body == book[i].body;
  double perm_work = 0, iron_work = 0;
  if (reported_ && !same) {
    // A coil switched on or off since (its poles come and go with its
    // current), or a part came or went: the permanent magnets' poles are
    // matched by their part, so that their pairs' work is still booked
    // against the store's change (it was left out, and the store's change
    // showed as the coupling's mismatch at every commutation of the motor).
    perm_work = permanent_work_across_a_change(book, first, kinds);
  }
  if (same) {
    perm_work = energy(reported_shares_, reported_poles_, 1) - permanent;
    // The iron's strengths change along the motion: its pairs' work at the
    // mean of the strengths at the two reports (the trapezoid), the partner
    // of the rigid body's kick at each report booked along the mean velocity
    // around it (docs/energy.md "Session 20"); at the strengths of the last
    // report alone it was first order in the step.
    iron_work =
        0.5 * (energy(reported_shares_, reported_poles_, 2) - energy(reported_shares_, book, 2) +
               energy(shares, reported_poles_, 2) - energy(shares, book, 2));
  }
  // What the iron's forces did beyond the fall of its store: the pole
  // model's own error (the induced moment follows the mean field of the
  // samples, the force the poles' line) and the step's.
  const double store_fall = same ? reported_iron_store_ - iron_store : 0.0;
  out.source("soft iron's work beyond its store", iron_work - store_fall);
  reported_iron_store_ = iron_store;
  out.transfer("magnetism", -(perm_work + iron_work));
  reported_poles_ = std::move(book);
  reported_shares_ = std::move(shares);
  reported_bodies_.clear();
  for (const MagneticBody& b : bodies_) reported_bodies_.push_back(b.id);
  reported_first_pole_ = std::move(first);
  reported_kinds_ = std::move(kinds);
  reported_ = true;
}

}  // namespace alloy::magnetism
