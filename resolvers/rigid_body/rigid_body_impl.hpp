// Private to resolvers/rigid_body/: the ODE side of RigidBodyResolver (its
// Impl) and the helpers that more than one of its source files use. The
// resolver's sources are split along its jobs:
//   rigid_body.cpp           the resolver: construction, build, advance
//   rigid_body_settings.cpp  RigidBodyConfig: the plugin's settings
//   rigid_body_world.cpp     building the ODE world from the properties, and
//                            writing poses back
//   rigid_body_loads.cpp     the command queue: loads, displacements, contacts
//   rigid_body_contacts.cpp  contact joints, restitution, substep contacts
//   rigid_body_step.cpp      the step (step_world)
//   rigid_body_state.cpp     saved state (save_state, restore_state)
//   rigid_body_bounds.cpp    what the rigid body refuses
//   rigid_body_energy.cpp    the energy books
// Nothing outside this folder includes it (it includes ODE).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/joint_projection.hpp"
#include "resolvers/rigid_body/ode_support.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"

namespace alloy::rigid::detail {

/// The factor a step of h multiplies a velocity by for damping dv/dt = -c v,
/// before the step's kick and drift. ODE steps semi-implicitly: the drift
/// uses the velocity after the kick, v' = f v + h a. Under a steady force the
/// speed settles where v' = h a / (1 - f), so f = 1 - c h makes a
/// drag-limited speed exact (a motor's bearing, a terminal velocity), in the
/// position as in the velocity. ODE's own damping, e^(-c h) after the drift,
/// runs such a speed c h / 2 fast (+1.2 % for the motor at 1/480 s). Where
/// the damping's time constant is shorter than two steps, 1 - c h would
/// reach 0 and turn the velocity round; there the factor goes on from the
/// same value at c h = 1/2 and falls towards 0 without crossing it.
inline double damping_factor(double c, double h) {
  const double x = c * h;
  return x <= 0.5 ? 1 - x : 0.25 / x;
}

}  // namespace alloy::rigid::detail

namespace alloy::rigid {

using detail::damping_factor;

// --- the ODE side ----------------------------------------------------------------------

struct RigidBodyResolver::Impl {
  /// An object simulated as (part of) an ODE body. Parts glued by fixed joints
  /// share one body: ODE then solves one rigid body instead of a stiff chain of
  /// fixed joints that sags under load, costs solver rows and drifts apart with
  /// QuickStep. The assembly's mass and inertia are the sum of its parts'.
  struct Part {
    ObjectId id;
    std::uint32_t body = 0;
    Vec3 offset;           ///< the part's centre of mass in the body frame
    Quat rot;              ///< the part's orientation relative to the body frame
    bool identity = true;  ///< a body of one part: the part's frame is the body's
    // Values last written, to tell our own writes from edits made between steps.
    Vec3 pos, vel, angvel;
    Quat q;
  };
  struct Body {
    dBodyID id = nullptr;
    std::uint32_t first_part = 0, part_count = 0;
    bool kinematic = false;  ///< pinned, or glued to the play area or a static part
    bool planar = false;
    bool moved = false;    ///< a kinematic body teleported by an edit: write its parts
    bool jointed = false;  ///< held by a hinge: its collisions are ODE's (restitution_pass)
    double linear_damping = 0, angular_damping = 0;  ///< 1/s
    double mass = 0;
    // auto_disable: the load queued this step, and the load it had when it
    // last ran; a sleeping body wakes when the two differ.
    Vec3 load_force, load_torque, awake_force, awake_torque;
    bool asleep = false;  ///< disabled when this advance began
    bool held = false;    ///< disabled by apply_holds (a part buried in a heap)
  };
  struct Hinge {
    ObjectId id;
    dJointID joint = nullptr;
    bool to_world =
        false;  ///< body 2 is the play area: the anchor side to report is ODE's anchor 2
  };
  /// A contact pair turned into joints in this advance.
  struct PairRecord {
    std::uint32_t command;
    std::uint32_t first_feedback, count;
    bool swapped;  ///< b's body was attached first: ODE's force 1 acts on b
  };

