#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

namespace {

/// How fast body 1 moves into body 2 (null: the play area) at `point`,
/// along `normal` (ODE's contact normal, pointing out of body 2 into body 1), m/s.
double approach_speed(dBodyID b1, dBodyID b2, Vec3 point, Vec3 normal) {
  dVector3 v1, v2 = {0, 0, 0};
  dBodyGetPointVel(b1, point.x, point.y, point.z, v1);
  if (b2) dBodyGetPointVel(b2, point.x, point.y, point.z, v2);
  return -(normal.x * (v1[0] - v2[0]) + normal.y * (v1[1] - v2[1]) + normal.z * (v1[2] - v2[2]));
}

}  // namespace

void RigidBodyResolver::add_contact_joints(double h, bool record, bool feedback) {
  Impl& m = *impl_;
  // What every point reads, loaded once: the ODE calls below are opaque to the
  // compiler, which would otherwise reload each member after every call (a
  // 1,000-box pile makes about 4,000 joints a step).
  const dWorldID world = m.world;
  const dJointGroupID group = m.contact_group;
  const ContactPoint* const points = contact_points_.data();
  const double* const depths = m.depth.data();
  const double layer = config_.surface_layer, shallow = 0.5 * config_.surface_layer;
  const bool auto_disable = config_.auto_disable;
  dJointFeedback* const feedback_buffer = m.feedback.data();
  const std::uint32_t commands = std::uint32_t(contacts_.size());
  // The contact model (docs/architecture.md): a spring k and damper c,
  // integrated implicitly over this step h: ERP = h k / (h k + c),
  // CFM = 1 / (h k + c); or rigid (k = 0): CFM 0 and the world's error reduction.
  const double k = config_.contact_stiffness, hk_c = h * k + config_.contact_damping;
  const bool spring = k > 0;
  const double soft_erp = spring ? h * k / hk_c : 0, soft_cfm = spring ? 1 / hk_c : 0;
  // Filled per pair and point; the fields never set stay zero (as a fresh dContact{}).
  dContact contact{};
  std::uint32_t fb = 0;
  for (std::uint32_t ci = 0; ci < commands; ++ci) {
    const ContactCommand& c = contacts_[ci];
    const std::int32_t ba = m.body_of(c.a), bb = m.body_of(c.b);
    if (ba == bb) continue;  // one assembly, or two parts that are not bodies
    const bool fixed_a = ba < 0 || m.bodies[ba].kinematic,
               fixed_b = bb < 0 || m.bodies[bb].kinematic;
    if (fixed_a && fixed_b) continue;
    // Two sleeping bodies (or one on a static part) need no joint: ODE would
    // skip their island anyway, and without the joints a settled pile
    // publishes no impulses, so the stages that read them (collisions, and
    // through it everything else) are skipped while it sleeps. A moving body
    // that touches a sleeper gets its joint, and ODE wakes the sleeper.
    if (auto_disable && m.sleeping_or_static(ba) && m.sleeping_or_static(bb)) continue;
    const bool swapped = ba < 0;
    dBodyID b1 = m.bodies[swapped ? bb : ba].id;
    dBodyID b2 = swapped ? nullptr : (bb >= 0 ? m.bodies[bb].id : nullptr);
    // Approx1: the friction bound is mu times the normal force (Coulomb), not a force.
    // No dContactBounce where restitution_pass has already turned the
    // collisions round: ODE's bounce (a velocity target for all of an
    // island's contacts at once) would share one ball's impulse along a
    // chain. Hinged bodies still bounce the old way.
    int mode = dContactApprox1 | dContactSoftCFM | (spring ? dContactSoftERP : 0);
    const bool may_bounce = c.restitution > 0 && m.pass_skips(ba, bb);
    if (may_bounce) mode |= dContactBounce;
    contact.surface.bounce = may_bounce ? c.restitution : 0;
    contact.surface.bounce_vel = may_bounce ? c.bounce_velocity : 0;
    contact.surface.mu = c.friction;
    contact.surface.soft_cfm = soft_cfm;
    contact.surface.soft_erp = soft_erp;
    const double restitution = c.restitution, bounce_velocity = c.bounce_velocity;
    const double sign = swapped ? -1.0 : 1.0;  // the normal must push body 1 out
    const std::uint32_t first_feedback = fb;
    const std::uint32_t end = c.first + c.count;
    for (std::uint32_t k = c.first; k < end; ++k) {
      const ContactPoint& p = points[k];
      const double depth = depths[k];
      // A resting or sliding point that has drifted shallower than half the
      // surface layer may close to the full layer within this step (ODE's
      // normal surface motion: an allowance, never a pull). Without it the
      // velocity-level contact lets curved relative motion (a bar resting on
      // a turning wheel) drift the parts apart by 1/2 a_n dt^2 a step, and the
      // contact ends and begins again every few steps. Points that bounce, or
      // that are deep enough, are left exactly as ODE treats them.
      contact.surface.mode = mode;
      contact.surface.motionN = 0;
      if (depth < shallow) {
        // The approach speed matters only to a point that may bounce.
        if (restitution <= 0 ||
            approach_speed(b1, b2, p.position, sign * p.normal) <= bounce_velocity) {
          contact.surface.mode = mode | dContactMotionN;
          contact.surface.motionN = -(layer - depth) / h;
        }
      }
      contact.geom.pos[0] = p.position.x, contact.geom.pos[1] = p.position.y,
      contact.geom.pos[2] = p.position.z;
      contact.geom.normal[0] = sign * p.normal.x, contact.geom.normal[1] = sign * p.normal.y,
      contact.geom.normal[2] = sign * p.normal.z;
      contact.geom.depth = depth;
      dJointID j = dJointCreateContact(world, group, &contact);
      dJointAttach(j, b1, b2);
      // The joint's force is reported only for readers of impulses; without
      // feedback ODE skips copying its Jacobian and computing J^T lambda.
      if (feedback) dJointSetFeedback(j, &feedback_buffer[fb]);
      ++fb;
    }
    if (record) m.records.push_back({ci, first_feedback, fb - first_feedback, swapped});
  }
}

