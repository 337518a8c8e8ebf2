// The `collisions` derived property set (paper 3.3): which parts touch, from
// their positions and shapes alone, with ODE's collision detection in a space
// of its own (the rigid body's bodies are never touched).
//
// Reads    position, orientation, velocity, angular_velocity, shape, size,
//          radius, length, static; joint, body_a, body_b (joined parts do not
//          collide); the rigid body's published impulses.
// Provides for the step of its last update, each list sorted by (a, b):
//          began    pairs that touch now and did not at the last update
//          ongoing  pairs that touched then and still do
//          ended    pairs that touched then and do not now
//          with contact points, normals, depths, the approach speed, and the
//          impulse the rigid body applied to the pair in its last advance.
// Emits    contact_began {speed, depth} and contact_ended {impulse, duration}.
//
// Impulses are computed only for their readers: a stage that reads them
// declares it with demand_impulses() (sound_from_collisions, Lua stages that
// read contacts, the viewer's contact forces, lua::ModRuntime while a mod
// handles contact_ended or every event), or a scene with the setting
// `collisions { impulses = true }` (for other observers of contact_ended).
// Without a demand the rigid body skips ODE's joint feedback (about 2 % of a
// pile's step): the pairs' impulse fields stay 0, impulses_known() is false,
// and contact_ended carries only its duration. A pair that began before the
// demand did has no complete total: its contact_ended has no impulse either.
//
// Pairs of two static parts are never tested (floor against wall).
//
// Parts buried in a heap (docs/security.md): the bound on pairs per part
// (limits::contact_pairs_per_part) still leaves a heap of n parts placed
// through each other n^2 / 2 pairs to look at and 32 n to solve (1,000 balls
// at one spot: 31,472 touching pairs, seconds a step). When an update leaves
// pairs out, every movable part sunk deep (a pair deeper than half the sum of
// the two parts' inscribed radii: for two balls, centres closer than half
// the sum of their radii, Box2D's rule) into more than 32 movable parts that
// are not waiting already waits, in slot order: it takes no part in
// collisions, and the rigid body holds it still, until it is sunk so into at
// most 4 (the heap's parts have moved apart), checked each update in the
// order they went, each one back counting for the next. A `crowded` event
// says when parts begin to wait. The same rule as rigid_body.box2d's.
//
// Continuous detection (rigid_body setting `ccd`, on by default): a movable
// part that moved more than half its inscribed radius in the last step, along
// its velocity, is swept: a ray from its centre's previous position to its
// current one against the space. If the centre crossed a surface, the part has
// tunnelled (or sunk past the point where the discrete contact's normal can be
// trusted): its discrete pairs are replaced by one contact with the surface it
// crossed first, at the pose where it first touches it, and sweeps() says how
// far the part must move back to that pose (the rigid body applies it before
// its next advance, Box2D's time-of-impact idea without the sub-step).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "resolvers/rigid_body/contact.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

struct dxGeom;
struct dContactGeom;

namespace alloy::rigid {

class RigidBodyResolver;

/// The narrow phase of two parts' ODE geoms (dCollide with our own rules; the
/// rigid body's substeps use it too, so that both find the same points):
/// two cylinders side by side (parallel axes, each centred within the
/// other's thickness: disks in the play area) touch as two circles, across
/// their axes; and a point between a round part (sphere, capsule, cylinder)
/// and one that is not lies on the round part's surface, so that the surface
/// layer's overlap does not shorten its rolling radius. Returns the number of
/// points written to out[0, max).
int collide_parts(dxGeom* g1, dxGeom* g2, int max, dContactGeom* out);

/// A part moved back along its path to where it first touched a surface.
struct Sweep {
  ObjectId part;
  Vec3 displacement;  ///< from its current position to the touching one, m
};

class CollisionSet final : public ContactSet {
 public:
  /// always_impulses: demand impulses for the set's whole life (the scene's
  /// setting `impulses = true`), whether or not a stage reads them.
  CollisionSet(const RigidBodyResolver& rigid, int max_contacts, bool always_impulses = false);
  ~CollisionSet() override;

  void update(const WorldView& world) override;
  void on_structure_changed(const WorldView& world) override;

  /// The set's memory as it was before its last update (the pairs that
  /// touched then, with their began_step and impulse totals; the swept
  /// parts' previous positions; the step of that update). A restore primes
  /// derived sets by updating them once: the restored set repeats its last
  /// update from that memory, and so publishes what the uninterrupted run's
  /// set published (began, ended, totals, durations), bit for bit.
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  /// Parts that tunnelled in the last step, in ObjectId order (see the header).
  std::span<const Sweep> sweeps() const { return sweeps_; }
  /// Parts buried in a heap, waiting outside collisions (see the header), in
  /// the order they went: the rigid body holds them still.
  std::span<const ObjectId> waiting() const { return waiting_; }
  /// Shape tests made to find buried parts, in all (a measure of the guard's cost).
  std::uint64_t crowd_tests() const;
  /// Declares that the caller reads the pairs' impulses (see the header):
  /// they are computed from the rigid body's next advance on while it is held.
  ImpulseDemand demand_impulses() const override;
  /// Moves the parts' geoms to their predicted poses, tests each pair
  /// (bounds, then collide_parts) and puts them back where they were.
  std::vector<PredictedTouch> touching_ahead(const WorldView& world,
                                             std::span<const ObjectId> parts,
                                             double seconds) const override;

 private:
  struct Impl;
  const RigidBodyResolver& rigid_;
  std::unique_ptr<Impl> impl_;
  std::vector<Sweep> sweeps_;
  std::vector<ObjectId> waiting_;
  ImpulseDemand always_;
  // impulses_known_ and impulses_since_ as they were before the last update
  // (save_state), and, after a restore, the step the first update repeats.
  bool prior_known_ = false;
  std::uint64_t prior_since_ = 0;
  bool restored_ = false;

  void sweep(const WorldView& world);
  /// The "contact_limit" event when this update began to leave pairs out
  /// (limits::contact_pairs).
  void report_left_out(const WorldView& world);
  /// The "crowded" event when parts begin to wait (Impl::settle_crowds).
  void report_waiting(const WorldView& world);
  /// ODE failed inside the update (see collisions.cpp): reported, not fatal.
  void engine_failed(const WorldView& world, const std::string& what);
};

}  // namespace alloy::rigid
