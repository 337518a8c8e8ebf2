#include "resolvers/gravity/nbody_gravity.hpp"

#include <algorithm>
#include <cmath>

namespace alloy::gravity {

void accelerations(std::span<const Vec3> position, std::span<const double> mass, double G,
                   double softening, std::span<Vec3> out) {
  const std::size_t n = position.size();
  const double eps2 = softening * softening;
  std::fill(out.begin(), out.begin() + std::ptrdiff_t(n), Vec3{});
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 xi = position[i];
    const double gmi = G * mass[i];
    Vec3 ai = out[i];
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec3 d = position[j] - xi;
      const double s2 = dot(d, d) + eps2;
      if (!(s2 > 0)) continue;  // coincident points, no softening: no direction to pull in
      const double inv = 1.0 / (s2 * std::sqrt(s2));  // 1 / s^3
      ai += (G * mass[j] * inv) * d;
      out[j] -= (gmi * inv) * d;
    }
    out[i] = ai;
  }
}

void NBodyGravity::resolve_ids(const WorldView& v) {
  if (gravity_ != kNoProperty) return;
  position_ = v.property("position"), mass_ = v.property("mass"), density_ = v.property("density");
  static_ = v.property("static"), gravity_ = v.property("gravity");
}

bool NBodyGravity::inputs_changed(const WorldView& v) const {
  const PropertyStore& store = v.store();
  const ColumnBase &x = store.column(position_), &m = store.column(mass_), &d = store.column(density_),
                   &s = store.column(static_);
  const std::uint64_t now[] = {x.version(), x.membership_version(), m.version(), m.membership_version(),
                               d.membership_version(), s.version(), s.membership_version(),
                               v.scope() ? v.scope()->version() : 0};
  return seen_.size() != std::size(now) || !std::equal(seen_.begin(), seen_.end(), std::begin(now));
}

void NBodyGravity::compute(ResolverAccess& access) {
  const auto position = access.column<Vec3>(position_);
  const auto mass = access.column<double>(mass_);
  const auto density = access.column<double>(density_);
  const auto is_static = access.column<std::uint8_t>(static_);
  auto gravity = access.writer<Vec3>(gravity_);

  // Every mass in scope. Member lists are refreshed between phases, so a mass
  // the rigid body has just written from density (in the same build round) is
  // in the density list only; has() is always current.
  slots_.clear();
  std::set_union(mass.members().begin(), mass.members().end(), density.members().begin(),
                 density.members().end(), std::back_inserter(slots_));
  std::erase_if(slots_, [&](std::uint32_t s) { return !mass.has(s) || !(mass[s] > 0); });
  const std::size_t n = slots_.size();
  x_.resize(n), m_.resize(n), a_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    x_[i] = position.value_or(slots_[i], {});  // the rigid body's default too
    m_[i] = mass[slots_[i]];
  }
  accelerations(x_, m_, G_, softening_, a_);
  ++evaluations_;

  // Objects that carried gravity and no longer qualify (made static, mass
  // removed) get none, as with gravity.uniform.
  for (std::uint32_t s : gravity.members())
    if (!mass.has(s) || is_static.value_or(s, 0)) gravity.set(s, Vec3{});
  for (std::size_t i = 0; i < n; ++i)
    if (!is_static.value_or(slots_[i], 0)) gravity.set(slots_[i], a_[i]);

  const PropertyStore& store = access.store();
  const ColumnBase &x = store.column(position_), &m = store.column(mass_), &d = store.column(density_),
                   &st = store.column(static_);
  seen_ = {x.version(), x.membership_version(), m.version(), m.membership_version(),
           d.membership_version(), st.version(), st.membership_version(),
           access.scope() ? access.scope()->version() : 0};
}

void NBodyGravity::build(ResolverAccess& access) {
  resolve_ids(access);
  compute(access);
}

void NBodyGravity::advance(ResolverAccess& access, double) {
  resolve_ids(access);
  if (inputs_changed(access)) compute(access);
}

void NBodyGravity::on_scope_exit(ResolverAccess& access, std::span<const std::uint32_t> left) {
  auto gravity = access.writer<Vec3>("gravity");
  for (std::uint32_t s : left) gravity.erase(s);
}

}  // namespace alloy::gravity