namespace {

/// A 3x3 matrix, row-major: the world-frame inverse inertia of a body.
struct Mat3 {
  double m[9] = {};
  Vec3 operator*(Vec3 v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
  }
};

/// R I^-1 R^T of an ODE body, I its body-frame inertia about the centre of mass.
Mat3 world_inverse_inertia(dBodyID b) {
  dMass mass;
  dBodyGetMass(b, &mass);
  const dReal* I = mass.I;  // 3x4, row-major
  const double a = I[0], bb = I[1], c = I[2], d = I[4], e = I[5], f = I[6], g = I[8], hh = I[9],
               k = I[10];
  const double c0 = e * k - f * hh, c1 = -(d * k - f * g), c2 = d * hh - e * g;
  const double det = a * c0 + bb * c1 + c * c2;
  Mat3 inv;
  if (!(std::abs(det) > 0)) return inv;
  const double in[9] = {c0 / det, -(bb * k - c * hh) / det, (bb * f - c * e) / det,
                        c1 / det, (a * k - c * g) / det,    -(a * f - c * d) / det,
                        c2 / det, -(a * hh - bb * g) / det, (a * e - bb * d) / det};
  const dReal* R = dBodyGetRotation(b);  // 3x4, row-major
  double t[9];                           // R I^-1
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col)
      t[3 * r + col] = R[4 * r] * in[col] + R[4 * r + 1] * in[3 + col] + R[4 * r + 2] * in[6 + col];
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col)
      inv.m[3 * r + col] =
          t[3 * r] * R[4 * col] + t[3 * r + 1] * R[4 * col + 1] + t[3 * r + 2] * R[4 * col + 2];
  return inv;
}

