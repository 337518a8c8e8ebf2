// The rigid body resolver: ODE dynamics for every object that carries mass or
// density and is not static (paper 3.2: the "dynamics resolver").
//
// Reads   shape, size, radius, length, mass, density, static, pinned, planar,
//         linear_damping, angular_damping, and joint objects (joint, body_a,
//         body_b, anchor, axis, joint_friction, limit_low, limit_high).
// Writes  position, orientation, velocity, angular_velocity, mass (from density),
//         anchor and axis of hinges (kept current so that a rebuild or a swap
//         of resolver finds the joint where it is).
// Queue   add_force / add_torque (from rigid_body_from_gravity, magnetism, ...)
//         and add_contact (from rigid_body_from_collisions), performed in the
//         next advance() and then cleared.
// Publishes the impulse applied to each contact pair in the last advance
//         (state_version() moves when it changes); the collisions set reads it.
//         Computed only while some stage demands it (demand_impulses()): ODE's
//         joint feedback costs about 2 % of a pile's step, and most scenes
//         never read an impulse.
//
// All state that matters lives in properties: build() recreates the ODE world
// from them, and advance() rebuilds when a defining column changed (a part
// unpinned, a shape resized) and teleports bodies whose pose or velocity was
// edited from outside between steps.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "resolvers/rigid_body/contact.hpp"
#include "resolvers/rigid_body/energy_books.hpp"
#include "resolvers/rigid_body/engine.hpp"
#include "resolvers/rigid_body/load_screen.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::rigid {

