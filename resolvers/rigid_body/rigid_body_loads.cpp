#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

void RigidBodyResolver::queue(ObjectId part, Vec3 value, Vec3 point, Load kind) {
  store_.check_alive(part);
  load_sources_.note(forces_.size(), world_.running_stage());
  forces_.push_back({part.index, part.generation, value, point, kind});
}

void RigidBodyResolver::add_force(ObjectId part, Vec3 force) {
  queue(part, force, {}, Load::Force);
}
void RigidBodyResolver::add_force(ObjectId part, Vec3 force, Vec3 point) {
  queue(part, force, point, Load::ForceAtPoint);
}
void RigidBodyResolver::add_torque(ObjectId part, Vec3 torque) {
  queue(part, torque, {}, Load::Torque);
}

std::span<RigidBodyResolver::LoadCommand> RigidBodyResolver::open_loads(std::size_t n) {
  if (open_ == ~std::size_t(0)) {
    open_ = forces_.size();
    load_sources_.note(open_, world_.running_stage());
  }
  LoadCommand* room = forces_.room(open_, n);
  forces_.set_size(open_ + n);
  return {room, n};
}
void RigidBodyResolver::close_loads(std::size_t used) {
  if (open_ == ~std::size_t(0)) return;
  forces_.set_size(open_ + std::min(used, forces_.size() - open_));
  open_ = ~std::size_t(0);
}

void RigidBodyResolver::add_load(ObjectId part, Vec3 force, Vec3 torque, Vec3 force_rate,
                                 Vec3 torque_rate) {
  store_.check_alive(part);
  rated_sources_.note(rated_loads_.size(), world_.running_stage());
  rated_loads_.push_back({part.index, part.generation, force, torque, force_rate, torque_rate});
}

void RigidBodyResolver::add_contact(const ContactCommand& pair,
                                    std::span<const ContactPoint> points) {
  ContactCommand c = pair;
  c.first = std::uint32_t(contact_points_.size());
  c.count = std::uint32_t(points.size());
  contact_points_.insert(contact_points_.end(), points.begin(), points.end());
  contacts_.push_back(c);
}

void RigidBodyResolver::add_contacts(std::span<const ContactCommand> pairs,
                                     std::span<const ContactPoint> points) {
  const auto base = std::uint32_t(contact_points_.size());
  contact_points_.insert(contact_points_.end(), points.begin(), points.end());
  contacts_.reserve(contacts_.size() + pairs.size());
  for (const ContactCommand& pair : pairs) {
    contacts_.push_back(pair);
    contacts_.back().first += base;
  }
}

void RigidBodyResolver::displace(ObjectId part, Vec3 displacement) {
  displacements_.emplace_back(part, displacement);
}

void RigidBodyResolver::apply_displacements() {
  Impl& m = *impl_;
  // Of several parts of one body (an assembly) the one moved back furthest wins.
  std::vector<std::pair<std::int32_t, Vec3>> moves;
  for (const auto& [part, d] : displacements_) {
    const std::int32_t b = m.body_of(part);
    if (b < 0 || m.bodies[b].kinematic) continue;
    auto it =
        std::find_if(moves.begin(), moves.end(), [&](const auto& mv) { return mv.first == b; });
    if (it == moves.end())
      moves.emplace_back(b, d);
    else if (length(d) > length(it->second))
      it->second = d;
  }
  for (const auto& [b, d] : moves) {
    const dBodyID id = m.bodies[b].id;
    const dReal* x = dBodyGetPosition(id);
    dBodySetPosition(id, x[0] + d.x, x[1] + d.y, x[2] + d.z);
    dBodyEnable(id);
  }
  displacements_.clear();
}

void RigidBodyResolver::hold(std::span<const ObjectId> parts) {
  held_.assign(parts.begin(), parts.end());
}

void RigidBodyResolver::apply_holds() {
  // Held: disabled (apply_loads skips it, ODE does not integrate it; it has
  // no contacts, collisions left it out) with no velocity, so that it comes
  // back at rest where it waited. Released when the list leaves it out.
  Impl& m = *impl_;
  std::vector<std::uint8_t> want(m.bodies.size(), 0);
  for (const ObjectId part : held_)
    if (const std::int32_t b = m.body_of(part); b >= 0 && !m.bodies[b].kinematic) want[b] = 1;
  held_bodies_ = 0;
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    Impl::Body& body = m.bodies[b];
    if (want[b]) {
      dBodySetLinearVel(body.id, 0, 0, 0);
      dBodySetAngularVel(body.id, 0, 0, 0);
      dBodySetForce(body.id, 0, 0, 0);
      dBodySetTorque(body.id, 0, 0, 0);
      dBodyDisable(body.id);
      body.held = true;
      ++held_bodies_;
    } else if (body.held) {
      body.held = false;
      dBodyEnable(body.id);
    }
  }
}