  struct Ids {
    PropertyId position, orientation, velocity, angular_velocity, mass, density, shape, size,
        radius, length, static_, pinned, planar, linear_damping, angular_damping, joint, body_a,
        body_b, anchor, axis, joint_friction, limit_low, limit_high, anchor_a, anchor_b;
  };

  explicit Impl(const RigidBodyConfig& c) : config(c) { ensure_ode(); }
  ~Impl() { destroy_world(); }

  void create_world() {
    world = dWorldCreate();
    // Gravity is not ODE's business: the gravity resolvers compute it per body
    // and rigid_body_from_gravity queues it as a force (paper 3, section 4.1.3).
    dWorldSetGravity(world, 0, 0, 0);
    dWorldSetERP(world, config.erp);
    dWorldSetCFM(world, config.cfm);
    dWorldSetQuickStepNumIterations(world, config.iterations);
    dWorldSetQuickStepW(world, config.sor);
    dWorldSetContactSurfaceLayer(world, config.surface_layer);
    dWorldSetContactMaxCorrectingVel(world, config.max_correcting_velocity);
    dWorldSetAutoDisableFlag(world, config.auto_disable ? 1 : 0);
    if (config.auto_disable) {
      dWorldSetAutoDisableLinearThreshold(world, config.auto_disable_linear);
      dWorldSetAutoDisableAngularThreshold(world, config.auto_disable_angular);
      dWorldSetAutoDisableSteps(world, config.auto_disable_steps);
      dWorldSetAutoDisableTime(world, 0);
      // Average the speeds over the window: one slow step in a bounce is not rest.
      dWorldSetAutoDisableAverageSamplesCount(world,
                                              unsigned(std::min(config.auto_disable_steps, 10)));
    }
    contact_group = dJointGroupCreate(0);
  }
  void destroy_geoms() {
    for (dGeomID g : geom_of_slot)
      if (g) dGeomDestroy(g);
    geom_of_slot.clear();
  }
  void destroy_world() {
    destroy_geoms();
    if (contact_group) dJointGroupDestroy(contact_group);
    if (world) dWorldDestroy(world);  // destroys every body and joint in it
    contact_group = nullptr;
    world = nullptr;
    bodies.clear();
    parts.clear();
    gyros.clear();
    hinges.clear();
    projection.clear();
    setup_poses.clear();
    hinge_setup.clear();
    projection_calls.clear();
    std::fill(part_of_slot.begin(), part_of_slot.end(), -1);
  }

  void resolve_ids(const WorldView& v) {
    if (have_ids) return;
    id = {v.property("position"),
          v.property("orientation"),
          v.property("velocity"),
          v.property("angular_velocity"),
          v.property("mass"),
          v.property("density"),
          v.property("shape"),
          v.property("size"),
          v.property("radius"),
          v.property("length"),
          v.property("static"),
          v.property("pinned"),
          v.property("planar"),
          v.property("linear_damping"),
          v.property("angular_damping"),
          v.property("joint"),
          v.property("body_a"),
          v.property("body_b"),
          v.property("anchor"),
          v.property("axis"),
          v.property("joint_friction"),
          v.property("limit_low"),
          v.property("limit_high"),
          v.property("anchor_a"),
          v.property("anchor_b")};
    // Columns whose edit means "the bodies are different now": rebuild.
    for (PropertyId p :
         {id.mass, id.density, id.shape, id.size, id.radius, id.length, id.static_, id.pinned,
          id.planar, id.linear_damping, id.angular_damping, id.joint, id.body_a, id.body_b,
          id.anchor, id.axis, id.joint_friction, id.limit_low, id.limit_high})
      defining.push_back(&v.store().column(p));
    pose_columns = {&v.store().column(id.position), &v.store().column(id.orientation),
                    &v.store().column(id.velocity), &v.store().column(id.angular_velocity)};
    have_ids = true;
  }

  bool defining_changed() const {
    for (std::size_t i = 0; i < defining.size(); ++i)
      if (defining[i]->version() != defining_seen[i]) return true;
    return false;
  }
  void snapshot_versions() {
    defining_seen.resize(defining.size());
    for (std::size_t i = 0; i < defining.size(); ++i) defining_seen[i] = defining[i]->version();
    for (std::size_t i = 0; i < 4; ++i) pose_seen[i] = pose_columns[i]->version();
  }