/// Settings of the `rigid_body` plugin, with defaults chosen for the world's
/// default step of 1/240 s.
struct RigidBodyConfig {
  enum class Solver : std::uint8_t { Quick, Step };
  /// "quick": dWorldQuickStep, iterative (SOR-PGS), O(rows * iterations): the
  /// only choice that scales to piles. "step": dWorldStep, a direct LCP solve,
  /// exact but O(rows^3): for small precise mechanisms.
  Solver solver = Solver::Quick;
  /// QuickStep iterations. Measured on a stack of 10 cubes standing 10 s at
  /// 240 Hz (tests/resolvers accuracy): the top drifts 1.2 cm with ODE's default
  /// of 20, 4.5 mm with 40, 2 mm with 60. 40 keeps a 2x margin under the 1 cm
  /// criterion; the cost is linear in it and small for kit-sized scenes.
  int iterations = 40;
  /// Over-relaxation of QuickStep (ODE's default).
  double sor = 1.3;
  /// Error reduction per step. 0.2 at 240 Hz removes a joint or contact error
  /// with a time constant of about 5 steps (21 ms): invisible, and low enough
  /// that the push-out does not add visible energy to resting contacts.
  double erp = 0.2;
  /// Constraint force mixing of joints (not contacts). A small softness
  /// (ODE's single-precision default) regularises redundant constraints (a
  /// planar body on a hinge) and lets QuickStep converge. As a spring it is
  /// k = erp / (h cfm) with damping (1 - erp) / cfm: stiffer as the step
  /// falls, so a joint's stretch under a load falls with the step.
  double cfm = 1e-5;
  /// Contact stiffness, N/m, and damping, N*s/m, of resting and sliding
  /// contacts (docs/architecture.md, "Contact model"). Each contact point is
  /// a spring-damper solved implicitly over the step h: ERP = h k / (h k + c)
  /// and CFM = 1 / (h k + c) (ODE's manual), the same physical spring at any
  /// step. The defaults give exactly the ERP 0.2 and CFM 1e-5 used at 1/240 s
  /// before (k = 0.2 / (h CFM), c = 0.8 / CFM): an overlap relaxes with the
  /// time constant c / k = 17 ms, and a 1 kg box rests 2 micrometres deep.
  /// Collisions do not depend on them (restitution_pass resolves those
  /// exactly). 0: rigid contacts, CFM 0 and the error reduction `erp`; for
  /// QuickStep only (the direct solver's LCP fails on a box's four redundant
  /// contact points without some compliance), and stacks stand less still.
  double contact_stiffness = 4.8e6;
  double contact_damping = 8e4;
  /// Collisions with restitution (approach faster than the pair's bounce
  /// velocity) are resolved before the step by pairwise impulses, one
  /// collision point at a time, the fastest approaching first, each moved to
  /// its time of impact (see restitution_pass). At most this many impulses a
  /// step (a chain of n touching balls needs n - 1); the remaining
  /// approach, if any, is left to the simultaneous solve.
  int max_collision_impulses = 256;
  /// Hinges hold by a position projection after each step (SHAKE-like; see
  /// resolvers/rigid_body/joint_projection.hpp and docs/architecture.md,
  /// "Joint model"): each island of hinged planar bodies gets, along the
  /// hinges' start-of-step directions, the impulse that puts its anchors
  /// back together, on the poses and the velocities alike. At 1/240 s a
  /// small ball on a 1 m lever then keeps its length to 1e-11 instead of
  /// stretching 5 %, a 1000:1 chain to 4.4e-5 instead of coming apart, and
  /// a pendulum its energy (no drift from the error reduction). Islands of
  /// bodies that turn in 3D, or of more than 16 hinges, keep ODE's hinges.
  /// false: ODE's hinges alone.
  bool joint_projection = true;
  /// Most contact points per pair of parts: 4 is a box face's corners.
  int max_contacts = 4;
  /// Penetration allowed without correction, m. Resting contacts then keep a
  /// small overlap instead of being pushed apart and falling back each step,
  /// which would make contact lists (and electric circuits) flicker; a pressed
  /// contact that has drifted shallower than half of it (a bar sliding on a
  /// turning part) may close to it again within a step. Small, because a
  /// stack sinks by it once per contact (10 cubes: 1 mm).
  double surface_layer = 0.0001;
  /// Cap on the velocity with which ERP pushes overlapping parts apart, m/s:
  /// a deep overlap (a part dropped into another) separates gently instead of
  /// exploding. Does not limit restitution.
  double max_correcting_velocity = 2.0;
  /// ODE steps of dt / substeps per advance. The coupling window stays the
  /// world's step: forces queued by interactions are held over the window (a
  /// zero-order hold; a load queued with its rate by add_load follows it, a
  /// first-order hold), and the contacts found at its start are kept, their
  /// depth carried forward by the parts' approach speed. For stiff mechanisms
  /// (heavy on light, long chains) where the contact and joint solve needs a
  /// shorter step than the rest of the world, and for loads that change with
  /// the pose faster than the coupling window resolves (a magnet's torque on
  /// a turning rotor) when queued with their rates.
  int substeps = 1;
  /// With substeps: "kept" keeps the contact points found at the window's
  /// start (their depth carried by the approach speed); "found" finds each
  /// queued pair's points again before every substep from the parts' present
  /// poses (ODE's narrow phase on the pair's two shapes), so that a contact
  /// that slides along a turning part, or ends within the window, is where
  /// the parts are. New pairs are still found once a window (the collisions
  /// set), so with "found" the error reduction (erp) acts at the window's
  /// pace, erp / substeps per substep. No effect with one substep.
  enum class SubstepContacts : std::uint8_t { Kept, Found };
  SubstepContacts substep_contacts = SubstepContacts::Kept;
  /// Bodies at rest stop being simulated (ODE's auto-disable) until something
  /// touches them, an edit moves them, or the load queued on them changes. A
  /// settled pile then costs little more than its collision detection.
  bool auto_disable = false;
  /// Below these average speeds for `auto_disable_steps` steps a body sleeps.
  /// Above QuickStep's resting jitter: boxes at rest in a stack solved with
  /// 40 iterations still move at about 2 cm/s (tests/stress), and with 0.01 m/s
  /// nothing ever slept; 0.05 m/s and 0.2 rad/s are the thresholds measured to
  /// put the 20-box stack, the pyramid and the 1,000-body pile to sleep.
  double auto_disable_linear = 0.05;  ///< m/s
  double auto_disable_angular = 0.2;  ///< rad/s
  int auto_disable_steps = 20;
  /// Continuous collision detection: a part that moves more than half its
  /// inscribed radius in a step is swept, and if its centre crossed a surface
  /// it is moved back to where it first touched it (collisions.hpp). Without
  /// it a 500 m/s ball passes through a 0.1 m wall in 191 shots of 200 at
  /// 1/240 s (docs/performance.md, stress tests). Costs nothing for slow parts.
  bool ccd = true;

  /// Reads and validates the plugin settings; InputError names the bad key.
  static RigidBodyConfig from(const PluginSettings& settings);
  /// The setting keys `from` accepts.
  static const std::vector<std::string>& keys();
};

/// One contact pair queued by an interaction: points [first, first + count) of
/// the queue's point list, and the combined surface of the pair.
struct ContactCommand {
  ObjectId a, b;  ///< the two parts, a < b; either may be immovable
  std::uint32_t first = 0, count = 0;
  double friction = 0.5;         ///< Coulomb mu of the pair
  double restitution = 0;        ///< of the pair, 0..1
  double bounce_velocity = 0.1;  ///< approach speeds below this do not bounce, m/s
};

