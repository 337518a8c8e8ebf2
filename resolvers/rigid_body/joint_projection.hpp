// Hinges that hold: a position projection after each ODE step (issue 12,
// items 3 and 5; docs/architecture.md, "Joint model").
//
// ODE solves a hinge at the velocity level, J(q_n) v_{n+1} = -(erp / h) C(q_n),
// and then moves the bodies along v_{n+1}. Two things go wrong. QuickStep's
// iterations do not converge on a small body at the end of a long lever or a
// light chain holding a heavy weight (a 1000:1 chain comes apart), and even an
// exact velocity solve lets the anchors drift apart at second order, which
// the error reduction then pulls back with a velocity bias that does work on
// the swing (a pendulum loses about 0.6 % of its energy a period).
//
// After the step this adds, per island of hinged bodies, the constraint
// impulse along the start-of-step Jacobian J(q_n)^T that puts every hinge's
// anchors back together at the new poses: the same impulse changes the
// velocities (dv = M^-1 J^T dmu) and the poses (h dv), as SHAKE does. The
// total hinge impulse of the step is then fixed by g(q_{n+1}) = (1 - erp)
// g(q_n) alone, whatever the velocity solve converged to: a constrained
// symplectic Euler step, with no energy drift. The small system
// (J M^-1 J^T) dmu = -r is solved directly (Eigen): once at the velocity
// level, then by Newton on the positions. Where Newton cannot converge (a
// light link's geometric stiffness too fast for the step) the island's step
// is redone along the end-of-step Jacobian, which is stable but damps.
//
// Only islands of planar bodies (the kit's) of at most kMaxHinges hinges are
// projected; the others keep ODE's hinges (docs/architecture.md says why).
// Contacts, joint limits and the friction motor of a hinge are ODE's alone:
// the projection adds impulses only along the hinge's own rows, which a limit
// or a motor about the axis does not touch.
#pragma once

#include <cstdint>
#include <vector>

#include "resolvers/rigid_body/ode_support.hpp"
#include "runtime/math.hpp"

namespace alloy::rigid {

class JointProjection {
 public:
  /// Islands with more hinges than this are left to ODE's error reduction
  /// alone: their dense solve (2 to 5 rows a hinge, up to 16 Newton passes)
  /// would cost more than the step.
  static constexpr std::size_t kMaxHinges = 16;

  /// Forgets every body and hinge (the world is being rebuilt).
  void clear();
  /// A body that some hinge holds; `planar` bodies move in the play area only
  /// (Plane2D: x, y and the turn about z), `fixed` ones do not yield (pinned,
  /// kinematic). Returns its index for add_hinge. Reads the body's mass now:
  /// call after dBodySetMass.
  std::int32_t add_body(dBodyID id, bool planar, bool fixed);
  /// A hinge between bodies b1 and b2 (indices from add_body; b2 = -1: the
  /// play area) at the world point `anchor` about the unit world `axis`, as
  /// the bodies stand now.
  /// Body 2 (or the play area) is held at `anchor2`, body 1 at `anchor`.
  void add_hinge(std::int32_t b1, std::int32_t b2, Vec3 anchor, Vec3 axis, Vec3 anchor2);
  /// Groups the hinges into islands (after the last add_hinge).
  void finish();
  /// Records the start-of-step poses (before the ODE step).
  void begin_step();
  /// Corrects poses and velocities after the ODE step of `h` seconds so that
  /// each hinge's error is (1 - erp) of what it was at begin_step: ~0 in
  /// steady running; an error made by an edit (a teleport) decays as ODE's
  /// error reduction would decay it.
  void project(double h, double erp);

  std::size_t hinge_count() const { return hinges_.size(); }
  /// Hinges left to ODE: in islands too large (kMaxHinges) or not planar.
  std::size_t unprojected_hinges() const { return unprojected_; }
  /// The largest hinge error left after the last project(), m or rad.
  double last_residual() const { return last_residual_; }
  /// The most Newton passes an island needed in the last project().
  int last_passes() const { return last_passes_; }
  /// Island steps redone along the end-of-step directions (SHAKE's Newton
  /// did not converge: a light body's geometric stiffness too fast for the
  /// step), since clear().
  std::uint64_t fallbacks() const { return fallbacks_; }

 private:
  struct Body {
    dBodyID id;
    bool planar, fixed;
    double inv_mass;
    double inv_inertia[9];  // body frame
    Vec3 x0;                // at begin_step
    Quat q0;
  };
  struct Hinge {
    std::int32_t b1, b2;
    Vec3 r1, r2;  // the anchor in each body's frame (r2: world point when b2 < 0)
    Vec3 a1;      // the axis in body 1's frame
    Vec3 u2, v2;  // two directions across the axis, in body 2's frame (world when b2 < 0)
  };
  struct Island {
    std::vector<std::uint32_t> hinges;
    std::vector<std::int32_t> bodies;  // the movable ones
  };
  /// The five errors of hinge `h` at the bodies' present poses (or at x0/q0).
  void errors(const Hinge& h, bool start, double out[5]) const;
  void project_island(const Island& island, double h, double erp);

  std::vector<Body> bodies_;
  std::vector<Hinge> hinges_;
  std::vector<Island> islands_;
  std::size_t unprojected_ = 0;
  double last_residual_ = 0;
  int last_passes_ = 0;
  std::uint64_t fallbacks_ = 0;
};

}  // namespace alloy::rigid
