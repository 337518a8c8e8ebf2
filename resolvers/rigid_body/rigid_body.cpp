#include "resolvers/rigid_body/rigid_body.hpp"

#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

// --- the resolver -------------------------------------------------------------------------

RigidBodyResolver::RigidBodyResolver(const World& world, RigidBodyConfig config)
    : world_(world), store_(world.store()), config_(config), impl_(std::make_unique<Impl>(config)) {
  impl_->host = &world;
}

RigidBodyResolver::~RigidBodyResolver() = default;

std::size_t RigidBodyResolver::body_count() const {
  return impl_->bodies.size();
}
std::size_t RigidBodyResolver::joint_count() const {
  return impl_->hinges.size();
}
std::size_t RigidBodyResolver::awake_count() const {
  return std::size_t(
      std::count_if(impl_->bodies.begin(), impl_->bodies.end(),
                    [](const Impl::Body& b) { return !b.kinematic && dBodyIsEnabled(b.id); }));
}

void RigidBodyResolver::build(ResolverAccess& access) {
  unapplied_.clear();
  ensure_ode();
  Impl& m = *impl_;
  m.resolve_ids(access);
  try {
    m.rebuild(access);
  } catch (const OdeError& e) {
    engine_failed(access, e.what());  // reported; the next advance tries again
    return;
  } catch (...) {
    // Nothing half-built survives; the next advance tries again (and reports again).
    m.destroy_world();
    m.dirty = true;
    throw;
  }
  ++rebuilds_;
  m.measure_bodies();
  m.snapshot_versions();
}

void RigidBodyResolver::advance(ResolverAccess& access, double dt) {
  try {
    step_world(access, dt);
  } catch (const OdeError& e) {
    engine_failed(access, e.what());
  }
}

}  // namespace alloy::rigid
