#include "resolvers/gravity/nbody_gravity.hpp"

#include <algorithm>
#include <cmath>

namespace alloy::gravity {

void accelerations(std::span<const Vec3> at, std::span<const Vec3> source,
                   std::span<const double> mass, double G, double softening, std::span<Vec3> out) {
  const double eps2 = softening * softening;
  const std::size_t ns = source.size();
  for (std::size_t i = 0; i < at.size(); ++i) {
    const Vec3 x = at[i];
    Vec3 a{};
    for (std::size_t j = 0; j < ns; ++j) {
      const Vec3 d = source[j] - x;
      const double s2 = dot(d, d) + eps2;
      if (d == Vec3{} || !(s2 > 0))
        continue;  // itself, or a coincident point: no direction to pull in
      a += (G * mass[j] / (s2 * std::sqrt(s2))) * d;
    }
    out[i] = a;
  }
}

void tree_accelerations(std::span<const Vec3> source, std::span<const double> mass, double G,
                        double softening, multipole::Tree& tree, std::span<Vec3> out, double theta,
                        int order, std::uint32_t leaf_size) {
  std::vector<multipole::Source> sources(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) sources[i] = {source[i], mass[i]};
  tree.build(sources, softening, {.theta = theta, .leaf_size = leaf_size, .fmm_order = order});
  tree.evaluate_at_sources(out);
  // The tree sums m K(x - p), which points away from the masses.
  for (Vec3& a : out) a = a * -G;
}

void NBodyGravity::resolve_ids(const WorldView& v) {
  if (gravity_ != kNoProperty) return;
  position_ = v.property("position"), mass_ = v.property("mass"), density_ = v.property("density");
  static_ = v.property("static"), gravity_ = v.property("gravity");
}

NBodyGravity::Counters NBodyGravity::counters(const WorldView& v) const {
  const PropertyStore& store = v.store();
  const ColumnBase &x = store.column(position_), &m = store.column(mass_),
                   &d = store.column(density_), &s = store.column(static_);
  return {x.version(),
          x.membership_version(),
          m.version(),
          m.membership_version(),
          d.membership_version(),
          s.version(),
          s.membership_version(),
          v.scope() ? v.scope()->version() : 0};
}

void NBodyGravity::compute(ResolverAccess& access) {
  const PropertyStore& store = access.store();
  // Scoped views: the targets. Unscoped ones: the sources, unless they are
  // the area's own (an area chooses the model, not which masses exist).
  const auto position = access.column<Vec3>(position_);
  const auto mass = access.column<double>(mass_);
  const auto density = access.column<double>(density_);
  const auto is_static = access.column<std::uint8_t>(static_);
  const ColumnView<Vec3> all_position(&store.typed<Vec3>(position_), &store);
  const ColumnView<double> all_mass(&store.typed<double>(mass_), &store);
  const ColumnView<double> all_density(&store.typed<double>(density_), &store);
  auto gravity = access.writer<Vec3>(gravity_);

  // Member lists are refreshed between phases, so a mass the rigid body has
  // just written from density (in the same build round) is in the density
  // list only; has() is always current.
  auto masses = [&](const ColumnView<double>& m, const ColumnView<double>& d,
                    std::vector<std::uint32_t>& out) {
    out.clear();
    std::set_union(m.members().begin(), m.members().end(), d.members().begin(), d.members().end(),
                   std::back_inserter(out));
    std::erase_if(out, [&](std::uint32_t s) { return !m.has(s) || !(m[s] > 0); });
  };
  masses(mass, density, targets_);
  std::erase_if(targets_, [&](std::uint32_t s) { return is_static.value_or(s, 0) != 0; });

  // Objects that carried gravity and no longer qualify (made static, mass
  // removed) get none, as with gravity.uniform.
  for (std::uint32_t s : gravity.members())
    if (!mass.has(s) || is_static.value_or(s, 0)) gravity.set(s, Vec3{});

  if (!targets_.empty()) {
    if (area_sources_)
      masses(mass, density, masses_);
    else
      masses(all_mass, all_density, masses_);
    a_.resize(targets_.size());
    if (masses_.size() >= kTreeFromMasses) {
      // Every target is a source (a non-static mass in scope): sum at the
      // sources and pick the targets' values out. The masses are gathered
      // straight into the summation's records, and its output is scaled by
      // -G while it is picked out (the sum is m K(x - p), pointing away from
      // the masses).
      sources_.resize(masses_.size());
      for (std::size_t i = 0; i < masses_.size(); ++i)
        sources_[i] = {all_position.value_or(masses_[i], {}), all_mass[masses_[i]]};
      source_a_.resize(masses_.size());
      // The Barnes-Hut walk up to kFmmFromMasses, the FMM from there (each the
      // faster where it is used, within the bound: bench/scaling.cpp --gravity).
      if (masses_.size() >= kFmmFromMasses) {
        fmm_.build(sources_, softening_,
                   {.theta = kTreeTheta, .order = kTreeOrder, .leaf_size = kTreeLeaf});
        fmm_.evaluate_at_sources(source_a_);
      } else {
        tree_.build(sources_, softening_, {.theta = kWalkTheta, .leaf_size = kWalkLeaf});
        tree_.evaluate_at_sources(source_a_);
      }
      std::size_t k = 0;
      for (std::size_t i = 0; i < targets_.size(); ++i) {
        while (k < masses_.size() && masses_[k] < targets_[i]) ++k;
        if (k < masses_.size() && masses_[k] == targets_[i]) {
          a_[i] = source_a_[k] * -G_;
        } else {  // not among the sources (cannot happen with the lists above): sum it directly
          a_[i] =
              multipole::direct_sum(sources_, softening_, position.value_or(targets_[i], {})) * -G_;
        }
      }
    } else {
      source_x_.resize(masses_.size()), source_m_.resize(masses_.size());
      for (std::size_t i = 0; i < masses_.size(); ++i) {
        source_x_[i] = all_position.value_or(masses_[i], {});  // the rigid body's default too
        source_m_[i] = all_mass[masses_[i]];
      }
      target_x_.resize(targets_.size());
      for (std::size_t i = 0; i < targets_.size(); ++i)
        target_x_[i] = position.value_or(targets_[i], {});
      accelerations(target_x_, source_x_, source_m_, G_, softening_, a_);
    }
    ++evaluations_;
    for (std::size_t i = 0; i < targets_.size(); ++i) gravity.set(targets_[i], a_[i]);
  }

  seen_ = counters(access);
  evaluated_ = true;
}

void NBodyGravity::build(ResolverAccess& access) {
  resolve_ids(access);
  compute(access);
}

void NBodyGravity::advance(ResolverAccess& access, double) {
  resolve_ids(access);
  if (!evaluated_ || counters(access) != seen_) compute(access);
}

void NBodyGravity::on_scope_exit(ResolverAccess& access, std::span<const std::uint32_t> left) {
  resolve_ids(access);
  auto gravity = access.writer<Vec3>(gravity_);
  for (std::uint32_t s : left) gravity.erase(s);
}

}  // namespace alloy::gravity
