#include "resolvers/electricity/electricity_from_magnetism.hpp"

#include <cmath>

#include "resolvers/electricity/electricity.hpp"

namespace alloy::magnetism {

const ElectricityFromMagnetism::CoilFlux* ElectricityFromMagnetism::find(ObjectId id) const {
  for (const CoilFlux& c : coils_)
    if (c.id == id) return &c;
  return nullptr;
}

void ElectricityFromMagnetism::apply(const WorldView& world) {
  coils_.clear();
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(world);
  const MagnetColumns c = MagnetColumns::bind(world, *ids_);
  const auto inductance = inductance_.column<double>(world);
  const auto velocity = velocity_.column<Vec3>(world);
  const auto spin = spin_.column<Vec3>(world);
  const PropertyStore& store = world.store();

  // Every pole moves with its part: v + w x (pole - centre), the centre being
  // the midpoint of the part's two poles.
  const auto poles = forces_.poles();
  const auto bodies = forces_.bodies();
  pole_velocity_.assign(poles.size(), Vec3{});
  for (const MagneticBody& b : bodies) {
    if (b.pole_count != 2 || !store.alive(b.id)) continue;
    const std::uint32_t slot = b.id.index;
    const Vec3 v = velocity.value_or(slot, Vec3{}), w = spin.value_or(slot, Vec3{});
    if (!is_finite(v) || !is_finite(w)) continue;
    const Vec3 centre = (poles[b.first_pole].position + poles[b.first_pole + 1].position) * 0.5;
    for (std::uint32_t i = b.first_pole; i < b.first_pole + 2; ++i)
      pole_velocity_[i] = v + cross(w, poles[i].position - centre);
  }

  // The poles at the end of the coming step, moved on with their velocity.
  const double dt = world.dt();
  moved_poles_.assign(poles.begin(), poles.end());
  for (std::size_t i = 0; i < moved_poles_.size(); ++i)
    moved_poles_[i].position = poles[i].position + pole_velocity_[i] * dt;

  std::vector<CoilGeometry> geometry;  // the coils with a usable geometry, for the mutual part
  std::vector<ObjectId> geometry_id;
  for (std::uint32_t slot : c.magnet.members()) {
    if (c.kind(slot) != MagnetKind::Electromagnet || !inductance.has(slot)) continue;
    const auto d = pole_separation(c, slot);
    const auto k = coil_factor(c, slot);
    if (!c.position.has(slot) || !d || !(*d > 0) || !k) continue;  // magnetism's build names these
    CoilGeometry coil;
    coil.centre = c.position[slot];
    coil.axis = rotate(c.orientation.value_or(slot, Quat{}), {1, 0, 0});
    coil.axis = coil.axis / length(coil.axis);
    coil.separation = *d;
    coil.linkage = *k * c.turns.value_or(slot, 0.0);
    coil.velocity = velocity.value_or(slot, Vec3{});
    coil.angular_velocity = spin.value_or(slot, Vec3{});
    const ObjectId id = store.id_at(slot);
    if (const MagneticBody* own = forces_.find(id)) coil.body = std::uint32_t(own - bodies.data());
    FluxLinkage f, f_end;
    if (is_finite(coil.centre) && is_finite(coil.axis) && is_finite(coil.velocity) &&
        is_finite(coil.angular_velocity) && std::isfinite(coil.linkage)) {
      f = coil_flux(poles, pole_velocity_, forces_.softening(), coil);
      // The same at the end of the coming step, every part moved on along
      // its present motion: electricity ramps the EMF over its substeps
      // from the last step's end value to this one, so the EMF it
      // integrates is the flux's change over the step, to second order,
      // while the parts' displacement over that step is the one the
      // force's work is booked along (docs/magnetism.md "The coupling's
      // timing").
      CoilGeometry moved = coil;
      moved.centre = coil.centre + coil.velocity * dt;
      moved.axis = coil.axis + cross(coil.angular_velocity, coil.axis) * dt;
      moved.axis = moved.axis / length(moved.axis);
      f_end = coil_flux(moved_poles_, pole_velocity_, forces_.softening(), moved);
      if (coil.linkage != 0) geometry.push_back(coil), geometry_id.push_back(id);
    }
    if (!std::isfinite(f.flux) || !std::isfinite(f.rate)) f = {};
    if (!std::isfinite(f_end.rate)) f_end = f;
    coils_.push_back({id, f});
    // Faraday and Lenz: the EMF opposes the change of the flux that links it.
    target_.set_induced_emf(id, -f_end.rate);
  }

  // A transformer: every pair of coils shares M (the same model as the flux
  // above, so M_ab = M_ba); the electricity resolver adds -M dI/dt to each.
  mutuals_.clear();
  for (std::size_t a = 0; a < geometry.size(); ++a)
    for (std::size_t b = a + 1; b < geometry.size(); ++b) {
      const double m = mutual_inductance(geometry[a], geometry[b], forces_.softening());
      if (m == 0 || !std::isfinite(m)) continue;
      mutuals_.push_back({geometry_id[a], geometry_id[b], m});
      target_.set_mutual_inductance(geometry_id[a], geometry_id[b], m);
    }
}

void register_electricity_from_magnetism(PluginRegistry& registry) {
  registry.add({
      .info = {.name = ElectricityFromMagnetism::kName,
               .kind = StageKind::Interaction,
               .reads = {prop::kMagnet, prop::kTurns, prop::kCoilFactor, prop::kPoleSeparation,
                         "inductance", prop::kPosition, prop::kOrientation, "velocity",
                         "angular_velocity", prop::kShape, prop::kSize, prop::kRadius,
                         prop::kLength},
               .needs = {prop::kMagnet},
               .derived = {MagneticForces::kName},
               .target = electricity::kResolverName,
               .doc = "Faraday: a coil's changing flux linkage induces an EMF in its circuit"},
      .create =
          [](PluginContext& ctx) {
            return std::make_unique<ElectricityFromMagnetism>(
                ctx.target<electricity::ElectricityResolver>(),
                ctx.dependency<MagneticForces>(MagneticForces::kName));
          },
  });
}

}  // namespace alloy::magnetism
