// The rigid body on Box2D (2.4.1): a second engine providing `rigid_body`
// for the 2D kit, beside ODE's (resolvers/rigid_body/). Scenes choose it with
// `use = { rigid_body = "rigid_body.box2d", collisions = "collisions.box2d" }`
// or swap it in while the world runs (World::swap); everything else (gravity,
// magnetism, electricity, sound, Lua mods) talks to it through the same
// interfaces as to ODE: RigidBodyEngine for loads, ContactSet for contacts.
//
// Reads   shape, size, radius, length, mass, density, static, pinned,
//         linear_damping, angular_damping, friction, restitution, and joint
//         objects (joint, body_a, body_b, anchor, axis, joint_friction,
//         limit_low, limit_high): the same as ODE's engine, plus the contact
//         materials (Box2D resolves contacts inside its step, so the engine
//         mixes the materials itself, exactly as rigid_body_from_collisions
//         does for ODE: friction sqrt(mu_a mu_b), restitution max(e_a, e_b)).
// Writes  position, orientation, velocity, angular_velocity, mass (from
//         density), and the anchor of hinges.
//
// What Box2D cannot express is refused at build with an InputError naming the
// object: a part off the z = 0 plane, turned about anything but z, moving or
// spinning out of the plane, a hinge whose axis is not along z.
//
// Units. Box2D's tolerances (linear slop 5 mm, the 2 m/step speed cap, the
// sleep thresholds) are tuned for objects of 0.1 to 10 m, and the kit's parts
// are 2 to 12 cm. The engine runs Box2D in scaled units: lengths times
// `scale` (default 10), time and mass unchanged, so velocities scale by s,
// forces by s, torques and moments of inertia by s^2, impulses by s.
// docs/box2d.md has the measurements behind the default.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "resolvers/rigid_body/energy_books.hpp"
#include "resolvers/rigid_body/engine.hpp"
#include "resolvers/rigid_body/load_screen.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"

class b2Body;
class b2Contact;
class b2World;
struct b2ContactImpulse;
struct b2Vec2;

namespace alloy::box2d {

/// Settings of `rigid_body.box2d`.
struct Box2DConfig {
  /// Box2D length units per metre (see the header). 1: SI metres.
  double scale = 10;
  /// Box2D's sequential-impulse iterations per step (its defaults are 8 and
  /// 3; the velocity ones are raised to keep stacks as still as ODE's 40).
  int velocity_iterations = 20;
  int position_iterations = 8;
  /// Box2D steps per advance, at least: loads are held over the window.
  int substeps = 1;
  /// The longest Box2D step, s (0: no bound): an advance of dt takes
  /// max(substeps, ceil(dt / max_substep)) steps. 1/240 s by the
  /// work-precision study in docs/box2d.md ("Box2D's step and the world's"):
  /// at the kit's 1/240 s one step, as before; at 1/120 s two, at 1/60 s four
  /// (Box2D v3's own default at 60 Hz).
  double max_substep = 1.0 / 240;
  /// Bodies at rest sleep (Box2D's islands, 0.5 s below 1 cm/s and 2 deg/s in
  /// scaled units). Off by default, as ODE's auto_disable.
  bool sleep = false;
  /// Approach speeds below this do not bounce, m/s (rigid_body_from_collisions'
  /// bounce_velocity for ODE).
  double bounce_velocity = 0.1;

  /// Reads and validates the plugin settings; InputError names the bad key.
  static Box2DConfig from(const PluginSettings& settings);
};

/// Box2D steps in an advance of `dt` by the settings (before any the speed of
/// a body adds): max(substeps, ceil(dt / max_substep)).
int substeps_for(const Box2DConfig& config, double dt);

class Box2DEngine final : public rigid::RigidBodyEngine {
 public:
  Box2DEngine(const World& world, Box2DConfig config);
  ~Box2DEngine() override;

  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  void on_structure_changed(const WorldView&) override { dirty_ = true; }
  std::uint64_t state_version() const override { return state_version_; }
  /// Box2D's world is rebuilt from the properties at a restore (its warm
  /// starts are not saved: docs/saves.md); what is saved is whether the last
  /// advance left contact pairs out, so that a restored heap does not report
  /// `contact_limit` again as if it had just begun.
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;
  /// The same books as ODE's engine, under the same names (energy_books.hpp,
  /// box2d_energy.cpp): kinetic energy (store), the work of each stage's
  /// loads (transfer named after the physics), drag, the collision impulses'
  /// loss (restitution), the integrator's share and position corrections,
  /// and the contacts' and joints' (the residue) as sinks. Kept from the
  /// first report on, or from the first advance when the world's ledger
  /// asked before this engine was made (a swap).
  void report_energy(const WorldView& view, EnergyReport& out) override;

