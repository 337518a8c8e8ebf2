// The rigid body as the rest of alloy sees it, whichever engine simulates it
// (paper 3.2: rigid-body engines "can easily be replaced as better simulators
// become available"). Every plugin that provides `rigid_body` (ODE's
// RigidBodyResolver, and other engines) derives from RigidBodyEngine; the
// interactions that queue loads on the rigid body (gravity, magnetism, Lua
// mods' add_force) target this interface and never a particular engine.
//
// Loads are queued between advances and performed by the next advance, then
// cleared. A stale id throws AccessError; the slot form is the fast path for
// loops over a column's live members in the same phase.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "runtime/contact_set.hpp"
#include "runtime/math.hpp"
#include "runtime/object_id.hpp"
#include "runtime/stage.hpp"

namespace alloy::rigid {

class RigidBodyEngine : public Resolver {
 public:
  // --- interaction functions: queued, performed in the next advance -------------
  /// Force at the part's centre of mass, N.
  virtual void add_force(ObjectId part, Vec3 force) = 0;
  /// Force applied at a world point, N (adds the torque about the centre of mass).
  virtual void add_force(ObjectId part, Vec3 force, Vec3 point) = 0;
  /// Fast path for loops over a column's members (no liveness check: the slot
  /// comes from a live member list in the same phase).
  virtual void add_force(std::uint32_t slot, Vec3 force) = 0;
  /// Torque, N*m, world frame.
  virtual void add_torque(ObjectId part, Vec3 torque) = 0;
  /// A force at the part's centre of mass and a torque (world frame) with
  /// their rates of change, N/s and N*m/s (a derived set's d/dt along the
  /// present motion). An engine that substeps applies value + rate * t at
  /// time t into the window (a first-order hold); with one substep it is
  /// exactly the value.
  virtual void add_load(ObjectId part, Vec3 force, Vec3 torque, Vec3 force_rate,
                        Vec3 torque_rate) = 0;

  /// Uniform gravity: the weight m g of every part in `parts` (the members
  /// of the `gravity` column, each with a mass), g the same for all, for the
  /// next advance only (as a queued load). An engine may take it whole
  /// (Box2D's applies the weights itself, without a queued and screened
  /// record a part); it returns false when it cannot (then the caller queues
  /// add_force(slot, m g) on each part, the default).
  virtual bool add_uniform_gravity(Vec3 /*g*/, std::span<const std::uint32_t> /*parts*/) {
    return false;
  }

  // --- in-place queueing, for bindings that write load records themselves ------
  /// A queued load as the queue holds it (add_force, add_force at a point,
  /// add_torque). The Lua stages' prelude writes these in place (its FFI
  /// declaration mirrors this layout; lua/stage_abi.hpp asserts it).
  enum class Load : std::uint8_t { Force, ForceAtPoint, Torque };
  struct LoadCommand {
    std::uint32_t slot;
    std::uint32_t generation;  // 0: unchecked (slot fast path)
    Vec3 value, point;
    Load kind;
  };
  /// Room for `n` records after those queued when the room was first opened,
  /// to be filled by the caller: not cleared (the queue reuses its storage from
  /// step to step), so every record needs its slot, generation, value and
  /// kind, and its point for ForceAtPoint. Asking again for more keeps the
  /// records written so far, though the span moves. The generation of each
  /// record must be its object's, as add_force(ObjectId) would take it.
  /// close_loads(used) keeps the first `used` of them.
  virtual std::span<LoadCommand> open_loads(std::size_t n) = 0;
  virtual void close_loads(std::size_t used) = 0;

  // --- published state ------------------------------------------------------------
  /// Declares that the caller reads contact impulses: from the next advance
  /// on, and while the returned demand (or any other) is held, advances
  /// compute them.
  virtual ImpulseDemand demand_impulses() const = 0;

  // --- introspection (tests, profiling) --------------------------------------------
  /// The engine's bodies (one per assembly of glued parts).
  virtual std::size_t body_count() const = 0;
  /// The engine's joints made from joint objects.
  virtual std::size_t joint_count() const = 0;
  /// Bodies being simulated: not asleep and not kinematic.
  virtual std::size_t awake_count() const = 0;
};

}  // namespace alloy::rigid