/// The inverse inertia of a planar body (ODE's Plane2D joint lets it turn
/// about z only): 1 / I_zz about world z, nothing about x and y. An impulse
/// at a point off the plane (a cylinder's line contact has a point at each
/// face) then turns it about z alone, as the joint will; with the free
/// body's inertia part of the impulse went into a tilt the joint removes,
/// and a disk dropped on a floor rebounded to 0.19 of its drop, not e^2 = 0.25.
Mat3 planar_inverse_inertia(dBodyID b) {
  dMass mass;
  dBodyGetMass(b, &mass);
  const dReal* I = mass.I;               // body frame, 3x4 row-major
  const dReal* R = dBodyGetRotation(b);  // world z in the body frame: R's third row
  double izz = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) izz += R[8 + i] * I[4 * i + j] * R[8 + j];
  Mat3 inv;
  if (izz > 0) inv.m[8] = 1 / izz;
  return inv;
}

}  // namespace

void RigidBodyResolver::restitution_pass(double h, bool feedback) {
  // Collisions (an approach faster than the pair's bounce velocity, with
  // restitution) are resolved here, before ODE's velocity solve, by impulses
  // between two bodies at a time: the fastest approaching point first, then
  // the next, until none approaches (Gauss-Seidel on collisions, as in
  // Guendelman, Bridson and Fedkiw 2003). A ball hitting a row of touching
  // balls then stops, the next is hit and stops, and the last flies off:
  // Newton's cradle. ODE's bounce would solve the row at once and share the
  // impulse among all of them.
  //
  // The velocities worked on are those the step would end with without
  // contacts (this step's loads applied), so that ODE's solve afterwards,
  // seeing every collision point already separating, adds nothing to it.
  // Each impulse also moves its bodies to where they would be had the
  // collision happened when the parts first touched: a point found `depth`
  // deep while approaching at u touched depth / u ago, and since then the
  // bodies have moved with their old velocities instead of the new ones.
  // Without that move the overlap stays and the error reduction pushes it
  // out, adding speed (a cradle's first ball backs off at erp depth / h).
  Impl& m = *impl_;
  const std::uint32_t commands = std::uint32_t(contacts_.size());
  struct Point {
    std::uint32_t k, command;
    std::int32_t a, b;  // indices into work, -1: immovable
    double e, mu, bounce_velocity;
  };
  std::vector<Point> points;
  for (std::uint32_t ci = 0; ci < commands; ++ci) {
    const ContactCommand& c = contacts_[ci];
    if (!(c.restitution > 0) || c.count == 0) continue;
    const std::int32_t ba = m.body_of(c.a), bb = m.body_of(c.b);
    if (ba == bb) continue;
    const bool fixed_a = ba < 0 || m.bodies[ba].kinematic,
               fixed_b = bb < 0 || m.bodies[bb].kinematic;
    if (fixed_a && fixed_b) continue;
    if (m.pass_skips(ba, bb)) continue;
    if (config_.auto_disable && m.sleeping_or_static(ba) && m.sleeping_or_static(bb)) continue;
    for (std::uint32_t k = c.first; k < c.first + c.count; ++k)
      points.push_back({k, ci, ba, bb, c.restitution, c.friction, c.bounce_velocity});
  }
  if (points.empty() || config_.max_collision_impulses == 0) return;

  // The bodies the points touch, with their predicted velocities.
  struct Work {
    dBodyID id = nullptr;
    Vec3 x, v, w, v0, w0, dx, dth;
    Vec3 a, alpha;  // acceleration by this step's loads, m/s^2 and rad/s^2
    double inv_mass = 0;
    Mat3 inv_inertia;
  };
  std::vector<Work> work;
  std::vector<std::int32_t>& slot = m.pass_slot;
  slot.assign(m.bodies.size(), -1);
  auto enter = [&](std::int32_t body) -> std::int32_t {
    if (body < 0) return -1;
    if (slot[body] >= 0) return slot[body];
    const Impl::Body& bd = m.bodies[body];
    Work wk;
    wk.id = bd.id;
    wk.x = to_vec3(dBodyGetPosition(bd.id));
    wk.v = to_vec3(dBodyGetLinearVel(bd.id));
    wk.w = to_vec3(dBodyGetAngularVel(bd.id));
    if (!bd.kinematic) {
      wk.inv_mass = 1 / bd.mass;
      wk.inv_inertia = bd.planar ? planar_inverse_inertia(bd.id) : world_inverse_inertia(bd.id);
      if (dBodyIsEnabled(bd.id)) {  // a sleeper's load is not applied
        wk.a = wk.inv_mass * to_vec3(dBodyGetForce(bd.id));
        wk.alpha = wk.inv_inertia * to_vec3(dBodyGetTorque(bd.id));
      }
    }
    wk.v0 = wk.v, wk.w0 = wk.w;
    slot[body] = std::int32_t(work.size());
    work.push_back(wk);
    return slot[body];
  };
  for (Point& p : points) p.a = enter(p.a), p.b = enter(p.b);

  const ContactPoint* const cp = contact_points_.data();
  auto velocity_at = [&](std::int32_t i, Vec3 at) {
    return i < 0 ? Vec3{} : work[i].v + cross(work[i].w, at - work[i].x);
  };
  auto moved_at = [&](std::int32_t i, Vec3 at) {
    return i < 0 ? Vec3{} : work[i].dx + cross(work[i].dth, at - work[i].x);
  };
  auto acceleration_at = [&](std::int32_t i, Vec3 at) {
    return i < 0 ? Vec3{} : work[i].a + cross(work[i].alpha, at - work[i].x);
  };
  auto normal_speed = [&](const Point& p) {  // > 0: separating
    const ContactPoint& c = cp[p.k];
    return dot(c.normal, velocity_at(p.a, c.position) - velocity_at(p.b, c.position));
  };
  // 1 / (effective mass) of the pair at `at` along the unit direction d.
  auto inverse_mass = [&](const Point& p, Vec3 at, Vec3 d) {
    double s = 0;
    for (const std::int32_t i : {p.a, p.b}) {
      if (i < 0) continue;
      const Vec3 r = at - work[i].x;
      s += work[i].inv_mass + dot(d, cross(work[i].inv_inertia * cross(r, d), r));
    }
    return s;
  };
  auto push = [&](const Point& p, Vec3 at, Vec3 impulse, double tau) {  // impulse on a
    for (const std::int32_t i : {p.a, p.b}) {
      if (i < 0) continue;
      const Vec3 j = i == p.a ? impulse : -impulse;
      const Vec3 dv = work[i].inv_mass * j, dw = work[i].inv_inertia * cross(at - work[i].x, j);
      work[i].v += dv, work[i].w += dw;
      work[i].dx += tau * dv, work[i].dth += tau * dw;
    }
  };

  if (feedback && pass_impulse_.size() < commands) {
    pass_impulse_.resize(commands, Vec3{});
    pass_normal_.resize(commands, 0.0);
  }
  for (int n = 0; n < config_.max_collision_impulses; ++n) {
    // The fastest approach among the points that may bounce.
    const Point* hit = nullptr;
    double fastest = 0;
    for (const Point& p : points) {
      const double u = -normal_speed(p);
      if (u > p.bounce_velocity && u > fastest) fastest = u, hit = &p;
    }
    if (!hit) break;
    const ContactPoint& c = cp[hit->k];
    // Time since the parts touched, from the point's depth as the moves so
    // far have left it, and the approach speed they touched with: the loads
    // (gravity) have been speeding the approach up by g_n since, so
    // depth = u tau - g_n tau^2 / 2 and u_touch = u - g_n tau. Never more
    // than the step (the point was not found before).
    const double depth = m.depth[hit->k] -
                         dot(c.normal, moved_at(hit->a, c.position) - moved_at(hit->b, c.position));
    const double gn =
        -dot(c.normal, acceleration_at(hit->a, c.position) - acceleration_at(hit->b, c.position));
    double tau = 0;
    if (depth > 0) {
      const double disc = fastest * fastest - 2 * gn * depth;
      tau = disc > 0 ? 2 * depth / (fastest + std::sqrt(disc)) : fastest / gn;
    }
    tau = std::clamp(tau, 0.0, h);
    const double touch = std::max(0.0, fastest - gn * tau);
    // Turned round where they touched, then slowed by the loads for tau: the
    // change of normal speed is (1 + e) u_touch.
    const double jn = (1 + hit->e) * touch / inverse_mass(*hit, c.position, c.normal);
    push(*hit, c.position, jn * c.normal, tau);
    Vec3 total = jn * c.normal;
    // Coulomb friction in the same collision: stop the sliding, with at most
    // mu times the normal impulse.
    const Vec3 rel = velocity_at(hit->a, c.position) - velocity_at(hit->b, c.position);
    const Vec3 vt = rel - dot(rel, c.normal) * c.normal;
    const double slide = length(vt);
    if (hit->mu > 0 && slide > 1e-12) {
      const Vec3 t = vt / slide;
      const double jt = std::min(slide / inverse_mass(*hit, c.position, t), hit->mu * jn);
      push(*hit, c.position, -jt * t, tau);
      total -= jt * t;
    }
    if (feedback) pass_impulse_[hit->command] += total, pass_normal_[hit->command] += jn;
  }

  // Hand the changes to ODE: the velocity change (the loads are still to be
  // applied by the step itself) and the move to the time of impact.
  bool moved = false;
  for (const Work& wk : work) {
    if (wk.inv_mass == 0) continue;
    if (wk.v == wk.v0 && wk.w == wk.w0) continue;
    const Vec3 v = to_vec3(dBodyGetLinearVel(wk.id)) + (wk.v - wk.v0);
    const Vec3 w = to_vec3(dBodyGetAngularVel(wk.id)) + (wk.w - wk.w0);
    dBodySetLinearVel(wk.id, v.x, v.y, v.z);
    dBodySetAngularVel(wk.id, w.x, w.y, w.z);
    if (!(wk.dx == Vec3{}) || !(wk.dth == Vec3{})) {
      moved = true;
      dBodySetPosition(wk.id, wk.x.x + wk.dx.x, wk.x.y + wk.dx.y, wk.x.z + wk.dx.z);
      const double angle = length(wk.dth);
      if (angle > 0) {
        const Quat q = normalized(Quat::from_axis_angle(wk.dth / angle, angle) *
                                  to_quat(dBodyGetQuaternion(wk.id)));
        dQuaternion oq;
        to_ode(q, oq);
        dBodySetQuaternion(wk.id, oq);
      }
    }
    dBodyEnable(wk.id);
  }
  if (!moved) return;
  // Every point of a moved body is now as deep as the move left it.
  for (std::uint32_t ci = 0; ci < commands; ++ci) {
    const ContactCommand& c = contacts_[ci];
    const std::int32_t ba = m.body_of(c.a), bb = m.body_of(c.b);
    const std::int32_t wa = ba >= 0 ? slot[ba] : -1, wb = bb >= 0 ? slot[bb] : -1;
    if (wa < 0 && wb < 0) continue;
    for (std::uint32_t k = c.first; k < c.first + c.count; ++k) {
      const ContactPoint& p = cp[k];
      m.depth[k] = std::max(
          0.0, m.depth[k] - dot(p.normal, moved_at(wa, p.position) - moved_at(wb, p.position)));
    }
  }
}