  void rebuild(ResolverAccess& access);
  void apply_edits(ResolverAccess& access);
  void write_poses(ResolverAccess& access, bool all);
  void write_hinges(ResolverAccess& access);
  void fix_planar();
  void begin_rotation();
  void conserve_rotation(double h);

  /// Whether restitution_pass leaves a pair's collisions to ODE's bounce: a
  /// body held by a hinge, whose response to an impulse at the point the
  /// pass's free-body masses do not know (it turns about its pivot).
  bool pass_skips(std::int32_t ba, std::int32_t bb) const {
    return (ba >= 0 && bodies[ba].jointed) || (bb >= 0 && bodies[bb].jointed);
  }

  /// Whether body `b` (an index into bodies, -1: a static part) does not move:
  /// static, or a dynamic body ODE has put to sleep.
  bool sleeping_or_static(std::int32_t b) const {
    return b < 0 || (!bodies[b].kinematic && !dBodyIsEnabled(bodies[b].id));
  }

  /// The body index of the part in `slot` if it is the live object `id`, else -1.
  std::int32_t body_of(ObjectId obj) const {
    if (obj.index >= part_of_slot.size()) return -1;
    const std::int32_t p = part_of_slot[obj.index];
    if (p < 0 || parts[p].id != obj) return -1;
    return std::int32_t(parts[p].body);
  }

  /// The part in `slot` if it is a body's part (and, generation != 0, still
  /// the object the command was queued for), else null.
  const Part* part_for(std::uint32_t slot, std::uint32_t generation) const {
    if (slot >= part_of_slot.size()) return nullptr;
    const std::int32_t pi = part_of_slot[slot];
    if (pi < 0) return nullptr;  // not a body (static, or not a rigid part)
    const Part& p = parts[pi];
    if (generation != 0 && generation != p.id.generation) return nullptr;  // another object now
    return &p;
  }

  RigidBodyConfig config;
  dWorldID world = nullptr;
  dJointGroupID contact_group = nullptr;
  std::vector<Body> bodies;
  std::vector<Part> parts;                 // grouped by body, each body's parts in slot order
  std::vector<std::int32_t> part_of_slot;  // slot -> index into parts, or -1
  std::vector<Hinge> hinges;
  /// The hinges' position projection (joint_projection.hpp); empty when the
  /// setting joint_projection is off.
  JointProjection projection;
  std::vector<dJointFeedback> feedback;
  std::vector<Vec3> feedback_force;  ///< per contact point: force 1 summed over the substeps
  std::vector<double> depth;         ///< per queued contact point: depth at the current substep
  std::vector<PairRecord> records;
  // substep_contacts = found: a geom per part that was in a queued pair (in
  // no space), by slot; made when first needed, destroyed with the world.
  std::vector<dGeomID> geom_of_slot;
  std::vector<dContactGeom> collide_buffer;
  /// The bodies with damping and their velocity factors for a step of
  /// damping_dt (damping_factor), applied before each ODE step.
  struct Damped {
    dBodyID id;
    double linear, angular;
  };
  std::vector<Damped> damped;
  double damping_dt = 0;
  std::vector<std::int32_t> pass_slot;  ///< restitution_pass: body -> its work entry, or -1
  /// Bodies whose inertia is not the same about every axis (and that are
  /// free to turn in 3D): their gyroscopic term is ours (conserve_rotation),
  /// not ODE's. The body-frame inverse inertia, and the orientation at the
  /// start of the present step.
  struct Gyro {
    std::uint32_t body;
    double inv_inertia[9];
    Quat q0;
  };
  std::vector<Gyro> gyros;
  bool dirty = true;

