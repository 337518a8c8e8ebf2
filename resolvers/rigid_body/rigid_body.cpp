#include "resolvers/rigid_body/rigid_body.hpp"

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

/// How fast body 1 moves into body 2 (null: the play area) at `point`,
/// along `normal` (ODE's contact normal, pointing out of body 2 into body 1), m/s.
double approach_speed(dBodyID b1, dBodyID b2, Vec3 point, Vec3 normal) {
  dVector3 v1, v2 = {0, 0, 0};
  dBodyGetPointVel(b1, point.x, point.y, point.z, v1);
  if (b2) dBodyGetPointVel(b2, point.x, point.y, point.z, v2);
  return -(normal.x * (v1[0] - v2[0]) + normal.y * (v1[1] - v2[1]) + normal.z * (v1[2] - v2[2]));
}

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
double damping_factor(double c, double h) {
  const double x = c * h;
  return x <= 0.5 ? 1 - x : 0.25 / x;
}

}  // namespace

// --- settings -------------------------------------------------------------------------

const std::vector<std::string>& RigidBodyConfig::keys() {
  static const std::vector<std::string> k = {"solver",
                                             "iterations",
                                             "sor",
                                             "erp",
                                             "cfm",
                                             "max_contacts",
                                             "surface_layer",
                                             "max_correcting_velocity",
                                             "substeps",
                                             "substep_contacts",
                                             "auto_disable",
                                             "auto_disable_linear",
                                             "auto_disable_angular",
                                             "auto_disable_steps",
                                             "ccd",
                                             "contact_stiffness",
                                             "contact_damping",
                                             "max_collision_impulses",
                                             "joint_projection"};
  return k;
}

