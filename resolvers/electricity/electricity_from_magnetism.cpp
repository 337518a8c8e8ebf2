#include "resolvers/electricity/electricity_from_magnetism.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <utility>

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/magnetism/solenoid_field.hpp"

namespace alloy::magnetism {

const ElectricityFromMagnetism::CoilFlux* ElectricityFromMagnetism::find(ObjectId id) const {
  for (const CoilFlux& c : coils_)
    if (c.id == id) return &c;
  return nullptr;
}

ElectricityFromMagnetism::Motion ElectricityFromMagnetism::motion(ObjectId id, std::uint64_t step,
                                                                  double dt, Vec3 v, Vec3 w,
                                                                  bool record) {
  const std::uint32_t slot = id.index;
  if (latest_.size() <= slot) latest_.resize(slot + 1), earlier_.resize(slot + 1);
  Seen& latest = latest_[slot];
  Seen& earlier = earlier_[slot];
  // The apply one step before this one: `latest` unless this step was seen
  // already (then `earlier`, and nothing is recorded again).
  const bool again = latest.id == id && latest.step == step;
  const Seen& before = again ? earlier : latest;
  Motion m{v, w, {}, {}, false};
  const bool usable = before.id == id && before.step + 1 == step && dt > 0;
  const bool changed = usable && (v != before.velocity || w != before.spin);
  m.changed = changed;
  // Two steps in a row in which the rigid body moved the part: its velocity
  // changes smoothly, and the difference is the acceleration of the last
  // step. A velocity that changes once in n steps (the rigid body every n-th
  // step) or was never seen gives none.
  Vec3 a{}, alpha{};
  bool rated = false;
  if (changed && before.changed) {
    a = (v - before.velocity) / dt, alpha = (w - before.spin) / dt;
    rated = is_finite(a) && is_finite(alpha);
  }
  // ... and only if it is close to the step before's: a contact's impulse,
  // a hand's push or a part resting on another changes the velocity in one
  // step by what no smooth motion does, and extrapolating that jump over
  // the coming step would induce an EMF the motion never has. Then (and in
  // the step after the jump) the EMF keeps the present velocity.
  auto close = [](Vec3 now, Vec3 last) {
    return length(now - last) <= 0.5 * std::max(length(now), length(last));
  };
  if (rated && before.rated && close(a, before.acceleration) && close(alpha, before.angular))
    m.acceleration = a, m.angular = alpha;
  if (!again && record) earlier = latest, latest = Seen{id, step, v, w, changed, rated, a, alpha};
  return m;
}

bool ElectricityFromMagnetism::save_state(StateWriter& out) const {
  // Field by field (no padding bytes): the slots that hold a record.
  std::uint64_t n = 0;
  for (std::size_t s = 0; s < latest_.size(); ++s) n += !latest_[s].id.is_null();
  // None (induction_order 1 keeps none): no state, so the worlds of order 1
  // hash as they did before the history existed.
  if (n == 0) return false;
  out.put(n);
  for (std::size_t s = 0; s < latest_.size(); ++s) {
    if (latest_[s].id.is_null()) continue;
    for (const Seen* seen : {&latest_[s], &earlier_[s]}) {
      out.put(seen->id.index), out.put(seen->id.generation), out.put(seen->step);
      out.put(seen->velocity.x), out.put(seen->velocity.y), out.put(seen->velocity.z);
      out.put(seen->spin.x), out.put(seen->spin.y), out.put(seen->spin.z);
      out.put(seen->acceleration.x), out.put(seen->acceleration.y), out.put(seen->acceleration.z);
      out.put(seen->angular.x), out.put(seen->angular.y), out.put(seen->angular.z);
      out.put(std::uint8_t(seen->changed)), out.put(std::uint8_t(seen->rated));
    }
  }
  // The predictions (session 20), field by field.
  for (const Prediction* p : {&prediction_, &earlier_prediction_}) {
    out.put(p->step), out.put(std::uint8_t(p->made));
    out.put(std::uint64_t(p->pole_position.size()));
    for (std::size_t i = 0; i < p->pole_position.size(); ++i) {
      out.put(p->pole_position[i].x), out.put(p->pole_position[i].y);
      out.put(p->pole_position[i].z), out.put(p->pole_body[i]);
    }
    out.put(std::uint64_t(p->bodies.size()));
    for (const ObjectId& id : p->bodies) out.put(id.index), out.put(id.generation);
    out.put(std::uint64_t(p->coils.size()));
    for (const Prediction::Coil& c : p->coils) {
      out.put(c.id.index), out.put(c.id.generation);
      out.put(c.centre.x), out.put(c.centre.y), out.put(c.centre.z);
      out.put(c.axis.x), out.put(c.axis.y), out.put(c.axis.z);
    }
  }
  // The parts' predicted poses (session 21, only where there is soft iron:
  // the iron is solved again there), after both predictions so that a save
  // without them restores as before.
  if (!prediction_.poses.empty() || !earlier_prediction_.poses.empty())
    for (const Prediction* p : {&prediction_, &earlier_prediction_}) {
      out.put(std::uint64_t(p->poses.size()));
      for (const MagneticForces::PartPose& pose : p->poses)
        for (const Vec3& v : {pose.centre, pose.axes[0], pose.axes[1], pose.axes[2]})
          out.put(v.x), out.put(v.y), out.put(v.z);
    }
  return true;
}

void ElectricityFromMagnetism::restore_state(StateReader& in) {
  latest_.clear(), earlier_.clear();
  first_apply_ = false;  // the history goes on: the priming apply is a repeat
  const auto n = in.get<std::uint64_t>();
  for (std::uint64_t k = 0; k < n; ++k) {
    Seen pair[2];
    for (Seen& seen : pair) {
      seen.id.index = in.get<decltype(seen.id.index)>();
      seen.id.generation = in.get<decltype(seen.id.generation)>();
      seen.step = in.get<std::uint64_t>();
      seen.velocity.x = in.get<double>(), seen.velocity.y = in.get<double>();
      seen.velocity.z = in.get<double>();
      seen.spin.x = in.get<double>(), seen.spin.y = in.get<double>(),
      seen.spin.z = in.get<double>();
      seen.acceleration.x = in.get<double>(), seen.acceleration.y = in.get<double>();
      seen.acceleration.z = in.get<double>();
      seen.angular.x = in.get<double>(), seen.angular.y = in.get<double>();
      seen.angular.z = in.get<double>();
      seen.changed = in.get<std::uint8_t>() != 0;
      seen.rated = in.get<std::uint8_t>() != 0;
    }
    const std::uint32_t slot = pair[0].id.index;
    // A slot far beyond any store is a damaged save, not a reason to
    // allocate gigabytes.
    if (slot >= (std::uint32_t(1) << 28))
      throw InputError("the saved state of stage 'electricity_from_magnetism' is damaged: slot " +
                       std::to_string(slot));
    if (latest_.size() <= slot) latest_.resize(slot + 1), earlier_.resize(slot + 1);
    latest_[slot] = pair[0], earlier_[slot] = pair[1];
  }
  prediction_ = earlier_prediction_ = Prediction{};
  auto damaged = [&](const std::string& what) {
    throw InputError("the saved state of stage 'electricity_from_magnetism' is damaged: " + what);
  };
  // `record`: the bytes of one record; a count beyond what is left is
  // damage, not a reason to allocate.
  auto count = [&](std::size_t record) {
    const auto n = in.get<std::uint64_t>();
    if (n > in.remaining() / record) damaged("a count of " + std::to_string(n));
    return std::size_t(n);
  };
  for (Prediction* p : {&prediction_, &earlier_prediction_}) {
    p->step = in.get<std::uint64_t>();
    p->made = in.get<std::uint8_t>() != 0;
    const std::size_t poles = count(28);
    p->pole_position.resize(poles), p->pole_body.resize(poles);
    for (std::size_t i = 0; i < poles; ++i) {
      Vec3& x = p->pole_position[i];
      x.x = in.get<double>(), x.y = in.get<double>(), x.z = in.get<double>();
      p->pole_body[i] = in.get<std::uint32_t>();
      if (!is_finite(x)) damaged("a predicted pole position is not a finite number");
    }
    p->bodies.resize(count(8));
    for (ObjectId& id : p->bodies) {
      id.index = in.get<decltype(id.index)>();
      id.generation = in.get<decltype(id.generation)>();
    }
    p->coils.resize(count(56));
    for (Prediction::Coil& c : p->coils) {
      c.id.index = in.get<decltype(c.id.index)>();
      c.id.generation = in.get<decltype(c.id.generation)>();
      c.centre.x = in.get<double>(), c.centre.y = in.get<double>(), c.centre.z = in.get<double>();
      c.axis.x = in.get<double>(), c.axis.y = in.get<double>(), c.axis.z = in.get<double>();
      if (!is_finite(c.centre) || !is_finite(c.axis))
        damaged("a predicted coil position is not a finite number");
    }
    for (std::uint32_t b : p->pole_body)
      if (b >= p->bodies.size()) damaged("a predicted pole names a part out of range");
  }
  if (in.remaining() == 0) return;  // no soft iron, or a save from before session 21
  for (Prediction* p : {&prediction_, &earlier_prediction_}) {
    p->poses.resize(count(96));
    for (MagneticForces::PartPose& pose : p->poses)
      for (Vec3* v : {&pose.centre, &pose.axes[0], &pose.axes[1], &pose.axes[2]}) {
        v->x = in.get<double>(), v->y = in.get<double>(), v->z = in.get<double>();
        if (!is_finite(*v)) damaged("a predicted pose is not a finite number");
      }
    if (!p->poses.empty() && p->poses.size() != p->bodies.size())
      damaged("the predicted poses do not match the parts");
  }
}

void ElectricityFromMagnetism::check_coupling(const WorldView& world, ObjectId coil,
                                              const CoilGeometry& g, double inductance) {
  // An open loop carries no current: no coupling to overshoot.
  if (!target_.closed(coil)) return;
  const PropertyStore& store = world.store();
  const auto mass = mass_.column<double>(world);
  const auto fixed = static_.column<std::uint8_t>(world);
  const auto pinned = pinned_.column<std::uint8_t>(world);
  const auto resistance = resistance_.column<double>(world);
  // A part the rigid body does not move (static, pinned, no mass) takes no
  // velocity from the coil: its inverse mass is 0.
  auto inverse_mass = [&](std::uint32_t slot) {
    if (fixed.value_or(slot, 0) != 0 || pinned.value_or(slot, 0) != 0) return 0.0;
    const double m = mass.value_or(slot, 0.0);
    return m > 0 && std::isfinite(m) ? 1 / m : 0.0;
  };
  const double dt = world.dt();
  // The coil's own resistance: the loop's is at least that (wires, the
  // battery, a lamp add to it), so the gain below is an upper bound. The
  // circuit's floor (1 uOhm) keeps an ideal coil finite.
  const double r = std::max(resistance.value_or(coil.index, 0.0), 1e-6);
  // The current one step after a step EMF of 1 V: (1 - exp(-R dt/L)) / R.
  const double x = inductance > 0 ? r * dt / inductance : INFINITY;
  const double response = x < 1e-8 ? dt / inductance : -std::expm1(-x) / r;
  const double coil_inverse = inverse_mass(coil.index);
  CoilGeometry held = g;  // the gradient with the coil held: the part moves alone
  held.velocity = {}, held.angular_velocity = {};
  const auto poles = forces_.poles();
  static constexpr Vec3 kAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const MagneticBody& b : forces_.bodies()) {
    if (b.pole_count != 2 || b.id == coil || !store.alive(b.id)) continue;
    // Relative motion: the part and the coil recoil from each other.
    const double inverse = inverse_mass(b.id.index) + coil_inverse;
    if (!(inverse > 0)) continue;
    const std::span<const Pole> pair = poles.subspan(b.first_pole, 2);
    Vec3 gradient;  // dPhi/dx of the part's translation, Wb/m
    double* component[3] = {&gradient.x, &gradient.y, &gradient.z};
    for (int k = 0; k < 3; ++k) {
      const Vec3 unit[2] = {kAxes[k], kAxes[k]};
      *component[k] = coil_flux(pair, unit, forces_.softening(), held).rate;
    }
    const double g2 = dot(gradient, gradient);
    const double gain = g2 * inverse * dt * response;
    if (!std::isfinite(gain)) continue;
    largest_gain_ = std::max(largest_gain_, gain);
    if (gain < kStrongCouplingGain) continue;
    auto seen = std::find_if(strong_.begin(), strong_.end(), [&](const StrongCoupling& s) {
      return s.coil == coil && s.part == b.id;
    });
    if (seen != strong_.end()) {
      seen->gain = std::max(seen->gain, gain);
      continue;
    }
    strong_.push_back({coil, b.id, gain});
    // The gain grows with the step (as dt with a resistive coil, dt^2 with
    // an inductive one): the step scaled by half the threshold over the
    // gain brings it below half the threshold either way.
    const double suggested = dt * 0.5 * kStrongCouplingGain / gain;
    world.emit({.type = "induction_coupling_strong",
                .a = coil,
                .b = b.id,
                .values = {{"gain", gain},
                           {"gradient", std::sqrt(g2)},
                           {"mass", 1 / inverse},
                           {"resistance", r},
                           {"inductance", inductance},
                           {"dt", dt},
                           {"dt_suggested", suggested}},
                .text = "the coil and the part are coupled too strongly for the step (the "
                        "one-step-late induction overshoots and creates energy): use a step of "
                        "at most " +
                        std::to_string(suggested) + " s"});
  }
}

