// Where a hinge holds each of its parts, for both rigid-body engines (ODE's
// rigid_body and rigid_body.box2d).
//
// A hinge is defined by a point fixed in each part: `anchor_a` in part a's
// frame and `anchor_b` in part b's (a world point for the play area). The first build takes both
// from the authored world `anchor` at the parts' poses then, and writes them. Every later build (a
// swap of engine, a restore, a rebuild after an edit) makes the joint from these two points, not
// from `anchor` at the present poses: a hinge stretched by the solver at that moment (Box2D's, up
// to 0.2 mm in a swinging double pendulum) would otherwise have its stretch baked into the new
// joint, and a swap after swap ratchets the parts apart for good (adv15 F15: 1.77 mm after 30
// swaps). `anchor` stays the world pivot as the running engine reports it (on part a); moving it by
// an edit (further than kEditedAnchor from where part a holds it) redefines both points from it at
// the poses of that moment.
#pragma once

#include <algorithm>
#include <cmath>

#include "runtime/math.hpp"

namespace alloy::rigid {

/// How far the world `anchor` may lie from part a's point before it counts
/// as edited, m per metre of distance from the origin (at least 1 um): Box2D
/// reports the anchor in single precision (about 1e-7 of the coordinate).
inline constexpr double kEditedAnchor = 1e-6;

/// The rotation undoing q (q unit).
inline Quat unturned(Quat q) {
  return {q.w, -q.x, -q.y, -q.z};
}

struct HingeAnchors {
  Vec3 local_a;          ///< in part a's frame; a world point when a is the play area
  Vec3 local_b;          ///< in part b's frame; a world point when b is the play area
  Vec3 on_a;             ///< world point where part a (or the play area) holds it
  Vec3 on_b;             ///< world point where part b (or the play area) holds it
  bool defined = false;  ///< local_a and local_b were made now: write them back
};

/// The hinge's two points at the parts' present poses. `anchor` (may be
/// null: the default pivot) is the world pivot property, `local_a` and
/// `local_b` (null when absent) the stored points. Part a (b) is the play
/// area when `has_a` (`has_b`) is false.
inline HingeAnchors hinge_anchors(const Vec3* anchor, Vec3 default_pivot, const Vec3* local_a,
                                  const Vec3* local_b, bool has_a, Vec3 xa, Quat qa, bool has_b,
                                  Vec3 xb, Quat qb) {
  HingeAnchors h;
  const Vec3 pivot = anchor ? *anchor : default_pivot;
  if (local_a && local_b) {
    h.local_a = *local_a, h.local_b = *local_b;
    h.on_a = has_a ? xa + rotate(qa, h.local_a) : h.local_a;
    h.on_b = has_b ? xb + rotate(qb, h.local_b) : h.local_b;
    const double tol =
        kEditedAnchor * std::max({1.0, std::abs(pivot.x), std::abs(pivot.y), std::abs(pivot.z)});
    auto near = [&](Vec3 p) {
      const Vec3 d = p - pivot;
      return std::abs(d.x) <= tol && std::abs(d.y) <= tol && std::abs(d.z) <= tol;
    };
    // Either side: an engine reports where part a holds the pivot, but a
    // scene may have written the other.
    if (!anchor || near(h.on_a) || near(h.on_b)) return h;
  }
  h.defined = true;
  h.on_a = h.on_b = pivot;
  h.local_a = has_a ? rotate(unturned(qa), pivot - xa) : pivot;
  h.local_b = has_b ? rotate(unturned(qb), pivot - xb) : pivot;
  return h;
}

}  // namespace alloy::rigid
