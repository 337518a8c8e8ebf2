#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

// --- bounds: what the rigid body refuses ---------------------------------------------------
//
// ODE asserts (and, by default, aborts the process) when a number it is given
// is finite but absurd: a bounding box overflows in collide(), a rotation
// cannot be normalised. The property registry bounds every edit (limits::);
// here the rigid body bounds what reaches ODE from its queue and what ODE
// makes of it. A body that would break the bounds is refused: its parts are
// frozen (an "out_of_bounds" event naming the stage that gave the value), it
// is held where it was at the window's start for the rest of the window, and
// the next structure sync rebuilds the world without it. What still goes
// wrong inside ODE arrives as an OdeError (ode_support.hpp) and is reported,
// not fatal.

namespace {

/// The smallest eigenvalue of ODE's symmetric 3x3 inertia (dMatrix3 rows of
/// 4), by the trigonometric solution of the characteristic cubic.
double smallest_moment(const dMatrix3 I) {
  const double a = I[0], b = I[5], c = I[10], d = I[1], e = I[6], f = I[2];
  const double off = d * d + e * e + f * f;
  if (off == 0) return std::min({a, b, c});
  const double q = (a + b + c) / 3;
  const double p =
      std::sqrt(((a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2 * off) / 6);
  if (!(p > 0)) return q;
  const double A = (a - q) / p, B = (b - q) / p, C = (c - q) / p, D = d / p, E = e / p, F = f / p;
  const double r =
      std::clamp((A * (B * C - E * E) - D * (D * C - E * F) + F * (D * E - B * F)) / 2, -1.0, 1.0);
  return q + 2 * p * std::cos(std::acos(r) / 3 + 2 * std::numbers::pi / 3);
}

std::vector<std::pair<std::string, double>> components(Vec3 v) {
  return {{"x", v.x}, {"y", v.y}, {"z", v.z}};
}
/// Whether every component lies within +-bound (false for NaN).
bool within(Vec3 v, double bound) {
  return std::abs(v.x) <= bound && std::abs(v.y) <= bound && std::abs(v.z) <= bound;
}

}  // namespace

bool RigidBodyResolver::Impl::refuse_part(ResolverAccess& access, std::uint32_t slot, double mass,
                                          const dMass& local) {
  std::string why;
  if (!(mass >= limits::min_mass && mass <= limits::max_mass)) {
    why = "has a mass of " + number(mass) + " kg, outside the " + number(limits::min_mass) +
          " .. " + number(limits::max_mass) + " kg a moving body may have";
  } else if (const double i = smallest_moment(local.I);
             !(i >= limits::min_inertia) || !dMassCheck(&local)) {
    why = "has a smallest moment of inertia of " + number(i) + " kg m^2, below the " +
          number(limits::min_inertia) +
          " kg m^2 a moving body needs (a part too light or too thin)";
  }
  if (why.empty()) return false;
  refused[slot] = 1;
  access.refuse(slot, "", why + ": it was left out of the rigid body", {{"mass", mass}});
  return true;
}

void RigidBodyResolver::Impl::measure_bodies() {
  inv_mass.assign(bodies.size(), 0);
  inv_inertia.assign(bodies.size(), 0);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (bodies[b].kinematic) continue;
    dMass mass;
    dBodyGetMass(bodies[b].id, &mass);
    inv_mass[b] = 1 / mass.mass;
    inv_inertia[b] = 1 / std::max(smallest_moment(mass.I), limits::min_inertia);
  }
}

void RigidBodyResolver::screen_loads(ResolverAccess& access, double dt) {
  // The shared screen (load_screen.hpp): each load's share of its body's
  // change of velocity, |F| dt / m and |torque| dt / I_min.
  Impl& m = *impl_;
  const std::size_t nb = m.bodies.size();
  strongest_source_.assign(nb, nullptr);
  if (forces_.size() == 0 && rated_loads_.empty()) return;
  LoadScreen& screen = screen_;
  screen.begin(nb);
  auto add = [&](std::uint32_t b, double f, double t, std::size_t i) {
    screen.add(b, f * dt * m.inv_mass[b], t * dt * m.inv_inertia[b], i);
  };
  const LoadCommand* loads = forces_.begin();
  for (std::size_t i = 0; i < forces_.size(); ++i) {
    const LoadCommand& c = loads[i];
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p || m.bodies[p->body].kinematic) continue;
    const double f = length(c.value);
    switch (c.kind) {
      case Load::Force:
        add(p->body, f, p->identity ? 0 : length(p->offset) * f, i);
        break;
      case Load::ForceAtPoint: {
        const Vec3 x = to_vec3(dBodyGetPosition(m.bodies[p->body].id));
        add(p->body, f,
            LoadScreen::point_within_extent(c.point) ? length(cross(c.point - x, c.value))
                                                     : HUGE_VAL,
            i);
        break;
      }
      case Load::Torque:
        add(p->body, 0, f, i);
        break;
    }
  }
  for (std::size_t j = 0; j < rated_loads_.size(); ++j) {
    const RatedLoad& c = rated_loads_[j];
    const Impl::Part* p = m.part_for(c.slot, c.generation);
    if (!p || m.bodies[p->body].kinematic) continue;
    const double f = length(c.force) + length(c.force_rate) * dt;
    add(p->body, f,
        length(c.torque) + length(c.torque_rate) * dt + (p->identity ? 0 : length(p->offset) * f),
        forces_.size() + j);
  }
  auto source_of = [&](std::size_t i) {
    return i < forces_.size() ? &load_sources_.name_of(i)
                              : &rated_sources_.name_of(i - forces_.size());
  };
  for (std::uint32_t b = 0; b < nb; ++b) {
    if (const std::size_t i = screen.pusher(b); i != LoadScreen::npos)
      strongest_source_[b] = source_of(i);
    if (!screen.breaks(b)) continue;
    const std::size_t i = screen.culprit(b);
    std::string what;
    std::vector<std::pair<std::string, double>> values;
    if (i < forces_.size()) {
      what = LoadScreen::describe(loads[i]);
      values = LoadScreen::components(loads[i].value);
    } else {
      const RatedLoad& c = rated_loads_[i - forces_.size()];
      what = LoadScreen::describe_rated(c.force, c.torque);
      values = LoadScreen::components(c.force);
    }
    refuse_body(access, b, *source_of(i), screen.refusal(b, what, dt), std::move(values));
  }
}