  void add_force(ObjectId part, Vec3 force) override;
  void add_force(ObjectId part, Vec3 force, Vec3 point) override;
  void add_force(std::uint32_t slot, Vec3 force) override;
  void add_torque(ObjectId part, Vec3 torque) override;
  /// Substep k of the window applies value + rate * k * dt / substeps.
  void add_load(ObjectId part, Vec3 force, Vec3 torque, Vec3 force_rate, Vec3 torque_rate) override;
  /// Taken whole when every part of every moving body is among `parts` and g
  /// lies in the plane (else false: the weights come as forces, screened and
  /// reported as any load). The advance then applies each part's weight m g
  /// at the place in the queue where it was given, the same float operations
  /// as the queued forces (bit for bit), without queueing or screening them
  /// one by one (the screen checks |g| dt once). Not Box2D's world gravity:
  /// Box2D forms m g in single precision and adds it after the other forces,
  /// which changed the doorbell's 34 strikes to 3 s to 33 (rounding alone).
  /// Checked again at the advance against the bodies it steps (a rebuild may
  /// bring parts outside the field): if they are not all covered then, the
  /// weights are queued as forces there.
  bool add_uniform_gravity(Vec3 g, std::span<const std::uint32_t> parts) override;
  std::span<LoadCommand> open_loads(std::size_t n) override;
  void close_loads(std::size_t used) override;

  ImpulseDemand demand_impulses() const override { return ImpulseDemand(impulse_demand_); }
  std::size_t body_count() const override;
  std::size_t joint_count() const override;
  std::size_t awake_count() const override;

  // --- published for collisions.box2d ---------------------------------------------
  /// Appends the pairs touching after the last advance, sorted by (a, b), to
  /// `pairs`: a and b only (ContactSet's deferred geometry).
  void pairs_into(std::vector<ContactPair>& pairs) const;
  /// Fills `pairs` (sorted, a subset of pairs_into's, geometry 0) with their
  /// points, appended to `points`, and first, count, normal_speed and depth:
  /// the same values whichever subset is asked. Valid from one advance to the
  /// next: while state_version() is what it was after the advance.
  void geometry_into(std::span<ContactPair> pairs, std::vector<ContactPoint>& points) const;
  /// ContactSet::touching_ahead on Box2D's own shapes: each body moved on by
  /// its velocities for `seconds`, each pair of the parts' fixtures that
  /// Box2D would collide, does not touch in `now` and one of which moves,
  /// found by its predicted bounds and tested with its distance (radii
  /// included). Needs only the bodies: a restored engine answers at once.
  std::vector<PredictedTouch> touching_ahead(std::span<const ObjectId> parts, double seconds,
                                             const ContactSet& now) const;
  /// The contact set that reads this engine's contacts (collisions.box2d):
  /// told before Box2D's world is destroyed, to make a deferred geometry
  /// first (a swap hands the retired set's pairs to the next engine's).
  void attach_contacts(class Box2DContacts* set) const { contacts_ = set; }
  /// Impulses of the last advance per pair, sorted by (a, b); empty unless
  /// impulses_computed().
  std::span<const PairImpulse> impulses() const { return impulses_; }
  bool impulses_computed() const { return impulses_computed_; }
  const Box2DConfig& config() const { return config_; }
  /// Full builds so far (build() and rebuilds after an edit from outside).
  std::uint64_t rebuild_count() const { return rebuilds_; }
  /// Parts moved back by continuous detection (a tunnelled centre), in every
  /// advance so far (box2d_engine.cpp, Impl::sweep).
  std::uint64_t sweep_count() const;
  /// Bodies waiting outside Box2D's world, each sunk deep into more than 64
  /// moving bodies (a heap of parts placed through each other; docs/security.md).
  std::size_t waiting_count() const;
  /// Work counters for the heap guard's tests: pairs Box2D's broad phase put
  /// to the contact filter (after its AddPair walk), shape tests the guard
  /// made, in every advance so far; Box2D's contacts now.
  std::uint64_t pair_filter_calls() const;
  std::uint64_t crowd_tests() const;
  std::size_t box2d_contact_count() const;

  struct Impl;  // Box2D's world and the part <-> body tables (box2d_engine.cpp)

 private:
  void queue(ObjectId part, Vec3 value, Vec3 point, Load kind);
  /// The load screen shared with ODE (load_screen.hpp), and an event for
  /// loads or parts of loads the plane drops (a force along z, a torque about
  /// x or y), once per stage and kind of load.
  void screen_loads(ResolverAccess& access, double dt);
  /// The "contact_limit" event when Box2D began to leave pairs out
  /// (limits::contact_pairs).
  void report_left_out(ResolverAccess& access);
  /// The "crowded" event when bodies begin to wait (Impl::settle_crowds).
  void report_waiting(ResolverAccess& access);
  bool edited_since_write(const WorldView& view) const;
  void note_versions(const WorldView& view);

