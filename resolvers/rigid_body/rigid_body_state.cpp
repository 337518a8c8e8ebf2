#include <cfloat>

#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------
//
// A restore builds the world from the restored properties (build), then
// restore_state makes it the world that was saved, bit for bit: what build
// derives from properties differently from the run that was not interrupted
// is put back as it was. That is
//   - each body's pose and velocities: a plain body's (one part, its own
//     frame) are its properties' exact bits, which build would normalise;
//     an assembly's are saved;
//   - an assembly's mass, inertia and parts' frames, which build measures
//     from the parts' present poses;
//   - the hinges and their projection, which measure anchor and axis in the
//     bodies' frames as they stood at the last build: those poses, pivots,
//     axes and angles are saved, the joints are remade at them, then the
//     bodies are moved to where they are;
//   - with auto_disable, who sleeps and the loads they slept under (ODE's
//     own idle counters are not reachable through its API: a body about to
//     fall asleep may fall asleep a step later after a restore);
//   - the impulses the last advance published (the collisions set reads them).
// Queued commands are not saved: the world primes the interactions again.
namespace {
// Version 2 (session 18): a hinge's setup keeps where body 1 is held beside
// the pivot, and a projected hinge its second point (the hinges' defining
// points, hinge_anchors.hpp); a version-1 save is refused by name, not misread.
constexpr std::uint32_t kStateVersion = 2;

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const dReal* v, int n) {
  return std::all_of(v, v + n, [](dReal x) { return std::isfinite(x); });
}
// A rotation as saved: finite and not zero (ODE normalises what it is given,
// and asserts on a zero vector).
bool usable_quat(const Quat& q) {
  const double n = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  return std::isfinite(n) && n > 0.25 && n < 4;
}
bool usable_axis(const Vec3& a) {
  const double n = dot(a, a);
  return std::isfinite(n) && n > 0.25 && n < 4;
}
// What dBodySetMass asserts (its mass check and the centre at the origin),
// tested here so that a damaged file is an input error, not an ODE failure.
bool usable_mass(const dMass& m) {
  if (!(m.mass > 0) || !std::isfinite(m.mass) || !finite(m.c, 3) || !finite(m.I, 12)) return false;
  for (int i = 0; i < 3; ++i)
    if (std::fabs(m.c[i]) > DBL_EPSILON) return false;
  dMatrix3 inertia;
  std::copy(m.I, m.I + 12, inertia);
  return dIsPositiveDefinite(inertia, 3) != 0;
}
}  // namespace

bool RigidBodyResolver::save_state(StateWriter& out) const {
  if (!unapplied_.empty()) {  // restored, not rebuilt yet: see restore_state
    for (std::byte b : unapplied_) out.put(b);
    return true;
  }
  const Impl& m = *impl_;
  out.put(kStateVersion);
  // A defining column edited since the last build (by a stage that ran after
  // us, or an edit): the next advance rebuilds, and so must the restored one.
  const bool rebuild = m.dirty || (m.have_ids && m.defining_changed());
  out.put<std::uint8_t>(rebuild);
  out.put<std::uint64_t>(m.bodies.size());
  out.put<std::uint64_t>(m.parts.size());
  out.put<std::uint64_t>(m.hinges.size());
  if (!rebuild) {
    for (const Impl::Body& b : m.bodies) {
      if (m.plain(b)) continue;
      dMass mass;
      dBodyGetMass(b.id, &mass);
      out.put(mass);
      for (std::uint32_t i = b.first_part; i < b.first_part + b.part_count; ++i) {
        out.put(m.parts[i].offset);
        out.put(m.parts[i].rot);
      }
      out.put(to_vec3(dBodyGetPosition(b.id)));
      out.put(to_quat(dBodyGetQuaternion(b.id)));
      out.put(to_vec3(dBodyGetLinearVel(b.id)));
      out.put(to_vec3(dBodyGetAngularVel(b.id)));
    }
    out.put_vector(m.setup_poses);
    out.put_vector(m.hinge_setup);
    out.put_vector(m.projection_calls);
    if (config_.auto_disable)
      for (const Impl::Body& b : m.bodies) {
        out.put<std::uint8_t>(dBodyIsEnabled(b.id) ? 1 : 0);
        out.put<std::uint8_t>(b.asleep);
        out.put(b.load_force), out.put(b.load_torque);
        out.put(b.awake_force), out.put(b.awake_torque);
      }
  }
  out.put_vector(impulses_);
  out.put<std::uint8_t>(impulses_computed_);
  out.put(state_version_);
  return true;
}

