#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

void RigidBodyResolver::step_world(ResolverAccess& access, double dt) {
  ensure_ode();
  Impl& m = *impl_;
  m.resolve_ids(access);
  if (m.dirty || m.defining_changed()) build(access);
  if (m.dirty) return;  // the build failed inside ODE (engine_failed): nothing to step
  m.apply_edits(access);
  screen_loads(access, dt);
  // Swapped in while a ledger keeps the books: from this first advance on.
  books_on_ = books_on_ || world_.energy_books_kept();

  const int n = config_.substeps;
  const double h = dt / n;
  if (h != m.damping_dt) {
    m.damped.clear();
    for (const auto& b : m.bodies)
      if (!b.kinematic && (b.linear_damping > 0 || b.angular_damping > 0))
        m.damped.push_back(
            {b.id, damping_factor(b.linear_damping, h), damping_factor(b.angular_damping, h)});
    m.damping_dt = h;
  }
  if (config_.auto_disable) wake_on_load_change();
  if (!displacements_.empty()) apply_displacements();
  if (!held_.empty() || held_bodies_ > 0) apply_holds();

  // Impulses only for their readers (demand_impulses): the feedback below is
  // work the solve itself does not need.
  const bool feedback = *impulse_demand_ > 0;
  // Contact points as queued; their depth is carried forward between substeps.
  m.depth.resize(contact_points_.size());
  for (std::size_t k = 0; k < contact_points_.size(); ++k) m.depth[k] = contact_points_[k].depth;
  if (feedback) {
    m.feedback.resize(contact_points_.size());  // joints keep pointers into it: no growth below
    m.feedback_force.assign(contact_points_.size(), Vec3{});
  }
  m.records.clear();
  pass_impulse_.clear();
  pass_normal_.clear();

  const bool found = n > 1 && config_.substep_contacts == RigidBodyConfig::SubstepContacts::Found;
  if (found) {
    window_contacts_ = contacts_;
    window_points_ = contact_points_;
    if (feedback) {
      pair_force_.assign(contacts_.size(), Vec3{});
      pair_normal_.assign(contacts_.size(), 0.0);
    }
    // New pairs are still found once a window, a window's travel deep: push
    // such overlaps out at the window's pace, as one step of dt would, and not
    // n times faster (which throws a sliding contact off: measured on the
    // motor with 8 substeps, 64 contact events where the rotor makes 43).
    dWorldSetERP(m.world, config_.erp / n);
  }

  for (int sub = 0; sub < n; ++sub) {
    if (found && sub > 0) {
      find_substep_contacts(access);
      m.depth.resize(contact_points_.size());
      for (std::size_t k = 0; k < contact_points_.size(); ++k)
        m.depth[k] = contact_points_[k].depth;
      if (feedback)
        m.feedback.resize(std::max(m.feedback.size(), contact_points_.size()));  // no joints left
      m.records.clear();
    }
    const double ke0 = books_on_ ? kinetic_energy() : 0.0;
    m.damp();
    const double ke1 = books_on_ ? kinetic_energy() : 0.0;
    apply_loads();
    if (!rated_loads_.empty()) apply_rated_loads(sub * h);
    // Where the loads act before restitution_pass moves a colliding body to
    // its time of impact: the move is part of the displacement.
    if (books_on_) book_loads_before(sub * h);
    // Records serve the impulses and, with kept substeps, carry_depths.
    restitution_pass(h, feedback);
    const double ke2 = books_on_ ? kinetic_energy() : 0.0;
    if (books_on_) {
      books_.drag += ke0 - ke1, books_.restitution += ke1 - ke2;
      for (std::size_t i = 0; i < m.bodies.size(); ++i)  // the velocities the step starts from
        if (!m.bodies[i].kinematic) {
          books_.v0[i] = to_vec3(dBodyGetLinearVel(m.bodies[i].id));
          books_.w0[i] = to_vec3(dBodyGetAngularVel(m.bodies[i].id));
        }
      // A body restitution_pass moved to its time of impact moved with no
      // velocity: the loads' work along that move is booked with the
      // integrator's share (so a falling ball's books close at the bounce).
      for (EnergyBooks::Applied& a : books_.applied) {
        dVector3 at;
        dBodyGetRelPointPos(m.bodies[a.body].id, a.local.x, a.local.y, a.local.z, at);
        const double moved = dot(a.force, to_vec3(at) - a.at);
        books_.book_move(a, moved);
      }
    }
    add_contact_joints(h, (sub == 0 || found) && (feedback || (n > 1 && !found)), feedback);
    // QuickStep shuffles constraints with ODE's global random generator;
    // seeding it from the step number makes every world's step a function of
    // its own state (two worlds, or two runs, stay bit-identical).
    dRandSetSeed(static_cast<unsigned long>(
        (access.step() * std::uint64_t(n) + std::uint64_t(sub)) * 2654435761u + 1));
    m.begin_rotation();
    m.projection.begin_step();
    if (config_.solver == RigidBodyConfig::Solver::Quick)
      dWorldQuickStep(m.world, h);
    else
      dWorldStep(m.world, h);
    m.conserve_rotation(h);
    m.fix_planar();
    m.projection.project(h, dWorldGetERP(m.world));
    check_motion(access);
    if (books_on_) book_loads_after(h, ke2);
    if (feedback && found) {
      // Points differ from substep to substep: sum each pair's force instead.
      for (const auto& r : m.records) {
        const ContactCommand& c = contacts_[r.command];
        const double sign = r.swapped ? -1.0 : 1.0;
        for (std::uint32_t i = 0; i < r.count; ++i) {
          const Vec3 f1 = to_vec3(m.feedback[r.first_feedback + i].f1);
          pair_force_[r.command] += sign * f1;
          pair_normal_[r.command] += sign * dot(f1, contact_points_[c.first + i].normal);
        }
      }
    } else if (feedback) {
      for (std::size_t k = 0; k < m.records.size(); ++k) {
        const auto& r = m.records[k];
        for (std::uint32_t i = 0; i < r.count; ++i)
          m.feedback_force[r.first_feedback + i] += to_vec3(m.feedback[r.first_feedback + i].f1);
      }
    }
    dJointGroupEmpty(m.contact_group);
    if (sub + 1 < n && !found) carry_depths(h);
  }
  if (found) {
    dWorldSetERP(m.world, config_.erp);
    contacts_.swap(window_contacts_);
    contact_points_.swap(window_points_);
  }

  // Publish the impulse each pair received over the window.
  const bool had = !impulses_.empty() || impulses_computed_ != feedback;
  impulses_computed_ = feedback;
  impulses_.clear();
  if (feedback && found) {
    // Every pair queued for the window that touched at some substep.
    for (std::size_t ci = 0; ci < contacts_.size(); ++ci) {
      const ContactCommand& c = contacts_[ci];
      const Vec3 pass = ci < pass_impulse_.size() ? pass_impulse_[ci] : Vec3{};
      const double pass_n = ci < pass_normal_.size() ? pass_normal_[ci] : 0.0;
      if (pair_force_[ci] == Vec3{} && pair_normal_[ci] == 0 && pass_n == 0) continue;
      impulses_.push_back(
          {c.a, c.b, pair_force_[ci] * h + pass, std::max(0.0, pair_normal_[ci] * h + pass_n)});
    }
  }
  for (const auto& r : m.records) {
    if (found || !feedback) break;
    const ContactCommand& c = contacts_[r.command];
    Vec3 f{};
    double fn = 0;
    for (std::uint32_t k = 0; k < r.count; ++k) {
      const Vec3 f1 = m.feedback_force[r.first_feedback + k];
      f += f1;
      fn += dot(f1, contact_points_[c.first + k].normal) * (r.swapped ? -1.0 : 1.0);
    }
    // Each substep's force acted for h: the sum times h is the window's
    // impulse; the collision impulses of restitution_pass come on top.
    const Vec3 pass = r.command < pass_impulse_.size() ? pass_impulse_[r.command] : Vec3{};
    const double pass_n = r.command < pass_normal_.size() ? pass_normal_[r.command] : 0.0;
    impulses_.push_back(
        {c.a, c.b, (r.swapped ? -1.0 : 1.0) * f * h + pass, std::max(0.0, fn * h + pass_n)});
  }
  if (!std::is_sorted(
          impulses_.begin(), impulses_.end(),
          [](const PairImpulse& x, const PairImpulse& y) { return pair_less(x.a, x.b, y.a, y.b); }))
    std::sort(impulses_.begin(), impulses_.end(), [](const PairImpulse& x, const PairImpulse& y) {
      return pair_less(x.a, x.b, y.a, y.b);
    });
  if (had || !impulses_.empty()) ++state_version_;

  // 5. Write the new state to the properties.
  m.write_poses(access, false);
  m.write_hinges(access);
  m.snapshot_versions();
  forces_.clear();
  rated_loads_.clear();
  load_sources_.clear();
  rated_sources_.clear();
  contacts_.clear();
  contact_points_.clear();
}

}  // namespace alloy::rigid