void RigidBodyResolver::check_motion(ResolverAccess& access) {
  // After each ODE step: a body that left the world's extent or broke the
  // speed limits (loads within bounds applied step after step, a solver
  // blow-up) is refused before its pose reaches any property.
  Impl& m = *impl_;
  for (std::uint32_t b = 0; b < m.bodies.size(); ++b) {
    const Impl::Body& body = m.bodies[b];
    if (body.kinematic) continue;
    const Vec3 x = to_vec3(dBodyGetPosition(body.id)), v = to_vec3(dBodyGetLinearVel(body.id)),
               w = to_vec3(dBodyGetAngularVel(body.id));
    if (within(x, limits::extent) && within(v, limits::speed) && within(w, limits::angular_speed))
        [[likely]]
      continue;
    std::string what;
    std::vector<std::pair<std::string, double>> values;
    if (!within(x, limits::extent))
      what = "moved it to " + vector_text(x) + " m, beyond the world's extent of +-" +
             number(limits::extent) + " m",
      values = components(x);
    else if (!within(v, limits::speed))
      what = "gave it a velocity of " + vector_text(v) + " m/s, beyond the limit of +-" +
             number(limits::speed) + " m/s",
      values = components(v);
    else
      what = "gave it an angular velocity of " + vector_text(w) + " rad/s, beyond the limit of +-" +
             number(limits::angular_speed) + " rad/s",
      values = components(w);
    // Loads within the bounds, queued step after step, may have done it: name
    // the stage whose load did the most to the body in this window.
    const std::string* pusher = b < strongest_source_.size() ? strongest_source_[b] : nullptr;
    const bool named = pusher && !pusher->empty();
    refuse_body(access, b, named ? *pusher : "",
                (named ? "pushed it until the rigid body's step " : "") + what +
                    "; it was stopped where the step began",
                std::move(values));
  }
}

void RigidBodyResolver::refuse_body(ResolverAccess& access, std::uint32_t b,
                                    const std::string& source, const std::string& text,
                                    std::vector<std::pair<std::string, double>> values) {
  Impl& m = *impl_;
  Impl::Body& body = m.bodies[b];
  for (std::uint32_t i = body.first_part; i < body.first_part + body.part_count; ++i)
    access.refuse(m.parts[i].id.index, source, text, values);
  // Held for the rest of the window where its parts were last written (the
  // window's start), as an immovable body: no load, no integration, and the
  // properties keep their last values until the rebuild drops it.
  const Impl::Part& p = m.parts[body.first_part];
  const Quat qb = p.identity ? p.q : normalized(p.q * conjugate(p.rot));
  const Vec3 x = p.identity ? p.pos : p.pos - rotate(qb, p.offset);
  dQuaternion q;
  to_ode(qb, q);
  dBodySetPosition(body.id, x.x, x.y, x.z);
  dBodySetQuaternion(body.id, q);
  dBodySetLinearVel(body.id, 0, 0, 0);
  dBodySetAngularVel(body.id, 0, 0, 0);
  dBodySetForce(body.id, 0, 0, 0);
  dBodySetTorque(body.id, 0, 0, 0);
  dBodySetKinematic(body.id);
  body.kinematic = true;
  body.moved = false;
}

void RigidBodyResolver::engine_failed(ResolverAccess& access, const std::string& what) {
  // ODE was interrupted half way: its world is thrown away and rebuilt from
  // the properties at the next advance, which still hold the last good step.
  Impl& m = *impl_;
  try {
    m.destroy_world();
  } catch (const OdeError&) {
    m.world = nullptr, m.contact_group = nullptr;  // leaked rather than half destroyed
    m.bodies.clear(), m.parts.clear(), m.hinges.clear(), m.geom_of_slot.clear();
  }
  m.dirty = true;
  forces_.clear();
  rated_loads_.clear();
  load_sources_.clear();
  rated_sources_.clear();
  contacts_.clear();
  contact_points_.clear();
  displacements_.clear();
  ++engine_errors_;
  access.emit(Event{
      .type = "engine_error",
      .text = what + " (the rigid bodies were rebuilt from their properties; this step's motion "
                     "was dropped)"});
}

}  // namespace alloy::rigid