class RigidBodyResolver final : public RigidBodyEngine {
 public:
  RigidBodyResolver(const World& world, RigidBodyConfig config);
  ~RigidBodyResolver() override;

  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  std::uint64_t state_version() const override { return state_version_; }
  /// The ODE state that properties do not hold bit for bit (docs/saves.md):
  /// assemblies' mass and frames, the poses the hinges were measured in at
  /// the last build, each body's exact state where it is not its part's
  /// properties, sleep flags, the impulses published by the last advance.
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;
  /// Kinetic energy (store), the work of each stage's loads (transfer named
  /// after the physics: "gravity" for rigid_body_from_gravity), viscous drag,
  /// restitution, the integrator's share and the contacts' and joints' (the
  /// residue) as sinks (docs/energy.md). Books are kept from the first call on.
  void report_energy(const WorldView& view, EnergyReport& out) override;

  // --- interaction functions: queued, performed in the next advance -------------
  /// Force at the part's centre of mass, N. A stale id throws AccessError.
  void add_force(ObjectId part, Vec3 force) override;
  /// Force applied at a world point, N (adds the torque about the centre of mass).
  void add_force(ObjectId part, Vec3 force, Vec3 point) override;
  /// Fast path for loops over a column's members (no liveness check: the slot
  /// comes from a live member list in the same phase).
  void add_force(std::uint32_t slot, Vec3 force) override {
    load_sources_.note(forces_.size(), world_.running_stage());
    forces_.push_back({slot, store_.id_at(slot).generation, force, {}, Load::Force});
  }
  /// Torque, N*m, world frame.
  void add_torque(ObjectId part, Vec3 torque) override;
  /// A force at the part's centre of mass and a torque (world frame) with
  /// their rates of change, N/s and N*m/s (a derived set's d/dt along the
  /// present motion). Substep s of the window (s = 0 .. substeps - 1) applies
  /// value + rate * s * dt / substeps: a first-order hold, so that a load
  /// that depends on the pose follows the parts as they move within the
  /// window; with one substep it is exactly the value.
  void add_load(ObjectId part, Vec3 force, Vec3 torque, Vec3 force_rate, Vec3 torque_rate) override;
  /// A contact pair with its points; the resolver makes ODE contact joints of
  /// them for one advance. Pairs within one assembly or of two immovable parts
  /// are ignored.
  void add_contact(const ContactCommand& pair, std::span<const ContactPoint> points);
  /// Many pairs at once: each pair's [first, first + count) indexes `points`.
  /// The points are copied in one block (a pile queues about 4,000 a step).
  void add_contacts(std::span<const ContactCommand> pairs, std::span<const ContactPoint> points);
  /// Moves the part's body by `displacement` (m) before the next step, keeping
  /// its velocity: continuous detection's move back to the time of impact.
  /// Of several for one body, the largest is taken. Stale ids are ignored.
  void displace(ObjectId part, Vec3 displacement);
  /// The parts to hold still from the next advance on, replacing the last
  /// list: collisions' parts buried in a heap (CollisionSet::waiting). A held
  /// part's body is disabled with no velocity (no load, no integration) until
  /// a later list leaves it out; immovable parts and stale ids are ignored.
  void hold(std::span<const ObjectId> parts);

  // --- in-place queueing, for bindings that write load records themselves ------
  // (Load and LoadCommand: engine.hpp.)
  /// Room for `n` records after those queued when the room was first opened,
  /// to be filled by the caller: not cleared (the queue reuses its storage from
  /// step to step), so every record needs its slot, generation, value and
  /// kind, and its point for ForceAtPoint. Asking
  /// again for more keeps the records written so far, though the span moves.
  /// The generation of each record must be its object's, as add_force(ObjectId)
  /// would take it. close_loads(used) keeps the first `used` of them.
  std::span<LoadCommand> open_loads(std::size_t n) override;
  void close_loads(std::size_t used) override;

  // --- published state ------------------------------------------------------------
  /// Impulses of the last advance, one per contact pair it resolved, sorted by
  /// (a, b); empty when the advance computed none (impulses_computed()).
  std::span<const PairImpulse> impulses() const { return impulses_; }
  /// Declares that the caller reads impulses: from the next advance on, and
  /// while the returned demand (or any other) is held, advances compute them.
  ImpulseDemand demand_impulses() const override { return ImpulseDemand(impulse_demand_); }
  /// Whether the last advance computed impulses (some demand was held).
  bool impulses_computed() const { return impulses_computed_; }
  const RigidBodyConfig& config() const { return config_; }

  // --- introspection (tests, profiling) --------------------------------------------
  /// ODE bodies: one per assembly of parts glued by fixed joints.
  std::size_t body_count() const override;
  /// ODE joints made from joint objects (fixed joints merge bodies and make none).
  std::size_t joint_count() const override;
  /// Bodies being simulated: not kinematic, and not asleep (auto_disable).
  std::size_t awake_count() const override;
  /// Full rebuilds so far (build() and rebuilds after a defining edit).
  std::uint64_t rebuild_count() const { return rebuilds_; }
  /// Errors raised inside ODE so far (OdeError), each reported as an
  /// "engine_error" event; the world was rebuilt from properties after each.
  std::uint64_t engine_error_count() const { return engine_errors_; }