  // --- the energy books (box2d_energy.cpp), kept while books_on_ -----------------
  /// The Box2D body that carries a load's part (null: not ours, stale, not
  /// moving) and the part's centre in its frame.
  using Carrier =
      std::function<b2Body*(std::uint32_t slot, std::uint32_t generation, b2Vec2& local)>;
  /// Before the substeps: the window's loads (the queue, the rated loads and
  /// the uniform weights when `weigh`) with their accounts and carriers, and
  /// Box2D's contact callbacks relayed through the books (for restitution).
  void books_open(bool weigh, const ColumnView<double>& mass, const Carrier& carrier);
  /// Substep at time `tau` into the window: before the drag, before the step
  /// (h long), after it.
  void books_before_drag(double tau);
  void books_before_step(double h);
  void books_after_step(double h);
  /// After the window's sweep (continuous detection's move back, with no
  /// velocity): the loads' work along it, and the contact callbacks back.
  void books_close();
  /// PostSolve of a contact in a booked step: its impulses' work if it bounced.
  void book_collision(b2Contact* contact, const b2ContactImpulse* impulse);
  double kinetic_energy() const;
  b2World* box2d_world() const;  // null before the first build
  bool books_on_ = false;
  rigid::EnergyBooks books_;
  struct Books;  // the window's loads, carriers, velocities and the relay
  std::shared_ptr<Books> b2books_;

  const World& world_;
  const PropertyStore& store_;
  Box2DConfig config_;
  std::unique_ptr<Impl> impl_;
  std::vector<LoadCommand> loads_;
  std::size_t open_ = ~std::size_t(0);
  struct RatedLoad {
    std::uint32_t slot, generation;
    Vec3 force, torque, force_rate, torque_rate;
  };
  std::vector<RatedLoad> rated_;
  // The uniform gravity of the next advance (add_uniform_gravity): g, the
  // parts it weighs, and the stage that gave it (for a refusal's source).
  bool uniform_ = false;
  Vec3 uniform_g_;
  std::size_t uniform_at_ = 0;  // where in loads_ the weights were given
  std::vector<std::uint32_t> uniform_parts_;
  const std::string* uniform_source_ = nullptr;
  /// Whether every part of every moving body is in uniform_parts_.
  bool uniform_covers_all() const;
  rigid::SourceMarks load_sources_, rated_sources_;  // of loads_ and rated_
  rigid::LoadScreen screen_;
  /// (stage, kind) pairs whose out-of-plane loads were reported.
  std::vector<std::pair<std::string, std::string>> dropped_reported_;
  bool limited_before_ = false;  // the last advance left contact pairs out
  std::vector<PairImpulse> impulses_;
  std::shared_ptr<std::size_t> impulse_demand_ = std::make_shared<std::size_t>(0);
  bool impulses_computed_ = false;
  bool dirty_ = true;
  std::vector<std::uint64_t> versions_;  // of the columns read, after our last write
  std::vector<PropertyId> defining_;     // those columns (kDefining), looked up once
  std::array<PropertyId, 4> motion_{kNoProperty, kNoProperty, kNoProperty, kNoProperty};
  std::uint64_t state_version_ = 0;
  std::uint64_t rebuilds_ = 0;
  mutable class Box2DContacts* contacts_ = nullptr;  // attach_contacts
};

/// `collisions.box2d`: the contact lists of the Box2D engine's last advance.
class Box2DContacts final : public ContactSet {
 public:
  Box2DContacts(const Box2DEngine& engine, bool always_impulses);
  void update(const WorldView& world) override;
  ~Box2DContacts() override;
  ImpulseDemand demand_impulses() const override {
    return engine_ ? engine_->demand_impulses() : ImpulseDemand{};
  }
  /// The pairs touching after the last update, with their points, began
  /// steps and impulse totals. A restored Box2D world has no contacts until
  /// its first advance (they are not saved), so the update that primes a
  /// restored set publishes these instead, and the next one merges with them
  /// as the run that went on did: no pair ends and begins again, no circuit
  /// through a contact opens for a step (adv15 F9).
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;
  std::vector<PredictedTouch> touching_ahead(const WorldView& world,
                                             std::span<const ObjectId> parts,
                                             double seconds) const override {
    (void)world;
    return engine_ ? engine_->touching_ahead(parts, seconds, *this) : std::vector<PredictedTouch>{};
  }
  /// Box2D finds its contacts at the start of its step: a touch is reported
  /// an update after ODE's set would report it.
  int report_lag() const override { return 1; }

 private:
  void make_geometry(std::span<ContactPair> pairs,
                     std::vector<ContactPoint>& points) const override;
  bool geometry_available() const override {
    return engine_ && engine_->state_version() == version_;
  }
  friend class Box2DEngine;  // its end: engine_gone()
  /// The engine is being destroyed: makes the deferred geometry while its
  /// world still stands, and forgets it.
  void engine_gone();

  const Box2DEngine* engine_;  // null once the engine is gone (engine_gone)
  ImpulseDemand always_;       // impulses = true
  std::uint64_t version_ = 0;  // the engine's state_version() at the last update
  bool restored_ = false;      // the next update primes a restored set
};

}  // namespace alloy::box2d