void RigidBodyResolver::apply_loads() {
  Impl& m = *impl_;
  for (const LoadCommand& c : forces_) {
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p) continue;
    const Impl::Body& b = m.bodies[p->body];
    if (b.kinematic || !dBodyIsEnabled(b.id)) continue;  // a sleeping body keeps no load
    switch (c.kind) {
      case Load::Force:
        if (p->identity) {
          dBodyAddForce(b.id, c.value.x, c.value.y, c.value.z);
        } else {
          dVector3 at;
          dBodyGetRelPointPos(b.id, p->offset.x, p->offset.y, p->offset.z, at);
          dBodyAddForceAtPos(b.id, c.value.x, c.value.y, c.value.z, at[0], at[1], at[2]);
        }
        break;
      case Load::ForceAtPoint:
        dBodyAddForceAtPos(b.id, c.value.x, c.value.y, c.value.z, c.point.x, c.point.y, c.point.z);
        break;
      case Load::Torque:
        dBodyAddTorque(b.id, c.value.x, c.value.y, c.value.z);
        break;
    }
  }
}

void RigidBodyResolver::apply_rated_loads(double tau) {
  // The first-order hold of add_load: the value at `tau` s into the window,
  // the force at the part's centre where the part is now.
  Impl& m = *impl_;
  for (const RatedLoad& c : rated_loads_) {
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p) continue;
    const Impl::Body& b = m.bodies[p->body];
    if (b.kinematic || !dBodyIsEnabled(b.id)) continue;
    const Vec3 f = c.force + tau * c.force_rate, t = c.torque + tau * c.torque_rate;
    if (p->identity) {
      dBodyAddForce(b.id, f.x, f.y, f.z);
    } else {
      dVector3 at;
      dBodyGetRelPointPos(b.id, p->offset.x, p->offset.y, p->offset.z, at);
      dBodyAddForceAtPos(b.id, f.x, f.y, f.z, at[0], at[1], at[2]);
    }
    dBodyAddTorque(b.id, t.x, t.y, t.z);
  }
}

void RigidBodyResolver::wake_on_load_change() {
  Impl& m = *impl_;
  for (Impl::Body& b : m.bodies) b.load_force = b.load_torque = Vec3{};
  for (const LoadCommand& c : forces_) {
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p) continue;
    Impl::Body& b = m.bodies[p->body];
    if (b.kinematic) continue;
    const Vec3 x = to_vec3(dBodyGetPosition(b.id));
    switch (c.kind) {
      case Load::Force:
        b.load_force += c.value;
        if (!p->identity)
          b.load_torque += cross(rotate(to_quat(dBodyGetQuaternion(b.id)), p->offset), c.value);
        break;
      case Load::ForceAtPoint:
        b.load_force += c.value;
        b.load_torque += cross(c.point - x, c.value);
        break;
      case Load::Torque:
        b.load_torque += c.value;
        break;
    }
  }
  for (const RatedLoad& c : rated_loads_) {  // their value at the window's start
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p || m.bodies[p->body].kinematic) continue;
    Impl::Body& b = m.bodies[p->body];
    b.load_force += c.force;
    b.load_torque += c.torque;
    if (!p->identity)
      b.load_torque += cross(rotate(to_quat(dBodyGetQuaternion(b.id)), p->offset), c.force);
  }
  for (Impl::Body& b : m.bodies) {
    if (b.kinematic) continue;
    b.asleep = !dBodyIsEnabled(b.id);
    if (!b.asleep) {
      b.awake_force = b.load_force, b.awake_torque = b.load_torque;
      continue;
    }
    // The load it slept under (its weight, a magnet's pull) holds it still;
    // a different one (the magnet switched on, gravity turned) must move it.
    // Tolerances: 0.1 % of that load, or an acceleration of 1 mm/s^2.
    const double df = length(b.load_force - b.awake_force),
                 dtq = length(b.load_torque - b.awake_torque);
    if (df > 1e-3 * length(b.awake_force) + 1e-3 * b.mass ||
        dtq > 1e-3 * length(b.awake_torque) + 1e-4 * b.mass) {
      dBodySetForce(b.id, 0, 0, 0);
      dBodySetTorque(b.id, 0, 0, 0);
      dBodyEnable(b.id);
      b.asleep = false;
      b.awake_force = b.load_force, b.awake_torque = b.load_torque;
    }
  }
}

}  // namespace alloy::rigid