void ElectricityFromMagnetism::apply(const WorldView& world) {
  coils_.clear();
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(world);
  const MagnetColumns c = MagnetColumns::bind(world, *ids_);
  const auto inductance = inductance_.column<double>(world);
  const auto velocity = velocity_.column<Vec3>(world);
  const auto spin = spin_.column<Vec3>(world);
  const PropertyStore& store = world.store();
  const double dt = world.dt();
  const std::uint64_t step = world.step();
  // induction_order 1 (the default through session 16): the parts move on
  // with their present velocity, as in sessions 14-16 (header).
  const bool second = target_.config().induction_order == 2;
  // A stage's first apply (the priming of a stage just created: at the
  // start, after a hot reload, after a restore) records no velocities. A
  // stage created mid-run is primed before the next step's advance, one
  // restored after the snapshot's step: a record from that apply would
  // differ between the two, and a restored run would not go on bit for bit.
  // (A restored history makes that apply a repeat, which records nothing.)
  const bool record = !std::exchange(first_apply_, false);

  // Every pole moves with its part: v + w x (pole - centre), the centre being
  // the midpoint of the part's two poles. Over the coming step the part
  // moves with v + a dt (the rigid body's next velocity) and ends it with
  // v + 1.5 a dt (header: the half-step lag), the poles moved on to
  // where that motion takes them.
  const auto poles = forces_.poles();
  const auto bodies = forces_.bodies();
  pole_velocity_.assign(poles.size(), Vec3{});
  pole_velocity_end_.assign(poles.size(), Vec3{});
  moved_poles_.assign(poles.begin(), poles.end());
  // A part that moves but whose velocity did not change since the last
  // apply was not stepped (the rigid body every n-th step): it stands and
  // then jumps, and a prediction of it per step would make the circuit's
  // flux follow a path the part does not take. No prediction is then made
  // or used (the step's flux change starts from where the parts are).
  bool unseen_motion = false;
  for (const MagneticBody& b : bodies) {
    if (b.pole_count != 2 || !store.alive(b.id)) continue;
    const std::uint32_t slot = b.id.index;
    const Vec3 v = velocity.value_or(slot, Vec3{}), w = spin.value_or(slot, Vec3{});
    if (!is_finite(v) || !is_finite(w)) continue;
    const Motion m = second ? motion(b.id, step, dt, v, w, record) : Motion{v, w, {}, {}, false};
    if (second && !m.changed && (v != Vec3{} || w != Vec3{})) unseen_motion = true;
    const Vec3 v_step = v + m.acceleration * dt, w_step = w + m.angular * dt;
    const Vec3 v_end = v + m.acceleration * (1.5 * dt), w_end = w + m.angular * (1.5 * dt);
    const Vec3 centre = (poles[b.first_pole].position + poles[b.first_pole + 1].position) * 0.5;
    const Vec3 centre_end = centre + v_step * dt;
    for (std::uint32_t i = b.first_pole; i < b.first_pole + 2; ++i) {
      const Vec3 arm = poles[i].position - centre;
      pole_velocity_[i] = v + cross(w, arm);
      moved_poles_[i].position = poles[i].position + (v_step + cross(w_step, arm)) * dt;
      pole_velocity_end_[i] =
          second ? v_end + cross(w_end, moved_poles_[i].position - centre_end) : pole_velocity_[i];
    }
  }

  // Soft iron (order 2): its induced moments change as the parts move, and
  // the coils pay for the work that change lets the iron's forces do
  // through the flux of the iron's poles, solved again at the predicted
  // poses (MagneticForces::emf_iron_poles; docs/magnetism.md "Induction
  // through soft iron"). The poles' fixed shares (magnets, coils' own
  // currents) take the path above; the iron's flux is added at each end of
  // the step.
  const bool iron = second && forces_.has_iron();
  std::vector<MagneticForces::PartPose> pose_now, pose_end;
  if (iron) {
    pose_now = forces_.poses();
    pose_end = pose_now;
    auto turned = [](const MagneticForces::PartPose& from, Vec3 v, Vec3 w, double t) {
      MagneticForces::PartPose to = from;
      to.centre = from.centre + v * t;
      for (int i = 0; i < 3; ++i) {
        const Vec3 a = from.axes[i] + cross(w, from.axes[i]) * t;
        to.axes[i] = a / length(a);
      }
      return to;
    };
    for (std::size_t b = 0; b < bodies.size() && b < pose_now.size(); ++b) {
      const ObjectId id = bodies[b].id;
      if (!store.alive(id)) continue;
      const Vec3 v = velocity.value_or(id.index, Vec3{}), w = spin.value_or(id.index, Vec3{});
      if (!is_finite(v) || !is_finite(w) || (v == Vec3{} && w == Vec3{})) continue;
      const Motion m = motion(id, step, dt, v, w, record);
      pose_end[b] = turned(pose_now[b], v + m.acceleration * dt, w + m.angular * dt, dt);
    }
    forces_.emf_iron_poles(pose_end, iron_end_);
    // The poles' fixed shares, now and moved on (a coil's core and free
    // iron are in the iron's poles). A body's induced share is its north
    // pole's; the south pole carries minus it (a core's share can oppose
    // its coil's own).
    const auto induced = forces_.induced_shares();
    fixed_now_.assign(poles.begin(), poles.end());
    for (std::size_t i = 0; i < poles.size(); ++i) {
      const std::uint32_t b = poles[i].body;
      const double share = b < induced.size() ? induced[b] : 0.0;
      const bool north = b < bodies.size() && i == bodies[b].first_pole;
      const double fixed = poles[i].strength - (north ? share : -share);
      fixed_now_[i].strength = fixed, moved_poles_[i].strength = fixed;
    }
  }

  // The prediction the last apply made for where the parts are now (a
  // repeated apply starts from the one before, as the first did), if the
  // parts and their poles are the ones it was made for.
  const bool repeat = prediction_.made && prediction_.step == step;
  const Prediction& from = repeat ? earlier_prediction_ : prediction_;
  bool predicted = second && !unseen_motion && from.made && from.step + 1 == step &&
                   from.pole_position.size() == poles.size() && from.bodies.size() == bodies.size();
  for (std::size_t i = 0; predicted && i < poles.size(); ++i)
    predicted = from.pole_body[i] == poles[i].body;
  for (std::size_t b = 0; predicted && b < bodies.size(); ++b)
    predicted = from.bodies[b] == bodies[b].id;
  if (predicted) {
    if (iron)
      predicted_poles_ = fixed_now_;
    else
      predicted_poles_.assign(poles.begin(), poles.end());
    for (std::size_t i = 0; i < poles.size(); ++i)
      predicted_poles_[i].position = from.pole_position[i];
  }
  // The iron's poles at the step's start: where the last apply predicted
  // the parts now, or, without a prediction, where they are.
  if (iron)
    forces_.emf_iron_poles(predicted && from.poses.size() == bodies.size() ? from.poses : pose_now,
                           iron_start_);
  Prediction made;
  const bool keep = second && !repeat && record && !unseen_motion;
  if (keep) {
    made.step = step, made.made = true;
    for (const Pole& p : moved_poles_)
      made.pole_position.push_back(p.position), made.pole_body.push_back(p.body);
    for (const MagneticBody& b : bodies) made.bodies.push_back(b.id);
    if (iron) made.poses = pose_end;
  }

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
    coil.radius =
        coil_sheet_radius(c, slot, *k, *d);  // its near field as a sheet (solenoid_field.hpp)
    coil.sheet_bodies = forces_.sheet_bodies();
    coil.velocity = velocity.value_or(slot, Vec3{});
    coil.angular_velocity = spin.value_or(slot, Vec3{});
    const ObjectId id = store.id_at(slot);
    if (const MagneticBody* own = forces_.find(id)) coil.body = std::uint32_t(own - bodies.data());
    FluxLinkage f, f_end, f_all;
    bool usable = false;
    Vec3 moved_centre = coil.centre, moved_axis = coil.axis;
    double iron_end = 0;  // the iron's flux at the step's end
    if (is_finite(coil.centre) && is_finite(coil.axis) && is_finite(coil.velocity) &&
        is_finite(coil.angular_velocity) && std::isfinite(coil.linkage)) {
      f = f_all = coil_flux(poles, pole_velocity_, forces_.softening(), coil);
      if (iron) f = coil_flux(fixed_now_, pole_velocity_, forces_.softening(), coil);
      // The same at the end of the coming step, every part moved on along
      // its present motion: electricity ramps the EMF over its substeps
      // from the last step's end value to this one, so the EMF it
      // integrates is the flux's change over the step, to second order,
      // while the parts' displacement over that step is the one the
      // force's work is booked along (docs/magnetism.md "The coupling's
      // timing").
      const Motion m = second ? motion(id, step, dt, coil.velocity, coil.angular_velocity, record)
                              : Motion{coil.velocity, coil.angular_velocity, {}, {}, false};
      CoilGeometry moved = coil;
      moved.centre = coil.centre + (coil.velocity + m.acceleration * dt) * dt;
      moved.axis = coil.axis + cross(coil.angular_velocity + m.angular * dt, coil.axis) * dt;
      moved.axis = moved.axis / length(moved.axis);
      moved.velocity = coil.velocity + m.acceleration * (1.5 * dt);
      moved.angular_velocity = coil.angular_velocity + m.angular * (1.5 * dt);
      f_end = coil_flux(moved_poles_, pole_velocity_end_, forces_.softening(), moved);
      usable = true, moved_centre = moved.centre, moved_axis = moved.axis;
      if (iron) {
        iron_end = coil_flux(iron_end_, {}, forces_.softening(), moved).flux;
        if (!std::isfinite(iron_end)) iron_end = 0;
      }
      if (coil.linkage != 0) {
        geometry.push_back(coil), geometry_id.push_back(id);
        check_coupling(world, id, coil, inductance[slot]);
      }
    }
    if (!std::isfinite(f.flux) || !std::isfinite(f.rate)) f = {};
    if (!std::isfinite(f_all.flux) || !std::isfinite(f_all.rate)) f_all = {};
    if (!std::isfinite(f_end.rate)) f_end = f;
    coils_.push_back({id, f_all});
    // Faraday and Lenz: the EMF opposes the change of the flux that links it.
    if (!second || !usable || !std::isfinite(f_end.flux) || !std::isfinite(f.flux)) {
      target_.set_induced_emf(id, -f_end.rate);
      continue;
    }
    // Order 2: over the coming step the flux changes from where the last
    // apply predicted the parts would be now to where they are predicted
    // at the step's end, at the pole strengths of now. Its mean rate is the
    // EMF's mean over the step; summed over the steps the circuit
    // integrates the flux along the predicted path with no gap, and each
    // step's miss of the real motion is taken up in the next (a difference
    // of two predictions' errors, not the error itself).
    double start = f.flux;
    CoilGeometry then = coil;  // the coil at the step's start (as the last apply predicted it)
    if (predicted) {
      const auto it = std::find_if(from.coils.begin(), from.coils.end(),
                                   [&](const Prediction::Coil& c) { return c.id == id; });
      if (it != from.coils.end()) {
        then.centre = it->centre, then.axis = it->axis;
        const double phi =
            coil_flux(predicted_poles_, pole_velocity_, forces_.softening(), then).flux;
        if (std::isfinite(phi)) start = phi;
      }
    }
    // The flux the step's forces see is the integral of their gradient
    // along the motion, the trapezoid of the held-strength rates. Where the
    // flux jumps instead (a magnet's string crossing an air coil's winding,
    // where the thin sheet makes it step by mu0 n q L and the force has no
    // matching term), the chord would drive the circuit with a flux change
    // no force paid for (adv20: 12 J made in 1.2 s). Then this step takes the
    // ramp alone and the next starts from where the parts are.
    const double chord = f_end.flux - start, seen = 0.5 * dt * (f.rate + f_end.rate);
    // From where the parts are now, so that a miss of the last prediction
    // (a contact's impulse, a strong coupling's turn) is not taken for one.
    const double miss = std::abs(f_end.flux - f.flux - seen);
    // The iron's flux from the step's start to its end (its poles are
    // never a sheet's, so it has no jump), and its mean rate, which the
    // ramp's end value takes: its offset makes the mean right, and the
    // ramp's slope only shapes the EMF within the step (a forward
    // difference of the iron's flux at the end changed the books by 2e-5 of
    // the energy moved and cost two more solves).
    double iron_chord = 0;
    if (iron) {
      const double iron_start = coil_flux(iron_start_, {}, forces_.softening(), then).flux;
      if (std::isfinite(iron_start)) iron_chord = iron_end - iron_start;
    }
    const double iron_rate = iron_chord / dt;
    if (miss > 0.5 * std::max(std::abs(f_end.flux - f.flux), std::abs(seen)) &&
        miss > kFluxJump * (std::abs(f.flux) + std::abs(f_end.flux)) && miss > kFluxJumpFloor) {
      ++flux_jumps_;
      target_.set_induced_emf(id, -(f_end.rate + iron_rate));
      continue;
    }
    target_.set_induced_emf(id, -(f_end.rate + iron_rate), -(chord + iron_chord) / dt);
    if (keep) made.coils.push_back({id, moved_centre, moved_axis});
  }
  if (keep) earlier_prediction_ = std::move(prediction_), prediction_ = std::move(made);

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
                         prop::kLength, "mass", "static", "pinned", "resistance"},
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