void RigidBodyResolver::carry_depths(double h) {
  // Between substeps no new contacts are found: each kept point's depth grows
  // by how far its parts approached along the normal, so that the error
  // reduction does not push the same overlap out once per substep.
  Impl& m = *impl_;
  for (const auto& r : m.records) {
    const ContactCommand& c = contacts_[r.command];
    const std::int32_t ba = m.body_of(c.a), bb = m.body_of(c.b);
    dBodyID b1 = m.bodies[r.swapped ? bb : ba].id;
    dBodyID b2 = r.swapped ? nullptr : (bb >= 0 ? m.bodies[bb].id : nullptr);
    const double sign = r.swapped ? -1.0 : 1.0;
    for (std::uint32_t k = c.first; k < c.first + c.count; ++k) {
      const ContactPoint& p = contact_points_[k];
      m.depth[k] += h * approach_speed(b1, b2, p.position, sign * p.normal);
    }
  }
}

void RigidBodyResolver::find_substep_contacts(ResolverAccess& access) {
  // The window's pairs again, with the points ODE's narrow phase finds for
  // the two shapes where the parts are now (a body's part where its body
  // is, any other part where its properties put it). Each command keeps its
  // index, so a pair that no longer touches has count 0 for this substep.
  Impl& m = *impl_;
  const PropertyStore& store = access.store();
  const auto position = access.column<Vec3>(m.id.position);
  const auto orientation = access.column<Quat>(m.id.orientation);
  const auto shape = access.column<EnumValue>(m.id.shape);
  const auto size = access.column<Vec3>(m.id.size);
  const auto radius = access.column<double>(m.id.radius);
  const auto length = access.column<double>(m.id.length);
  if (m.geom_of_slot.size() < store.slot_count())
    m.geom_of_slot.resize(store.slot_count(), nullptr);
  m.collide_buffer.resize(std::size_t(config_.max_contacts));
  auto place = [&](ObjectId o) -> dGeomID {
    const std::uint32_t s = o.index;
    if (!shape.has(s)) return nullptr;
    dGeomID& g = m.geom_of_slot[s];
    const auto sh = Shape(shape[s].index);
    if (!g) {
      switch (sh) {
        case Shape::Box: {
          const Vec3 e = size.value_or(s, {});
          g = dCreateBox(nullptr, e.x, e.y, e.z);
          break;
        }
        case Shape::Sphere:
          g = dCreateSphere(nullptr, radius.value_or(s, 0));
          break;
        case Shape::Capsule:
          g = dCreateCapsule(nullptr, radius.value_or(s, 0), length.value_or(s, 0));
          break;
        case Shape::Cylinder:
          g = dCreateCylinder(nullptr, radius.value_or(s, 0), length.value_or(s, 0));
          break;
      }
    }
    Vec3 x = position.value_or(s, {});
    Quat q = normalized(orientation.value_or(s, Quat{}));
    if (const Impl::Part* p = m.part_for(s, o.generation)) {
      const dBodyID b = m.bodies[p->body].id;
      const Vec3 xb = to_vec3(dBodyGetPosition(b));
      const Quat qb = to_quat(dBodyGetQuaternion(b));
      x = p->identity ? xb : xb + rotate(qb, p->offset);
      q = p->identity ? qb : qb * p->rot;
    }
    dGeomSetPosition(g, x.x, x.y, x.z);
    dQuaternion oq;
    to_ode(sh == Shape::Capsule ? normalized(q) * capsule_axis_rotation() : normalized(q), oq);
    dGeomSetQuaternion(g, oq);
    return g;
  };
  contacts_.clear();
  contact_points_.clear();
  for (const ContactCommand& w : window_contacts_) {
    ContactCommand c = w;
    c.first = std::uint32_t(contact_points_.size());
    c.count = 0;
    const dGeomID ga = place(c.a), gb = place(c.b);
    if (ga && gb) {
      const int n = collide_parts(ga, gb, config_.max_contacts, m.collide_buffer.data());
      for (int k = 0; k < n; ++k) {
        const dContactGeom& g = m.collide_buffer[std::size_t(k)];
        contact_points_.push_back({to_vec3(g.pos), to_vec3(g.normal), g.depth});
      }
      c.count = std::uint32_t(std::max(n, 0));
    }
    contacts_.push_back(c);
  }
}

}  // namespace alloy::rigid