RigidBodyConfig RigidBodyConfig::from(const PluginSettings& s) {
  s.check_known("rigid_body", keys());
  RigidBodyConfig c;
  const std::string solver = s.string("solver", "quick");
  if (solver == "quick")
    c.solver = Solver::Quick;
  else if (solver == "step")
    c.solver = Solver::Step;
  else
    throw InputError(s.where,
                     "rigid_body: solver must be \"quick\" or \"step\", got \"" + solver + "\"");
  auto bad = [&](const char* what) {
    throw InputError(s.where, std::string("rigid_body: ") + what);
  };
  c.iterations = int(s.integer("iterations", c.iterations));
  if (c.iterations < 1 || c.iterations > 10000) bad("iterations must be between 1 and 10000");
  c.sor = s.number("sor", c.sor);
  if (!(c.sor > 0 && c.sor < 2)) bad("sor must be in (0, 2)");
  c.erp = s.number("erp", c.erp);
  if (!(c.erp >= 0 && c.erp <= 1)) bad("erp must be in [0, 1]");
  c.cfm = s.number("cfm", c.cfm);
  if (!(c.cfm >= 0 && c.cfm < 1)) bad("cfm must be in [0, 1)");
  c.contact_stiffness = s.number("contact_stiffness", c.contact_stiffness);
  if (!(c.contact_stiffness >= 0 && c.contact_stiffness < 1e300))
    bad("contact_stiffness must be >= 0 N/m (0: rigid)");
  c.contact_damping = s.number("contact_damping", c.contact_damping);
  if (!(c.contact_damping >= 0 && c.contact_damping < 1e300))
    bad("contact_damping must be >= 0 N*s/m");
  c.max_collision_impulses = int(s.integer("max_collision_impulses", c.max_collision_impulses));
  if (c.max_collision_impulses < 0 || c.max_collision_impulses > 1000000)
    bad("max_collision_impulses must be between 0 and 1000000");
  c.max_contacts = int(s.integer("max_contacts", c.max_contacts));
  if (c.max_contacts < 1 || c.max_contacts > 64) bad("max_contacts must be between 1 and 64");
  c.surface_layer = s.number("surface_layer", c.surface_layer);
  if (!(c.surface_layer >= 0 && c.surface_layer < 1)) bad("surface_layer must be in [0, 1) m");
  c.max_correcting_velocity = s.number("max_correcting_velocity", c.max_correcting_velocity);
  if (!(c.max_correcting_velocity > 0)) bad("max_correcting_velocity must be > 0");
  c.substeps = int(s.integer("substeps", c.substeps));
  if (c.substeps < 1 || c.substeps > 1000) bad("substeps must be between 1 and 1000");
  const std::string contacts = s.string("substep_contacts", "kept");
  if (contacts == "kept")
    c.substep_contacts = RigidBodyConfig::SubstepContacts::Kept;
  else if (contacts == "found")
    c.substep_contacts = RigidBodyConfig::SubstepContacts::Found;
  else
    bad("substep_contacts must be \"kept\" or \"found\"");
  c.auto_disable = s.boolean("auto_disable", c.auto_disable);
  c.joint_projection = s.boolean("joint_projection", c.joint_projection);
  c.ccd = s.boolean("ccd", c.ccd);
  c.auto_disable_linear = s.number("auto_disable_linear", c.auto_disable_linear);
  if (!(c.auto_disable_linear >= 0)) bad("auto_disable_linear must be >= 0 m/s");
  c.auto_disable_angular = s.number("auto_disable_angular", c.auto_disable_angular);
  if (!(c.auto_disable_angular >= 0)) bad("auto_disable_angular must be >= 0 rad/s");
  c.auto_disable_steps = int(s.integer("auto_disable_steps", c.auto_disable_steps));
  if (c.auto_disable_steps < 1 || c.auto_disable_steps > 100000)
    bad("auto_disable_steps must be between 1 and 100000");
  return c;
}

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
        body_b, anchor, axis, joint_friction, limit_low, limit_high;
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
          v.property("limit_high")};
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
  };
  /// A call made to `projection` while building: add_body (body >= 0) or
  /// add_hinge (body < 0), in order.
  struct ProjectionCall {
    std::int64_t body, planar, fixed, b1, b2;
    Vec3 pivot, axis;
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
  const auto axis = access.column<Vec3>(id.axis);
  const auto joint_friction = access.column<double>(id.joint_friction);
  const auto limit_low = access.column<double>(id.limit_low);
  const auto limit_high = access.column<double>(id.limit_high);
  auto mass_out = access.writer<double>(id.mass);
  auto anchor_out = access.writer<Vec3>(id.anchor);
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
  constexpr std::int32_t kWorld = -1, kGone = -2;
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
      throw InputError(where, std::string(name) + " is '" + store.describe(o) +
                                  "', which is neither a rigid body (mass or density) nor static");
    };
    if (!body_a.has(s)) throw InputError(where, "a joint needs body_a");
    std::int32_t a = ref(body_a, "body_a"), b = ref(body_b, "body_b");
    if (a == kGone || b == kGone || (a == kWorld && b == kWorld)) continue;
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
      // An assembly moves as its first part does.
      const Vec3 w = angular_velocity.value_or(root.slot, {});
      const Vec3 v = velocity.value_or(root.slot, {}) + cross(w, com - root.x);
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
    const Vec3 pivot = anchor.has(h.slot) ? anchor[h.slot] : cand[h.a >= 0 ? h.a : h.b].x;
    Vec3 ax = unit(axis.value_or(h.slot, {0, 0, 1}));  // any finite size: scaled first
    if (ax == Vec3{}) throw InputError(where, "a hinge axis must not be zero");
    const Quat qa = h.a >= 0 ? cand[h.a].q : Quat{}, qbb = h.b >= 0 ? cand[h.b].q : Quat{};
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
    dJointSetHingeAnchor(j, pivot.x, pivot.y, pivot.z);
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
    hinge_setup.push_back({pivot, ode_axis, angle});
    if (config.joint_projection) {
      const std::int32_t p1 = projected_body(swapped ? bb : ba), p2 = b2 ? projected_body(bb) : -1;
      projection.add_hinge(p1, p2, pivot, ax);
      projection_calls.push_back({-1, 0, 0, p1, p2, pivot, ax});
    }
    if (!anchor.has(h.slot)) anchor_out.set(h.slot, pivot);
    if (!axis.has(h.slot)) axis_out.set(h.slot, ax);
  }

  projection.finish();
  for (std::uint32_t b = 0; b < bodies.size(); ++b) {
    if (!bodies[b].jointed) continue;
    SetupPose sp{b, {}, {}};
    static_assert(sizeof(SetupPose) == 8 * 8 && sizeof(ProjectionCall) == 5 * 8 + 2 * sizeof(Vec3));
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
constexpr std::uint32_t kStateVersion = 1;
}

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
      dBodySetMass(b.id, &mass);
      b.mass = mass.mass;
      for (std::uint32_t i = b.first_part; i < b.first_part + b.part_count; ++i) {
        m.parts[i].offset = in.get<Vec3>();
        m.parts[i].rot = in.get<Quat>();
      }
      state[bi] = {in.get<Vec3>(), in.get<Quat>(), in.get<Vec3>(), in.get<Vec3>()};
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
    for (const auto& sp : m.setup_poses) {
      if (sp.body >= m.bodies.size()) refuse("a hinge's body is out of range");
      Impl::set_exact_pose(m.bodies[sp.body].id, sp.pos, sp.q);
    }
    for (std::size_t h = 0; h < m.hinges.size(); ++h) {
      const auto& hs = m.hinge_setup[h];
      dJointSetHingeAnchor(m.hinges[h].joint, hs.pivot.x, hs.pivot.y, hs.pivot.z);
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
        m.projection.add_hinge(std::int32_t(c.b1), std::int32_t(c.b2), c.pivot, c.axis);
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
  impulses_computed_ = in.get<std::uint8_t>() != 0;
  state_version_ = in.get<std::uint64_t>();
}

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

