#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

// --- energy books -------------------------------------------------------------
//
// Per substep: the kinetic energy before and after the damping factor (drag),
// after restitution_pass (restitution), and after the ODE step and its
// projections. The work of each queued load is booked two ways: along the
// step's displacement, h F . v' (ODE moves a body by h v', so for a uniform
// field this is exactly minus the change of its potential energy), and along
// the mean velocity, h F . (v + v') / 2 (exactly the kinetic energy the load
// alone would give under the semi-implicit step). The first is the transfer
// the load's stage sees; the difference is the integrator's share; what the
// kinetic energy did not receive of the second is the contacts' and joints'
// (including the joint projection and the contact springs): a residue, not a
// measured force's work.

double RigidBodyResolver::kinetic_energy() const {
  const Impl& m = *impl_;
  double e = 0;
  for (const Impl::Body& b : m.bodies) {
    if (b.kinematic) continue;
    dMass mass;
    dBodyGetMass(b.id, &mass);
    const dReal* v = dBodyGetLinearVel(b.id);
    const dReal* w = dBodyGetAngularVel(b.id);
    dVector3 wb;  // in the body frame, where ODE keeps the inertia
    dBodyVectorFromWorld(b.id, w[0], w[1], w[2], wb);
    double rot = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) rot += wb[i] * mass.I[4 * i + j] * wb[j];
    e += 0.5 * mass.mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 0.5 * rot;
  }
  return e;
}

void RigidBodyResolver::book_loads_before(double tau) {
  Impl& m = *impl_;
  books_.applied.clear();
  books_.v0.resize(m.bodies.size()), books_.w0.resize(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (m.bodies[i].kinematic) continue;
    books_.v0[i] = to_vec3(dBodyGetLinearVel(m.bodies[i].id));
    books_.w0[i] = to_vec3(dBodyGetAngularVel(m.bodies[i].id));
  }
  // The same loads apply_loads and apply_rated_loads gave ODE, with their arms.
  auto arm_of = [&](const Impl::Part& p, const Impl::Body& b) {
    if (p.identity) return Vec3{};
    dVector3 at;
    dBodyGetRelPointPos(b.id, p.offset.x, p.offset.y, p.offset.z, at);
    return to_vec3(at) - to_vec3(dBodyGetPosition(b.id));
  };
  std::uint32_t account = 0;
  std::string last = "\x01";
  auto source = [&](const std::string& stage) {
    if (stage != last) account = books_.account(stage), last = stage;
    return account;
  };
  for (std::size_t k = 0; k < forces_.size(); ++k) {
    const LoadCommand& c = forces_.begin()[k];
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p) continue;
    const Impl::Body& b = m.bodies[p->body];
    if (b.kinematic || !dBodyIsEnabled(b.id)) continue;
    EnergyBooks::Applied a{.body = p->body, .source = source(load_sources_.name_of(k))};
    switch (c.kind) {
      case Load::Force:
        a.force = c.value, a.arm = arm_of(*p, b);
        break;
      case Load::ForceAtPoint:
        a.force = c.value, a.arm = c.point - to_vec3(dBodyGetPosition(b.id));
        break;
      case Load::Torque:
        a.torque = c.value;
        break;
    }
    books_.applied.push_back(a);
  }
  // Where each force acts, to take its work along the point's displacement.
  auto place = [&](EnergyBooks::Applied& a) {
    const dBodyID id = m.bodies[a.body].id;
    a.at = to_vec3(dBodyGetPosition(id)) + a.arm;
    dVector3 local;
    dBodyGetPosRelPoint(id, a.at.x, a.at.y, a.at.z, local);
    a.local = to_vec3(local);
  };
  for (std::size_t k = 0; k < rated_loads_.size(); ++k) {
    const RatedLoad& c = rated_loads_[k];
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p) continue;
    const Impl::Body& b = m.bodies[p->body];
    if (b.kinematic || !dBodyIsEnabled(b.id)) continue;
    books_.applied.push_back({.body = p->body,
                              .force = c.force + tau * c.force_rate,
                              .torque = c.torque + tau * c.torque_rate,
                              .arm = arm_of(*p, b),
                              .source = source(rated_sources_.name_of(k))});
  }
  for (EnergyBooks::Applied& a : books_.applied) place(a);
}

void RigidBodyResolver::book_loads_after(double h, double ke_before) {
  Impl& m = *impl_;
  double along_mean = 0;
  for (const EnergyBooks::Applied& a : books_.applied) {
    const dBodyID id = m.bodies[a.body].id;
    const Vec3 v1 = to_vec3(dBodyGetLinearVel(id)), w1 = to_vec3(dBodyGetAngularVel(id));
    // ODE moves a body by h v': the displacement's work is h (F . v' + tau . w').
    const double step = h * (dot(a.force, v1) + dot(a.torque + cross(a.arm, a.force), w1));
    along_mean += books_.book_load(a, step, h, v1, w1);
  }
  books_.close_substep(along_mean, kinetic_energy() - ke_before);
}

void RigidBodyResolver::report_energy(const WorldView&, EnergyReport& out) {
  books_on_ = true;
  books_.report(kinetic_energy(), out);
}

}  // namespace alloy::rigid