void RigidBodyResolver::restore_state(StateReader& in) {
  Impl& m = *impl_;
  auto refuse = [&](const std::string& what) {
    throw InputError("the saved state of stage '" + in.stage() +
                     "' does not fit this world: " + what);
  };
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    refuse("it is of version " + std::to_string(v) + ", this build reads " +
           std::to_string(kStateVersion));
  const bool was_dirty = in.get<std::uint8_t>() != 0;
  const auto bodies = in.get<std::uint64_t>(), parts = in.get<std::uint64_t>(),
             hinges = in.get<std::uint64_t>();
  if (!was_dirty && (m.dirty || bodies != m.bodies.size() || parts != m.parts.size() ||
                     hinges != m.hinges.size())) {
    // Saved in a world whose structure changed in the step that led to the
    // snapshot (an object frozen): the world resyncs at its next step
    // (Snapshot::resync) and rebuilds us from properties, as it does the
    // uninterrupted run's rigid body; till then we save the bytes we were
    // given, as that one would save its own.
    StateWriter head;
    head.put(kStateVersion);
    head.put<std::uint8_t>(0);
    head.put(bodies), head.put(parts), head.put(hinges);
    unapplied_ = head.take();
    while (in.remaining() > 0) unapplied_.push_back(in.get<std::byte>());
    m.dirty = true;
    return;
  }
  if (was_dirty) {
    // Saved between a failed build and the next try: the next advance builds again.
    m.dirty = true;
  } else {
    // 1. Assemblies: mass and frames as measured when they were built.
    struct BodyState {
      Vec3 x;
      Quat q;
      Vec3 v, w;
    };
    std::vector<BodyState> state(m.bodies.size());
    for (std::size_t bi = 0; bi < m.bodies.size(); ++bi) {
      Impl::Body& b = m.bodies[bi];
      if (m.plain(b)) continue;
      const auto mass = in.get<dMass>();
      if (!usable_mass(mass)) refuse("an assembly's mass or inertia is not a body's");
      dBodySetMass(b.id, &mass);
      b.mass = mass.mass;
      for (std::uint32_t i = b.first_part; i < b.first_part + b.part_count; ++i) {
        m.parts[i].offset = in.get<Vec3>();
        m.parts[i].rot = in.get<Quat>();
        if (!finite(m.parts[i].offset) || !usable_quat(m.parts[i].rot))
          refuse("a part's place in its assembly is not finite");
      }
      state[bi] = {in.get<Vec3>(), in.get<Quat>(), in.get<Vec3>(), in.get<Vec3>()};
      if (!finite(state[bi].x) || !usable_quat(state[bi].q) || !finite(state[bi].v) ||
          !finite(state[bi].w))
        refuse("an assembly's pose or velocity is not finite");
    }
    for (Impl::Gyro& g : m.gyros) {  // from the mass just restored, as build computes it
      if (m.plain(m.bodies[g.body])) continue;
      dMass mass;
      dBodyGetMass(m.bodies[g.body].id, &mass);
      dMatrix3 inv;
      if (!dInvertPDMatrix(mass.I, inv, 3)) refuse("an assembly's inertia cannot be inverted");
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) g.inv_inertia[3 * r + c] = inv[4 * r + c];
    }
    // 2. The hinges and their projection, measured at the last build's poses.
    m.setup_poses = in.get_vector<Impl::SetupPose>();
    m.hinge_setup = in.get_vector<Impl::HingeSetup>();
    m.projection_calls = in.get_vector<Impl::ProjectionCall>();
    if (m.hinge_setup.size() != m.hinges.size())
      refuse("it sets up " + std::to_string(m.hinge_setup.size()) + " hinges, the world has " +
             std::to_string(m.hinges.size()));
    for (const auto& sp : m.setup_poses)
      if (!finite(sp.pos, 3) || !usable_quat(Quat{sp.q[0], sp.q[1], sp.q[2], sp.q[3]}))
        refuse("a hinge's body was set up at a pose that is not finite");
    for (const auto& hs : m.hinge_setup)
      if (!finite(hs.pivot) || !finite(hs.pivot1) || !usable_axis(hs.axis) ||
          !std::isfinite(hs.angle))
        refuse("a hinge's pivot, axis or angle is not finite or its axis is not a direction");
    for (const auto& c : m.projection_calls)
      if (!finite(c.pivot) || !finite(c.pivot2) || !finite(c.axis) ||
          (c.body < 0 && !usable_axis(c.axis)))
        refuse("a projected hinge's pivot or axis is not finite");
    for (const auto& sp : m.setup_poses) {
      if (sp.body >= m.bodies.size()) refuse("a hinge's body is out of range");
      Impl::set_exact_pose(m.bodies[sp.body].id, sp.pos, sp.q);
    }
    for (std::size_t h = 0; h < m.hinges.size(); ++h) {
      const auto& hs = m.hinge_setup[h];
      Impl::set_hinge_anchors(m.hinges[h].joint, dJointGetBody(m.hinges[h].joint, 0), hs.pivot1,
                              hs.pivot);
      dJointSetHingeAxisOffset(m.hinges[h].joint, hs.axis.x, hs.axis.y, hs.axis.z, hs.angle);
    }
    m.projection.clear();
    std::int64_t projected = 0;
    for (const auto& c : m.projection_calls) {
      if (c.body >= 0) {
        if (std::uint64_t(c.body) >= m.bodies.size()) refuse("a projected body is out of range");
        m.projection.add_body(m.bodies[c.body].id, c.planar != 0, c.fixed != 0);
        ++projected;
      } else {
        if (c.b1 < 0 || c.b1 >= projected || c.b2 < -1 || c.b2 >= projected)
          refuse("a projected hinge names a body out of range");
        m.projection.add_hinge(std::int32_t(c.b1), std::int32_t(c.b2), c.pivot, c.axis, c.pivot2);
      }
    }
    m.projection.finish();
    // 3. Every body where it is now: a plain body from its part's properties.
    const auto& position = store_.typed<Vec3>(m.id.position);
    const auto& orientation = store_.typed<Quat>(m.id.orientation);
    const auto& velocity = store_.typed<Vec3>(m.id.velocity);
    const auto& angular_velocity = store_.typed<Vec3>(m.id.angular_velocity);
    for (std::size_t bi = 0; bi < m.bodies.size(); ++bi) {
      Impl::Body& b = m.bodies[bi];
      if (m.plain(b)) {
        const std::uint32_t s = m.parts[b.first_part].id.index;
        state[bi] = {position.has(s) ? position[s] : Vec3{},
                     orientation.has(s) ? orientation[s] : Quat{},
                     velocity.has(s) ? velocity[s] : Vec3{},
                     angular_velocity.has(s) ? angular_velocity[s] : Vec3{}};
      }
      const BodyState& st = state[bi];
      const dReal pos[3] = {st.x.x, st.x.y, st.x.z};
      dQuaternion q;
      to_ode(st.q, q);
      Impl::set_exact_pose(b.id, pos, q);
      if (!b.kinematic) {
        dBodySetLinearVel(b.id, st.v.x, st.v.y, st.v.z);
        dBodySetAngularVel(b.id, st.w.x, st.w.y, st.w.z);
      }
    }
    if (config_.auto_disable)
      for (Impl::Body& b : m.bodies) {
        if (in.get<std::uint8_t>())
          dBodyEnable(b.id);
        else
          dBodyDisable(b.id);
        b.asleep = in.get<std::uint8_t>() != 0;
        b.load_force = in.get<Vec3>(), b.load_torque = in.get<Vec3>();
        b.awake_force = in.get<Vec3>(), b.awake_torque = in.get<Vec3>();
        if (!finite(b.load_force) || !finite(b.load_torque) || !finite(b.awake_force) ||
            !finite(b.awake_torque))
          refuse("a sleeping body's loads are not finite");
      }
    // 4. The values last written, as write_poses wrote them, so that the
    // next advance does not take the restored properties for an edit.
    for (Impl::Body& b : m.bodies) {
      const Vec3 x = to_vec3(dBodyGetPosition(b.id));
      const Quat q = to_quat(dBodyGetQuaternion(b.id));
      const Vec3 v = b.kinematic ? Vec3{} : to_vec3(dBodyGetLinearVel(b.id));
      const Vec3 w = b.kinematic ? Vec3{} : to_vec3(dBodyGetAngularVel(b.id));
      for (std::uint32_t i = b.first_part; i < b.first_part + b.part_count; ++i) {
        Impl::Part& p = m.parts[i];
        if (p.identity) {
          p.pos = x, p.q = q, p.vel = v;
        } else {
          const Vec3 r = rotate(q, p.offset);
          p.pos = x + r, p.q = q * p.rot, p.vel = v + cross(w, r);
        }
        p.angvel = w;
      }
    }
    m.measure_bodies();
    m.snapshot_versions();
  }
  if (was_dirty) m.dirty = true;
  impulses_ = in.get_vector<PairImpulse>();
  for (std::size_t i = 0; i < impulses_.size(); ++i) {
    const PairImpulse& p = impulses_[i];
    // Merged by pair into the contacts (ContactSet::publish): in pair order,
    // as advance sorts them (equal neighbours are left as advance leaves them).
    if (!(p.a < p.b) || !finite(p.impulse) || !(p.normal_impulse >= 0) ||
        !std::isfinite(p.normal_impulse) ||
        (i > 0 && pair_less(p.a, p.b, impulses_[i - 1].a, impulses_[i - 1].b)))
      refuse("a contact impulse is not finite or the pairs are out of order");
  }
  impulses_computed_ = in.get<std::uint8_t>() != 0;
  state_version_ = in.get<std::uint64_t>();
}

}  // namespace alloy::rigid