  // What a restore needs to remake the hinges exactly as the last build made
  // them (save_state): ODE's hinge and the projection measure the anchor and
  // axis in each body's frame as the bodies stood at that build, and the
  // bodies have moved since. Kept from build to build; a few per hinge.
  // These are saved as raw bytes (put_vector): no padding, every byte a field.
  struct SetupPose {
    std::uint64_t body;
    dReal pos[3], q[4];
  };
  struct HingeSetup {
    Vec3 pivot, axis;
    double angle;
    Vec3 pivot1;  // where body 1 is held (pivot: where body 2 or the play area holds it)
  };
  /// A call made to `projection` while building: add_body (body >= 0) or
  /// add_hinge (body < 0), in order.
  struct ProjectionCall {
    std::int64_t body, planar, fixed, b1, b2;
    Vec3 pivot, axis;
    Vec3 pivot2;  // add_hinge's anchor2
  };
  std::vector<SetupPose> setup_poses;   // of every body a hinge holds
  std::vector<HingeSetup> hinge_setup;  // parallel to hinges
  std::vector<ProjectionCall> projection_calls;
  /// A body of one part in its own frame: its state is its part's
  /// properties, bit for bit (write_poses), and a restore reads it there.
  bool plain(const Body& b) const { return b.part_count == 1 && parts[b.first_part].identity; }
  /// Sets a body's pose to these exact bits: ODE's setter normalises the
  /// quaternion, which moves the last bits of one the integrator left
  /// unnormalised by rounding; the rotation matrix is recomputed from the
  /// exact quaternion, as ODE's own step does (dQtoR after its dNormalize4).
  /// Makes hinge `j` hold body 1 at the world point `p1` and body 2 (or the
  /// play area) at `p2`, at the bodies' present poses. ODE's hinge takes one
  /// world anchor for both bodies, so body 1 is moved by p2 - p1 for the call
  /// and put back exactly: its local anchor is then p1's.
  static void set_hinge_anchors(dJointID j, dBodyID b1, Vec3 p1, Vec3 p2) {
    if (p1 == p2) {
      dJointSetHingeAnchor(j, p2.x, p2.y, p2.z);
      return;
    }
    const dReal* at = dBodyGetPosition(b1);
    const dReal x[3] = {at[0], at[1], at[2]};
    dBodySetPosition(b1, x[0] + (p2.x - p1.x), x[1] + (p2.y - p1.y), x[2] + (p2.z - p1.z));
    dJointSetHingeAnchor(j, p2.x, p2.y, p2.z);
    dBodySetPosition(b1, x[0], x[1], x[2]);
  }
  static void set_exact_pose(dBodyID id, const dReal* pos, const dReal* q) {
    dBodySetPosition(id, pos[0], pos[1], pos[2]);
    dBodySetQuaternion(id, q);
    dReal* bq = const_cast<dReal*>(dBodyGetQuaternion(id));  // the body's own storage
    for (int i = 0; i < 4; ++i) bq[i] = q[i];
    dQtoR(bq, const_cast<dReal*>(dBodyGetRotation(id)));
  }

  void damp() const {
    for (const Damped& d : damped) {
      if (!dBodyIsEnabled(d.id)) continue;  // asleep: nothing moves, nothing to wake
      const dReal* v = dBodyGetLinearVel(d.id);
      const dReal* w = dBodyGetAngularVel(d.id);
      dBodySetLinearVel(d.id, v[0] * d.linear, v[1] * d.linear, v[2] * d.linear);
      dBodySetAngularVel(d.id, w[0] * d.angular, w[1] * d.angular, w[2] * d.angular);
    }
  }

  // Bounds (screen_loads, check_motion): per body, 1 / mass and 1 / its
  // smallest principal moment of inertia; per slot, parts refused at the
  // last rebuild (a joint to one holds nothing); the world, for its frozen.
  std::vector<double> inv_mass, inv_inertia;
  std::vector<std::uint8_t> refused;
  const World* host = nullptr;
  void measure_bodies();
  bool refuse_part(ResolverAccess& access, std::uint32_t slot, double mass, const dMass& local);

  bool have_ids = false;
  Ids id{};
  std::vector<const ColumnBase*> defining;
  std::vector<std::uint64_t> defining_seen;
  std::array<const ColumnBase*, 4> pose_columns{};
  std::array<std::uint64_t, 4> pose_seen{};
};

}  // namespace alloy::rigid