 private:
  /// A load queued by add_load.
  struct RatedLoad {
    std::uint32_t slot, generation;
    Vec3 force, torque, force_rate, torque_rate;
  };
  struct Impl;

  void queue(ObjectId part, Vec3 value, Vec3 point, Load kind);
  /// advance() without its guard: OdeError escapes it.
  void step_world(ResolverAccess& access, double dt);
  // Bounds (limits:: in properties.hpp): the section "bounds" of rigid_body.cpp.
  void screen_loads(ResolverAccess& access, double dt);
  void check_motion(ResolverAccess& access);
  void refuse_body(ResolverAccess& access, std::uint32_t body, const std::string& source,
                   const std::string& text, std::vector<std::pair<std::string, double>> values);
  void engine_failed(ResolverAccess& access, const std::string& what);

  // The parts of advance().
  void apply_loads();
  void apply_rated_loads(double tau);
  void wake_on_load_change();
  void add_contact_joints(double h, bool record, bool feedback);
  void restitution_pass(double h, bool feedback);
  void apply_displacements();
  void apply_holds();
  void carry_depths(double h);
  void find_substep_contacts(ResolverAccess& access);

  const World& world_;
  const PropertyStore& store_;
  RigidBodyConfig config_;
  std::unique_ptr<Impl> impl_;
  /// The queued loads: [0, size) of a vector that keeps its elements between
  /// steps, so that open_loads zeroes memory only when the queue grows past
  /// its largest size so far (value-initialising the room every call cost a
  /// Lua stage about 8 % at 1,000 bodies).
  class LoadQueue {
   public:
    void push_back(const LoadCommand& c) {
      if (n_ == v_.size())
        v_.push_back(c);
      else
        v_[n_] = c;
      ++n_;
    }
    const LoadCommand* begin() const { return v_.data(); }
    const LoadCommand* end() const { return v_.data() + n_; }
    std::size_t size() const { return n_; }
    void clear() { n_ = 0; }
    /// Storage for [at, at + n), kept as it was where it existed.
    LoadCommand* room(std::size_t at, std::size_t n) {
      if (v_.size() < at + n) v_.resize(at + n);
      return v_.data() + at;
    }
    void set_size(std::size_t n) { n_ = n; }

   private:
    std::vector<LoadCommand> v_;
    std::size_t n_ = 0;
  };
  LoadQueue forces_;
  SourceMarks load_sources_, rated_sources_;  // of forces_ and rated_loads_
  LoadScreen screen_;                         // screen_loads' sums, kept for their storage

  /// The energy books (report_energy; energy_books.hpp). Kept only once a
  /// ledger asked (books_on_): they cost three passes over the bodies a
  /// substep.
  bool books_on_ = false;
  EnergyBooks books_;
  double kinetic_energy() const;
  void book_loads_before(double tau);
  void book_loads_after(double h, double ke_before);
  /// Per body, the stage whose load did the most to it in this window (into
  /// the marks' names; null: none), for check_motion's message.
  std::vector<const std::string*> strongest_source_;
  std::size_t open_ = ~std::size_t(0);  // open_loads: where the open room starts
  std::vector<RatedLoad> rated_loads_;
  std::vector<ContactCommand> contacts_;
  std::vector<ContactPoint> contact_points_;
  std::vector<std::pair<ObjectId, Vec3>> displacements_;
  std::vector<ObjectId> held_;   // hold(): parts to hold still
  std::size_t held_bodies_ = 0;  // bodies apply_holds disabled, still held
  // substep_contacts = found: the window's queued pairs and points, kept
  // while contacts_ / contact_points_ hold a substep's, and each pair's force
  // summed over the substeps (on a, and its normal part).
  std::vector<ContactCommand> window_contacts_;
  std::vector<ContactPoint> window_points_;
  std::vector<Vec3> pair_force_;
  std::vector<double> pair_normal_;
  std::vector<PairImpulse> impulses_;
  // restitution_pass: each queued pair's collision impulse on a (and its
  // normal part) summed over the window's substeps; empty when none.
  std::vector<Vec3> pass_impulse_;
  std::vector<double> pass_normal_;
  // Demands held by readers of impulses (shared: a demand may outlive us).
  std::shared_ptr<std::size_t> impulse_demand_ = std::make_shared<std::size_t>(0);
  bool impulses_computed_ = false;
  std::uint64_t state_version_ = 0;
  std::uint64_t rebuilds_ = 0;
  std::uint64_t engine_errors_ = 0;
  /// Saved state restored into a world that rebuilds us at its next step
  /// (restore_state), saved again as it was until then.
  std::vector<std::byte> unapplied_;
};

}  // namespace alloy::rigid
