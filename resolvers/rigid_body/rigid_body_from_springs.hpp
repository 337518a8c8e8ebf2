// Interaction rigid_body <- springs: a spring with a damper (a dashpot in
// parallel) between two points, one on each of two parts, or one on a part and
// one fixed to the board. Every step it queues, through the rigid body's public
// API (add_force at a point), the force
//
//   F = -(k (L - L0) + c dL/dt) n        on part a at its anchor, -F on part b,
//
// where L is the anchors' distance, n the unit vector from b's anchor to a's,
// and dL/dt the anchors' relative speed along n. With `spring_slack` true it is
// a string: the force is a pull only, k (L - L0) + c dL/dt held at 0 or more,
// and nothing at all while L <= L0. Nothing here knows the rigid
// body's engine, so it works on any resolver that takes forces at points.
//
// The force is explicit: it is worked out from the state at the start of the
// step and held through it, and the rigid body's semi-implicit Euler then
// moves the parts. For one mass on a spring that scheme is stable while
// (h w)^2 + 2 h c / m < 4 (w = sqrt(k / m), h the step). A hinged or turning
// part moves under a force at a point like a fraction of its mass (a rod
// hinged at one end and pulled at its tip: a third), so the springs keep
// (h w)^2 + 2 h c / m <= 1, with m the reduced mass of the two parts (a
// static or pinned part counts as infinitely heavy). A spring past that is
// refused, by name, when it is made or edited (World::check) and when a step
// would use it: the message gives the figures and what to change.
//
// Energy books (runtime/energy_ledger.hpp): each apply's force is kept with
// where its ends were; the rigid body's next advance moves the parts under
// it, and the apply after that advance (in the same step, before the ledger's
// report) closes its books from the ends' moves:
//   store     "spring energy": sum of k (L - L0)^2 / 2 now, J
//   sink      "damper heat": the damper's force times the stretch it worked
//             along, c (dL/dt) n . (da - db), J
//   sink      "integration (explicit spring force)": what the held force gave
//             that the store did not lose, -(W_elastic + change of the store);
//             it shrinks with the step (negative: energy the scheme made)
//   transfer  "springs": minus the work the forces did on the parts along the
//             ends' moves; the rigid body books the other side under the same
//             name, so the ledger shows how far the two measures are apart.
//
// Contract:
//   reads    position, orientation, velocity, angular_velocity, mass, static,
//            pinned, spring_* (below; spring_slack optional)
//   target   rigid_body (add_force at a world point)
//   needs    spring_stiffness
// The spring keeps no physical state of its own: everything is in its
// properties. The books' last step (forces and ends) is bookkeeping only; a
// restore makes the stage afresh, so the step before a restore is not booked.
#pragma once

#include <string>
#include <vector>

#include "runtime/plugin_registry.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::rigid {

class RigidBodyEngine;

/// The stability figure of a spring, (h w)^2 + 2 h c / m, and what it was
/// worked out from; `mass` is the reduced mass (infinite: both parts fixed).
struct SpringStability {
  double figure = 0;     ///< (h w)^2 + 2 h c / m
  double mass = 0;       ///< reduced mass of the two parts, kg
  double stiffness = 0;  ///< N/m
  double damping = 0;    ///< N s/m
  double dt = 0;         ///< s
};
/// The largest figure the springs accept (the explicit scheme's own bound is 4).
inline constexpr double kSpringStabilityLimit = 1.0;

/// Works out the figure for the spring `id` of `world` (its parts' present masses).
SpringStability spring_stability(const World& world, ObjectId id);

/// The properties a spring object carries.
std::vector<PropertyDef> spring_properties();

class RigidBodyFromSprings final : public Interaction {
 public:
  static constexpr const char* kName = "rigid_body_from_springs";
  explicit RigidBodyFromSprings(RigidBodyEngine& target) : target_(target) {}
  void apply(const WorldView& world) override;
  void report_energy(const WorldView& world, EnergyReport& out) override;

 private:
  /// One spring's force over the last step and where its ends were.
  struct Held {
    ObjectId spring, a, b;                       ///< the spring and its parts (b null: the board)
    Vec3 anchor_a, anchor_b;                     ///< the ends in the parts' frames (no part: world)
    Vec3 at_a, at_b;                             ///< the ends' world points at the step's start, m
    Vec3 force;                                  ///< the force on a (on b: minus it), N
    double elastic = 0;                          ///< k (L - L0) at the start (tension > 0), N
    double damper = 0;                           ///< c dL/dt at the start, N
    double stiffness = 0, rest = 0, length = 0;  ///< k, L0, L at the start
    bool slack = false;                          ///< a string: it stores nothing unstretched
  };
  /// Books the held forces along their ends' moves since they were worked out.
  void close_books(const WorldView& world);

  RigidBodyEngine& target_;
  std::vector<Held> held_;
  double given_ = 0;        ///< work done on the parts since the last report, J
  double heat_ = 0;         ///< damper heat since the last report, J
  double integration_ = 0;  ///< energy the explicit force did not take from the store, J
};

/// Registers rigid_body_from_springs (after the rigid body's plugins).
void register_rigid_body_from_springs(PluginRegistry& registry);

}  // namespace alloy::rigid
