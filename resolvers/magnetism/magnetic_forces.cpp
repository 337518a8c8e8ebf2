#include "resolvers/magnetism/magnetic_forces.hpp"

#include "resolvers/magnetism/magnet_parts.hpp"

namespace alloy::magnetism {

const MagneticBody* MagneticForces::find(ObjectId id) const {
  if (id.index >= body_of_slot_.size() || body_of_slot_[id.index] == kNoBody) return nullptr;
  const MagneticBody& b = bodies_[body_of_slot_[id.index]];
  return b.id == id ? &b : nullptr;
}

Vec3 MagneticForces::field(Vec3 point) const {
  Vec3 h;
  const std::uint32_t none = kNoBody;
  // One point: the direct sum is cheaper than building a tree.
  pole_fields(poles_, softening_, std::span(&point, 1), std::span(&none, 1), std::span(&h, 1));
  return h * kMu0;
}

void MagneticForces::update(const WorldView& world) {
  ++updates_;
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(world);
  const MagnetColumns c = MagnetColumns::bind(world, *ids_);
  const PropertyStore& store = world.store();

  bodies_.clear();
  poles_.clear();
  body_of_slot_.assign(store.slot_count(), kNoBody);

  // 1. Gather the parts: their axes, the fixed poles of magnets and coils, and
  //    the soft-iron bars whose poles depend on the field.
  struct Frame {
    Vec3 centre, axis;
    double separation;
  };
  std::vector<Frame> frames;
  std::vector<double> strength;  // per body: fixed, or induced once solved
  std::vector<Pole> fixed;
  std::vector<InducedBar> bars;
  for (std::uint32_t slot : c.magnet.members()) {
    const auto d = pole_separation(c, slot);
    if (!c.position.has(slot) || !d || !(*d > 0)) continue;  // the resolver's build names these
    const Vec3 centre = c.position[slot];
    Vec3 axis = rotate(c.orientation.value_or(slot, Quat{}), {1, 0, 0});
    axis = axis / length(axis);
    if (!is_finite(centre) || !is_finite(axis)) continue;  // not ours to repair; never spread it

    const auto b = std::uint32_t(bodies_.size());
    body_of_slot_[slot] = b;
    bodies_.push_back({.id = store.id_at(slot)});
    frames.push_back({centre, axis, *d});
    strength.push_back(0.0);
    if (c.kind(slot) == MagnetKind::SoftIron) {
      if (auto m = soft_iron_model(c, slot); m && m->gain > 0)
        bars.push_back({centre, axis, *d, m->gain, m->saturation, b});
    } else {
      const double q = c.pole_strength.value_or(slot, 0.0);
      if (q != 0 && std::isfinite(q)) {
        strength[b] = q;
        const BarPoles p = bar_poles(centre, axis, *d);
        fixed.push_back({p.north, q, b});
        fixed.push_back({p.south, -q, b});
      }
    }
  }

  // 2. The poles the field induces in soft iron, consistently with one another.
  const InductionResult induced = solve_induction(fixed, bars, softening_, summation_);
  for (std::size_t i = 0; i < bars.size(); ++i) strength[bars[i].body] = induced.strength[i];
  if (!induced.converged && induction_converged_)
    world.emit({.type = "magnetic_induction_unconverged",
                .text = "soft-iron parts too strongly coupled for the pole model; using the "
                        "field of the magnets alone"});
  induction_iterations_ = induced.iterations;
  induction_converged_ = induced.converged;

  // 3. Every pole, grouped by part, north first.
  for (std::uint32_t b = 0; b < bodies_.size(); ++b) {
    bodies_[b].pole_strength = strength[b];
    bodies_[b].first_pole = std::uint32_t(poles_.size());
    if (strength[b] == 0) continue;
    const BarPoles p = bar_poles(frames[b].centre, frames[b].axis, frames[b].separation);
    poles_.push_back({p.north, strength[b], b});
    poles_.push_back({p.south, -strength[b], b});
    bodies_[b].pole_count = 2;
  }

  // 4. Forces on poles, then force and torque about each part's centre.
  std::vector<Vec3> pole_force(poles_.size());
  used_tree_ = summation_.use_tree(poles_.size());
  accumulate_pole_forces(poles_, softening_, pole_force, summation_, &tree_);
  for (std::uint32_t b = 0; b < bodies_.size(); ++b) {
    MagneticBody& body = bodies_[b];
    for (std::uint32_t i = body.first_pole; i < body.first_pole + body.pole_count; ++i) {
      body.force += pole_force[i];
      body.torque += cross(poles_[i].position - frames[b].centre, pole_force[i]);
    }
    if (!is_finite(body.force) || !is_finite(body.torque)) {
      world.emit({.type = "magnetic_force_nonfinite",
                  .a = body.id,
                  .text = "magnetic force on the part is not finite; applying none"});
      body.force = {};
      body.torque = {};
    }
  }
}

}  // namespace alloy::magnetism