void RigidBodyResolver::step_world(ResolverAccess& access, double dt) {
  ensure_ode();
  Impl& m = *impl_;
  m.resolve_ids(access);
  if (m.dirty || m.defining_changed()) build(access);
  if (m.dirty) return;  // the build failed inside ODE (engine_failed): nothing to step
  m.apply_edits(access);
  screen_loads(access, dt);

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
        books_.work[a.source].second += moved;
        books_.integration += moved;
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

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
std::string vector_text(Vec3 v) {
  return "{" + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + "}";
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

void RigidBodyResolver::SourceMarks::mark(std::size_t at, const std::string* stage) {
  marks_.push_back({at, stage, stage ? *stage : std::string()});
}

const std::string& RigidBodyResolver::SourceMarks::name_of(std::size_t i) const {
  static const std::string none;
  auto it = std::upper_bound(marks_.begin(), marks_.end(), i,
                             [](std::size_t x, const Mark& m) { return x < m.from; });
  return it == marks_.begin() ? none : std::prev(it)->name;
}

void RigidBodyResolver::screen_loads(ResolverAccess& access, double dt) {
  // The loads queued on a body for the window may change its velocity by at
  // most limits::speed and its angular velocity by limits::angular_speed:
  // sum |F| dt / m and sum |torque| dt / I_min over its loads. Magnitudes are
  // summed, not vectors, so that neither the order of the sum nor +-huge
  // loads that cancel can overflow ODE's accumulators.
  Impl& m = *impl_;
  const std::size_t nb = m.bodies.size();
  strongest_source_.assign(nb, nullptr);
  if (forces_.size() == 0 && rated_loads_.empty()) return;
  std::vector<double> dv(nb, 0.0), dw(nb, 0.0), worst(nb, -1.0);
  std::vector<std::size_t> culprit(nb,
                                   0);  // the load that does most: i < forces_.size(), else rated
  auto add = [&](std::uint32_t b, double v, double w, std::size_t i) {
    v *= dt * m.inv_mass[b], w *= dt * m.inv_inertia[b];
    dv[b] += v, dw[b] += w;
    const double score = std::max(v / limits::speed, w / limits::angular_speed);
    if (!(score <= worst[b])) worst[b] = score, culprit[b] = i;  // NaN counts as the worst
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
        add(p->body, f, length(cross(c.point - x, c.value)), i);
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
  static constexpr const char* kName[] = {"add_force", "add_force_at", "add_torque"};
  for (std::uint32_t b = 0; b < nb; ++b) {
    // A stage is named as the body's pusher if its load alone changes the
    // speed by 1 % of the limit in a step (1 km/s): gravity's 0.04 m/s is not.
    if (!(worst[b] < 0.01))
      strongest_source_[b] = culprit[b] < forces_.size()
                                 ? &load_sources_.name_of(culprit[b])
                                 : &rated_sources_.name_of(culprit[b] - forces_.size());
    if (dv[b] <= limits::speed && dw[b] <= limits::angular_speed) continue;
    const std::size_t i = culprit[b];
    std::string what;
    std::vector<std::pair<std::string, double>> values;
    const std::string* source;
    if (i < forces_.size()) {
      const LoadCommand& c = loads[i];
      source = &load_sources_.name_of(i);
      what = std::string(kName[int(c.kind)]) + " " + vector_text(c.value) +
             (c.kind == Load::Torque ? " N m" : " N");
      if (c.kind == Load::ForceAtPoint) what += " at " + vector_text(c.point) + " m";
      values = components(c.value);
    } else {
      const RatedLoad& c = rated_loads_[i - forces_.size()];
      source = &rated_sources_.name_of(i - forces_.size());
      what = "add_load " + vector_text(c.force) + " N, " + vector_text(c.torque) + " N m";
      values = components(c.force);
    }
    const bool linear = !(dv[b] <= limits::speed);
    const std::string change = linear ? "its speed by " + number(dv[b]) + " m/s (the limit is " +
                                            number(limits::speed) + " m/s)"
                                      : "its angular speed by " + number(dw[b]) +
                                            " rad/s (the limit is " +
                                            number(limits::angular_speed) + " rad/s)";
    refuse_body(access, b, *source,
                "queued " + what + " on it: its loads would change " + change + " in one step of " +
                    number(dt) + " s; they were refused",
                std::move(values));
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

std::uint32_t RigidBodyResolver::work_account(const std::string& stage) {
  // The transfer is named after the physics whose stage queued the load
  // (rigid_body_from_gravity@moon -> gravity), so that the stage on the
  // other side of it can report the same name.
  std::string name = stage.substr(0, stage.find('@'));
  static constexpr std::string_view prefix = "rigid_body_from_";
  if (name.starts_with(prefix)) name.erase(0, prefix.size());
  if (name.empty()) name = "loads from outside the stages";
  for (std::size_t i = 0; i < books_.work.size(); ++i)
    if (books_.work[i].first == name) return std::uint32_t(i);
  books_.work.emplace_back(name, 0.0);
  return std::uint32_t(books_.work.size() - 1);
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
    if (stage != last) account = work_account(stage), last = stage;
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
  double along_step = 0, along_mean = 0;
  for (const EnergyBooks::Applied& a : books_.applied) {
    const dBodyID id = m.bodies[a.body].id;
    const Vec3 v1 = to_vec3(dBodyGetLinearVel(id)), w1 = to_vec3(dBodyGetAngularVel(id));
    const Vec3 v0 = books_.v0[a.body], w0 = books_.w0[a.body];
    const Vec3 torque = a.torque + cross(a.arm, a.force);
    const double step = h * (dot(a.force, v1) + dot(torque, w1));
    const double mean = 0.5 * h * (dot(a.force, v0 + v1) + dot(torque, w0 + w1));
    books_.work[a.source].second += step;
    along_step += step, along_mean += mean;
  }
  books_.integration += along_step - along_mean;
  books_.contacts += along_mean - (kinetic_energy() - ke_before);
}

void RigidBodyResolver::report_energy(const WorldView&, EnergyReport& out) {
  out.store("kinetic energy", kinetic_energy());
  books_on_ = true;
  out.sink("viscous drag (linear_damping, angular_damping)", std::exchange(books_.drag, 0.0));
  out.sink("restitution (collision impulses)", std::exchange(books_.restitution, 0.0));
  out.sink("integration and position corrections", std::exchange(books_.integration, 0.0));
  out.sink("contacts and joints (residue of the kinetic energy)",
           std::exchange(books_.contacts, 0.0));
  for (auto& [name, joules] : books_.work) out.transfer(name, std::exchange(joules, 0.0));
}

void RigidBodyResolver::advance(ResolverAccess& access, double dt) {
  try {
    step_world(access, dt);
  } catch (const OdeError& e) {
    engine_failed(access, e.what());
  }
}

}  // namespace alloy::rigid
