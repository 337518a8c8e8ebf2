#include "resolvers/rigid_body/hinge_anchors.hpp"
#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

namespace {

/// The angle of rotation q about the unit axis (the twist of a swing-twist
/// decomposition), wrapped to (-pi, pi].
double twist_angle(Quat q, Vec3 axis) {
  double a = 2.0 * std::atan2(q.x * axis.x + q.y * axis.y + q.z * axis.z, q.w);
  constexpr double pi = std::numbers::pi;
  if (a > pi) a -= 2 * pi;
  if (a <= -pi) a += 2 * pi;
  return a;
}

}  // namespace

void RigidBodyResolver::Impl::rebuild(ResolverAccess& access) {
  destroy_world();
  create_world();
  damping_dt = 0;

  const PropertyStore& store = access.store();
  const auto position = access.column<Vec3>(id.position);
  const auto orientation = access.column<Quat>(id.orientation);
  const auto velocity = access.column<Vec3>(id.velocity);
  const auto angular_velocity = access.column<Vec3>(id.angular_velocity);
  const auto mass = access.column<double>(id.mass);
  const auto density = access.column<double>(id.density);
  const auto shape = access.column<EnumValue>(id.shape);
  const auto size = access.column<Vec3>(id.size);
  const auto radius = access.column<double>(id.radius);
  const auto length = access.column<double>(id.length);
  const auto is_static = access.column<std::uint8_t>(id.static_);
  const auto pinned = access.column<std::uint8_t>(id.pinned);
  const auto planar = access.column<std::uint8_t>(id.planar);
  const auto linear_damping = access.column<double>(id.linear_damping);
  const auto angular_damping = access.column<double>(id.angular_damping);
  const auto joint = access.column<EnumValue>(id.joint);
  const auto body_a = access.column<ObjectId>(id.body_a);
  const auto body_b = access.column<ObjectId>(id.body_b);
  const auto anchor = access.column<Vec3>(id.anchor);
  const auto anchor_a = access.column<Vec3>(id.anchor_a);
  const auto anchor_b = access.column<Vec3>(id.anchor_b);
  const auto axis = access.column<Vec3>(id.axis);
  const auto joint_friction = access.column<double>(id.joint_friction);
  const auto limit_low = access.column<double>(id.limit_low);
  const auto limit_high = access.column<double>(id.limit_high);
  auto mass_out = access.writer<double>(id.mass);
  auto anchor_out = access.writer<Vec3>(id.anchor);
  auto anchor_a_out = access.writer<Vec3>(id.anchor_a);
  auto anchor_b_out = access.writer<Vec3>(id.anchor_b);
  auto axis_out = access.writer<Vec3>(id.axis);

  const std::size_t slots = store.slot_count();
  part_of_slot.assign(slots, -1);
  refused.assign(slots, 0);

  // 1. Candidate parts: every live object with mass or density that is not static.
  struct Candidate {
    std::uint32_t slot;
    double mass;
    dMass local;  // about the part's centre of mass, in the part's frame
    Vec3 x;
    Quat q;
  };
  std::vector<Candidate> cand;
  std::vector<std::int32_t> cand_of_slot(slots, -1);
  for (std::uint32_t s = 0; s < slots; ++s) {
    const ObjectId obj = store.id_at(s);
    if (obj.is_null() || !(mass.has(s) || density.has(s)) || is_static.value_or(s, 0)) continue;
    const ErrorLocation where{"", 0, store.describe(obj)};
    if (!shape.has(s))
      throw InputError(
          where, "it has mass but no shape: give it shape = box, sphere, capsule or cylinder");
    const auto sh = Shape(shape[s].index);
    const Vec3 sz = size.value_or(s, {});
    const double r = radius.value_or(s, 0), len = length.value_or(s, 0);
    switch (sh) {
      case Shape::Box:
        if (!(sz.x > 0 && sz.y > 0 && sz.z > 0))
          throw InputError(where, "a box needs a size with every extent > 0");
        break;
      case Shape::Sphere:
        if (!(r > 0)) throw InputError(where, "a sphere needs a radius > 0");
        break;
      case Shape::Capsule:
        if (!(r > 0) || !(len >= 0))
          throw InputError(where, "a capsule needs a radius > 0 and a length >= 0");
        break;
      case Shape::Cylinder:
        if (!(r > 0) || !(len > 0))
          throw InputError(where, "a cylinder needs a radius > 0 and a length > 0");
        break;
    }
    double m;
    if (density.has(s)) {
      // Density, when given, decides: mass follows the shape when it is resized.
      m = density[s] * shape_volume(sh, sz, r, len);
      if (!(m > 0)) throw InputError(where, "density must be > 0");
      mass_out.set(s, m);
    } else {
      m = mass[s];
      if (!(m > 0)) throw InputError(where, "mass must be > 0, got " + std::to_string(m));
    }
    dMass local;
    switch (sh) {
      case Shape::Box:
        dMassSetBoxTotal(&local, m, sz.x, sz.y, sz.z);
        break;
      case Shape::Sphere:
        dMassSetSphereTotal(&local, m, r);
        break;
      case Shape::Capsule:
        dMassSetCapsuleTotal(&local, m, 1 /* along x */, r, len);
        break;
      case Shape::Cylinder: {  // along z; cylinder_inertia's formulas
        const Vec3 i = cylinder_inertia(m, r, len);
        dMassSetParameters(&local, m, 0, 0, 0, i.x, i.y, i.z, 0, 0, 0);
        break;
      }
    }
    if (refuse_part(access, s, m, local)) continue;
    cand_of_slot[s] = std::int32_t(cand.size());
    cand.push_back(
        {s, m, local, position.value_or(s, {}), normalized(orientation.value_or(s, Quat{}))});
  }

  // 2. Joints: fixed joints unite parts into assemblies; hinges are made below.
  std::vector<std::int32_t> parent(cand.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = std::int32_t(i);
  auto find = [&](std::int32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<std::uint8_t> glued_to_world(cand.size(), 0);
  struct PendingHinge {
    std::uint32_t slot;
    std::int32_t a, b;  // candidate indices, -1: the play area
  };
  std::vector<PendingHinge> pending;
  // kOther: a rigid body outside this engine's scope, which another area's
  // engine holds. The world scopes a joint by the bodies it joins (a joint
  // has no position): it is in our scope only when every body it joins that
  // has a position is, and suspended while they are on two engines. So a
  // body of another engine here is one without a position (in no area),
  // joined to one of ours that is in an area: refused, naming both.
  constexpr std::int32_t kWorld = -1, kGone = -2, kOther = -3;
  for (std::uint32_t s : joint.members()) {
    const ObjectId jid = store.id_at(s);
    const ErrorLocation where{"", 0, store.describe(jid)};
    auto ref = [&](const ColumnView<ObjectId>& col, const char* name) -> std::int32_t {
      if (!col.has(s) || col[s].is_null()) return kWorld;
      const ObjectId o = col[s];
      // A part destroyed, refused or frozen: the joint holds nothing.
      if (!store.alive(o) || refused[o.index] || host->frozen(o)) return kGone;
      if (cand_of_slot[o.index] >= 0) return cand_of_slot[o.index];
      if (is_static.value_or(o.index, 0)) return kWorld;
      // A rigid body outside this engine's scope: another area's engine holds it.
      if (store.has(o, id.mass) || store.has(o, id.density)) return kOther;
      throw InputError(where, std::string(name) + " is '" + store.describe(o) +
                                  "', which is neither a rigid body (mass or density) nor static");
    };
    if (!body_a.has(s)) throw InputError(where, "a joint needs body_a");
    std::int32_t a = ref(body_a, "body_a"), b = ref(body_b, "body_b");
    if (a == kGone || b == kGone || (a == kWorld && b == kWorld)) continue;
    if (a == kOther || b == kOther) {
      auto named = [&](const ColumnView<ObjectId>& c) {
        return c.has(s) && !c[s].is_null() ? "'" + store.describe(c[s]) + "'" : "the play area";
      };
      const ObjectId other = a == kOther ? body_a[s] : body_b[s];
      throw InputError(where, "joins " + named(body_a) + " to " + named(body_b) + ", but '" +
                                  store.describe(other) +
                                  "' is simulated by another engine (it has no position, so it "
                                  "is in no area): a joint follows its bodies into areas by "
                                  "their positions; give it one");
    }
    if (JointType(joint[s].index) == JointType::Fixed) {
      if (a >= 0 && b >= 0)
        parent[find(a)] = find(b);
      else
        glued_to_world[a >= 0 ? a : b] = 1;
    } else {
      pending.push_back({s, a, b});
    }
  }

  // 3. One ODE body per assembly, in order of the assembly's first part.
  std::vector<std::int32_t> body_of_root(cand.size(), -1), body_of_cand(cand.size());
  std::vector<std::vector<std::int32_t>> members;
  for (std::size_t i = 0; i < cand.size(); ++i) {
    const std::int32_t r = find(std::int32_t(i));
    if (body_of_root[r] < 0) {
      body_of_root[r] = std::int32_t(members.size());
      members.emplace_back();
    }
    body_of_cand[i] = body_of_root[r];
    members[body_of_root[r]].push_back(std::int32_t(i));
  }
  bodies.reserve(members.size());
  parts.reserve(cand.size());
  for (std::size_t bi = 0; bi < members.size(); ++bi) {
    const auto& mem = members[bi];
    const Candidate& root = cand[mem.front()];
    Body body;
    body.first_part = std::uint32_t(parts.size());
    body.part_count = std::uint32_t(mem.size());
    // The body frame is the first part's orientation at its centre of mass.
    const Quat qb = root.q;
    Vec3 com = root.x;
    dMass total = root.local;
    if (mem.size() > 1) {
      double m_sum = 0;
      Vec3 mx{};
      for (std::int32_t i : mem) m_sum += cand[i].mass, mx += cand[i].mass * cand[i].x;
      com = mx / m_sum;
      dMassSetZero(&total);
    }
    for (std::int32_t i : mem) {
      const Candidate& c = cand[i];
      Part p;
      p.id = store.id_at(c.slot);
      p.body = std::uint32_t(bi);
      if (mem.size() > 1) {
        p.identity = false;
        p.rot = normalized(conjugate(qb) * c.q);
        p.offset = rotate(conjugate(qb), c.x - com);
        dMass m = c.local;
        dQuaternion q;
        dMatrix3 R;
        to_ode(p.rot, q);
        dQtoR(q, R);
        dMassRotate(&m, R);
        dMassTranslate(&m, p.offset.x, p.offset.y, p.offset.z);
        dMassAdd(&total, &m);
      }
      body.kinematic = body.kinematic || pinned.value_or(c.slot, 0) || glued_to_world[i];
      body.planar = body.planar || planar.value_or(c.slot, 0);
      body.linear_damping = std::max(body.linear_damping, linear_damping.value_or(c.slot, 0));
      body.angular_damping = std::max(body.angular_damping, angular_damping.value_or(c.slot, 0));
      part_of_slot[c.slot] = std::int32_t(parts.size());
      parts.push_back(p);
    }
    // The parts' centres of mass were measured from the assembly's, so the
    // residual is rounding; ODE wants it exactly at the body origin.
    total.c[0] = total.c[1] = total.c[2] = 0;

    body.id = dBodyCreate(world);
    dBodySetMass(body.id, &total);
    body.mass = total.mass;
    dBodySetPosition(body.id, com.x, com.y, com.z);
    dQuaternion q;
    to_ode(qb, q);
    dBodySetQuaternion(body.id, q);
    if (body.kinematic) {
      dBodySetKinematic(body.id);
    } else {
      // An assembly moves as its first part does when every part moves with
      // it (the engines wrote them so); parts glued while moving apart keep
      // their momentum and their angular momentum about the assembly's centre
      // (adv15 F13: they took the first part's velocity).
      Vec3 w = angular_velocity.value_or(root.slot, {});
      Vec3 v = velocity.value_or(root.slot, {}) + cross(w, com - root.x);
      if (mem.size() > 1) {
        auto norm = [](Vec3 x) { return std::sqrt(dot(x, x)); };
        Vec3 p{}, L{};
        bool rigid = true;
        for (std::int32_t i : mem) {
          const Candidate& c = cand[i];
          const Vec3 vi = velocity.value_or(c.slot, {}), wi = angular_velocity.value_or(c.slot, {});
          const Vec3 r = c.x - com;
          p += c.mass * vi;
          // The part's own spin: its inertia (part frame) turned to the world.
          const Vec3 wl = rotate(conjugate(c.q), wi);
          const dReal* I = c.local.I;
          const Vec3 Iw{I[0] * wl.x + I[1] * wl.y + I[2] * wl.z,
                        I[4] * wl.x + I[5] * wl.y + I[6] * wl.z,
                        I[8] * wl.x + I[9] * wl.y + I[10] * wl.z};
          L += rotate(c.q, Iw) + c.mass * cross(r, vi);
          // Moving with the assembly within rounding (1e-6 relative, as Box2D's
          // single precision writes it): nothing changes.
          const Vec3 dv = vi - (v + cross(w, r)), dw = wi - w;
          const double tol = 1e-6 * (1 + norm(v) + norm(w) * (1 + norm(r)));
          if (norm(dv) > tol || norm(dw) > tol) rigid = false;
        }
        if (!rigid) {
          v = p / total.mass;
          dMatrix3 inv;
          if (dInvertPDMatrix(total.I, inv, 3)) {
            const Vec3 Lb = rotate(conjugate(qb), L);
            w = rotate(qb, Vec3{inv[0] * Lb.x + inv[1] * Lb.y + inv[2] * Lb.z,
                                inv[4] * Lb.x + inv[5] * Lb.y + inv[6] * Lb.z,
                                inv[8] * Lb.x + inv[9] * Lb.y + inv[10] * Lb.z});
          }
        }
      }
      dBodySetLinearVel(body.id, v.x, v.y, v.z);
      dBodySetAngularVel(body.id, w.x, w.y, w.z);
      // Exact rotation for a constant angular velocity: the infinitesimal
      // default loses 1e-5 rad per second at 2 rad/s, more for a motor's rotor.
      dBodySetFiniteRotationMode(body.id, 1);
      if (body.planar) {
        dJointID plane = dJointCreatePlane2D(world, 0);
        dJointAttach(plane, body.id, nullptr);
      }
    }
    if (!body.kinematic && !body.planar) {
      // Inertia the same about every axis (a sphere, a cube): no gyroscopic
      // term, nothing to conserve beyond what ODE does.
      const dReal* I = total.I;
      const double scale = std::max({I[0], I[5], I[10]});
      const double off = std::max({std::abs(I[1]), std::abs(I[2]), std::abs(I[6])});
      if (off > 1e-12 * scale || std::abs(I[0] - I[5]) > 1e-12 * scale ||
          std::abs(I[0] - I[10]) > 1e-12 * scale) {
        Gyro g{std::uint32_t(bodies.size()), {}, {}};
        dMatrix3 inv;
        if (dInvertPDMatrix(I, inv, 3)) {
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) g.inv_inertia[3 * r + c] = inv[4 * r + c];
          dBodySetGyroscopicMode(body.id, 0);
          gyros.push_back(g);
        }
      }
    }
    bodies.push_back(body);
  }

  // 4. Hinges. The angle is that of body_a relative to body_b about the axis,
  // zero when their orientations are equal: a convention that depends on
  // properties alone, so that limits survive a rebuild or a swap of resolver.
  hinges.reserve(pending.size());
  std::vector<std::int32_t> projected(bodies.size(), -1);  // body -> its index in projection
  auto projected_body = [&](std::int32_t b) {
    if (projected[b] < 0) {
      projected[b] = projection.add_body(bodies[b].id, bodies[b].planar, bodies[b].kinematic);
      projection_calls.push_back({b, bodies[b].planar, bodies[b].kinematic, 0, 0, {}, {}});
    }
    return projected[b];
  };
  for (const PendingHinge& h : pending) {
    const std::int32_t ba = h.a >= 0 ? body_of_cand[h.a] : -1,
                       bb = h.b >= 0 ? body_of_cand[h.b] : -1;
    if (ba == bb) continue;  // both in one assembly: already rigid
    const ObjectId jid = store.id_at(h.slot);
    const ErrorLocation where{"", 0, store.describe(jid)};
    Vec3 ax = unit(axis.value_or(h.slot, {0, 0, 1}));  // any finite size: scaled first
    if (ax == Vec3{}) throw InputError(where, "a hinge axis must not be zero");
    const Quat qa = h.a >= 0 ? cand[h.a].q : Quat{}, qbb = h.b >= 0 ? cand[h.b].q : Quat{};
    // The points each part is held at, as defined (hinge_anchors.hpp): a
    // swap or a rebuild does not bake the present stretch into the joint.
    const Vec3 given = anchor.value_or(h.slot, {}), given_a = anchor_a.value_or(h.slot, {}),
               given_b = anchor_b.value_or(h.slot, {});
    const HingeAnchors held = hinge_anchors(
        anchor.has(h.slot) ? &given : nullptr, cand[h.a >= 0 ? h.a : h.b].x,
        anchor_a.has(h.slot) ? &given_a : nullptr, anchor_b.has(h.slot) ? &given_b : nullptr,
        h.a >= 0, h.a >= 0 ? cand[h.a].x : Vec3{}, qa, h.b >= 0, h.b >= 0 ? cand[h.b].x : Vec3{},
        qbb);
    double angle = twist_angle(qa * conjugate(qbb), ax);
    double lo = limit_low.value_or(h.slot, -dInfinity), hi = limit_high.value_or(h.slot, dInfinity);
    if (lo > hi) throw InputError(where, "limit_low must not exceed limit_high");
    // ODE wants a body first; when body_a is the play area the joint is seen
    // from body_b, and angle and limits change sign.
    const bool swapped = ba < 0;
    if (swapped) angle = -angle, std::swap(lo, hi), lo = -lo, hi = -hi;
    dBodyID b1 = bodies[swapped ? bb : ba].id;
    dBodyID b2 = swapped ? nullptr : (bb >= 0 ? bodies[bb].id : nullptr);
    bodies[swapped ? bb : ba].jointed = true;
    if (!swapped && bb >= 0) bodies[bb].jointed = true;
    dJointID j = dJointCreateHinge(world, 0);
    dJointAttach(j, b1, b2);
    // ODE's body 1 is part a's body unless a is the play area.
    const Vec3 p1 = swapped ? held.on_b : held.on_a, p2 = swapped ? held.on_a : held.on_b;
    set_hinge_anchors(j, b1, p1, p2);
    const Vec3 ode_axis = ax;
    dJointSetHingeAxisOffset(j, ode_axis.x, ode_axis.y, ode_axis.z, angle);
    if (hi < dInfinity) dJointSetHingeParam(j, dParamHiStop, hi);
    if (lo > -dInfinity) dJointSetHingeParam(j, dParamLoStop, lo);
    const double friction = joint_friction.value_or(h.slot, 0);
    if (friction > 0) {
      // A motor that wants zero relative speed, with at most `friction` of
      // torque: Coulomb friction in the pivot.
      dJointSetHingeParam(j, dParamVel, 0);
      dJointSetHingeParam(j, dParamFMax, friction);
    }
    hinges.push_back({jid, j, b2 == nullptr});
    hinge_setup.push_back({p2, ode_axis, angle, p1});
    if (config.joint_projection) {
      const std::int32_t q1 = projected_body(swapped ? bb : ba), q2 = b2 ? projected_body(bb) : -1;
      projection.add_hinge(q1, q2, p1, ax, p2);
      projection_calls.push_back({-1, 0, 0, q1, q2, p1, ax, p2});
    }
    if (held.defined) {
      anchor_a_out.set(h.slot, held.local_a);
      anchor_b_out.set(h.slot, held.local_b);
    }
    if (!anchor.has(h.slot)) anchor_out.set(h.slot, held.on_a);
    if (!axis.has(h.slot)) axis_out.set(h.slot, ax);
  }

  projection.finish();
  for (std::uint32_t b = 0; b < bodies.size(); ++b) {
    if (!bodies[b].jointed) continue;
    SetupPose sp{b, {}, {}};
    static_assert(sizeof(SetupPose) == 8 * 8 && sizeof(ProjectionCall) == 5 * 8 + 3 * sizeof(Vec3));
    std::copy_n(dBodyGetPosition(bodies[b].id), 3, sp.pos);
    std::copy_n(dBodyGetQuaternion(bodies[b].id), 4, sp.q);
    setup_poses.push_back(sp);
  }
  write_poses(access, true);
  dirty = false;
}

void RigidBodyResolver::Impl::write_poses(ResolverAccess& access, bool all) {
  auto position = access.writer<Vec3>(id.position);
  auto orientation = access.writer<Quat>(id.orientation);
  auto velocity = access.writer<Vec3>(id.velocity);
  auto angular_velocity = access.writer<Vec3>(id.angular_velocity);
  for (Body& b : bodies) {
    if (b.kinematic && !all && !b.moved) continue;  // pinned parts do not move
    // A body that slept through the whole advance has nothing new to say.
    if (b.asleep && !all && !b.moved && !dBodyIsEnabled(b.id)) continue;
    b.moved = false;
    const Vec3 x = to_vec3(dBodyGetPosition(b.id));
    const Quat q = to_quat(dBodyGetQuaternion(b.id));
    const Vec3 v = b.kinematic ? Vec3{} : to_vec3(dBodyGetLinearVel(b.id));
    const Vec3 w = b.kinematic ? Vec3{} : to_vec3(dBodyGetAngularVel(b.id));
    for (std::uint32_t i = b.first_part; i < b.first_part + b.part_count; ++i) {
      Part& p = parts[i];
      if (p.identity) {
        p.pos = x, p.q = q, p.vel = v;
      } else {
        const Vec3 r = rotate(q, p.offset);
        p.pos = x + r, p.q = q * p.rot, p.vel = v + cross(w, r);
      }
      p.angvel = w;
      const std::uint32_t s = p.id.index;
      position.set(s, p.pos);
      orientation.set(s, p.q);
      velocity.set(s, p.vel);
      angular_velocity.set(s, p.angvel);
    }
  }
}

void RigidBodyResolver::Impl::write_hinges(ResolverAccess& access) {
  if (hinges.empty()) return;
  auto anchor = access.writer<Vec3>(id.anchor);
  auto axis = access.writer<Vec3>(id.axis);
  for (const Hinge& h : hinges) {
    dVector3 p, a;
    // A pivot in the play area stays where the play area holds it.
    if (h.to_world)
      dJointGetHingeAnchor2(h.joint, p);
    else
      dJointGetHingeAnchor(h.joint, p);
    dJointGetHingeAxis(h.joint, a);
    anchor.set(h.id.index, to_vec3(p));
    axis.set(h.id.index, to_vec3(a));
  }
}

void RigidBodyResolver::Impl::apply_edits(ResolverAccess& access) {
  bool changed[4];
  bool any = false;
  for (int i = 0; i < 4; ++i) any |= changed[i] = pose_columns[i]->version() != pose_seen[i];
  if (!any) return;
  const auto position = access.column<Vec3>(id.position);
  const auto orientation = access.column<Quat>(id.orientation);
  const auto velocity = access.column<Vec3>(id.velocity);
  const auto angular_velocity = access.column<Vec3>(id.angular_velocity);
  for (Part& p : parts) {
    const std::uint32_t s = p.id.index;
    const bool dp = changed[0] && !(position.value_or(s, p.pos) == p.pos);
    const bool dq = changed[1] && !(orientation.value_or(s, p.q) == p.q);
    const bool dv = changed[2] && !(velocity.value_or(s, p.vel) == p.vel);
    const bool dw = changed[3] && !(angular_velocity.value_or(s, p.angvel) == p.angvel);
    if (!(dp || dq || dv || dw)) continue;
    Body& b = bodies[p.body];
    if (dp || dq) {
      // Teleport: the part goes where it was put, its assembly with it.
      const Quat qp = dq ? normalized(orientation[s]) : p.q;
      const Vec3 xp = dp ? position[s] : p.pos;
      const Quat qb = p.identity ? qp : normalized(qp * conjugate(p.rot));
      const Vec3 x = p.identity ? xp : xp - rotate(qb, p.offset);
      dQuaternion q;
      to_ode(qb, q);
      dBodySetPosition(b.id, x.x, x.y, x.z);
      dBodySetQuaternion(b.id, q);
      b.moved = true;
    }
    if ((dv || dw) && !b.kinematic) {
      const Vec3 w = dw ? angular_velocity[s] : to_vec3(dBodyGetAngularVel(b.id));
      const Vec3 vp = dv ? velocity[s] : p.vel;
      Vec3 v = vp;
      if (!p.identity) v = vp - cross(w, rotate(to_quat(dBodyGetQuaternion(b.id)), p.offset));
      dBodySetLinearVel(b.id, v.x, v.y, v.z);
      dBodySetAngularVel(b.id, w.x, w.y, w.z);
    }
    dBodyEnable(b.id);
  }
}

void RigidBodyResolver::Impl::begin_rotation() {
  for (Gyro& g : gyros) g.q0 = to_quat(dBodyGetQuaternion(bodies[g.body].id));
}

void RigidBodyResolver::Impl::conserve_rotation(double h) {
  // Euler's equations, I w' + w x I w = torque, integrated so that a free
  // body keeps its angular momentum exactly and its energy to O(h^2) with no
  // drift (a torque-free box tumbling 10 s at 1/240 s: both within 1e-4).
  // ODE's own gyroscopic term is an implicit Euler step: it loses energy
  // (7 % in those 10 s) and turns the momentum (3 %). With it switched off,
  // ODE's step gives the body w = w0 + h I0^-1 (torque + constraint torques),
  // so L = I0 w is exactly the angular momentum after the step's impulses;
  // what it gets wrong is the orientation (turned by that w while the
  // inertia turns with the body) and the w it reports. Here the orientation
  // is redone by the implicit midpoint rule on rotations, which is symmetric
  // and so has no energy drift: q1 = exp(h w_m) q0 with w_m = I(q_m)^-1 L at
  // q_m = exp(h w_m / 2) q0 (a few fixed-point passes; h |w| is small), and
  // the body leaves with w1 = I(q1)^-1 L.
  for (const Gyro& g : gyros) {
    const dBodyID id = bodies[g.body].id;
    if (!dBodyIsEnabled(id)) continue;
    const Vec3 w = to_vec3(dBodyGetAngularVel(id));
    auto apply_inverse = [&](Quat q, Vec3 l) {  // I(q)^-1 l, world frame
      const Vec3 b = rotate(conjugate(q), l);
      const double* m = g.inv_inertia;
      return rotate(q,
                    Vec3{m[0] * b.x + m[1] * b.y + m[2] * b.z, m[3] * b.x + m[4] * b.y + m[5] * b.z,
                         m[6] * b.x + m[7] * b.y + m[8] * b.z});
    };
    auto turn = [](Vec3 w, double t, Quat q) {
      const double a = length(w) * t;
      return a > 0 ? normalized(Quat::from_axis_angle(w / length(w), a) * q) : q;
    };
    // L = I(q0) w: the inertia the step's velocity update used.
    const Vec3 b = rotate(conjugate(g.q0), w);
    dMass mass;
    dBodyGetMass(id, &mass);
    const dReal* I = mass.I;
    const Vec3 l = rotate(
        g.q0, Vec3{I[0] * b.x + I[1] * b.y + I[2] * b.z, I[4] * b.x + I[5] * b.y + I[6] * b.z,
                   I[8] * b.x + I[9] * b.y + I[10] * b.z});
    Vec3 wm = w;
    for (int it = 0; it < 4; ++it) wm = apply_inverse(turn(wm, h / 2, g.q0), l);
    const Quat q1 = turn(wm, h, g.q0);
    const Vec3 w1 = apply_inverse(q1, l);
    dQuaternion oq;
    to_ode(q1, oq);
    dBodySetQuaternion(id, oq);
    dBodySetAngularVel(id, w1.x, w1.y, w1.z);
  }
}

void RigidBodyResolver::Impl::fix_planar() {
  // Plane2D constrains velocities; rounding still tilts the rotation a little
  // each step. Project it back onto rotations about z (as ODE's demo_plane2d does).
  for (const Body& b : bodies) {
    if (!b.planar || b.kinematic) continue;
    const dReal* q = dBodyGetQuaternion(b.id);
    const double n = std::hypot(q[0], q[3]);
    if (q[1] == 0 && q[2] == 0 && n == 1) continue;
    const dQuaternion fixed = {q[0] / n, 0, 0, q[3] / n};
    dBodySetQuaternion(b.id, fixed);
    const dReal* w = dBodyGetAngularVel(b.id);
    dBodySetAngularVel(b.id, 0, 0, w[2]);
  }
}

}  // namespace alloy::rigid
