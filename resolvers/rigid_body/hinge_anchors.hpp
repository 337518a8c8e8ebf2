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
// the poses of that moment, and so does part b's point lying further than kStretchedHinge from it
// (a copy pasted elsewhere keeps the original's points until then).
#pragma once

#include <algorithm>
#include <cmath>

#include "runtime/math.hpp"

namespace alloy::rigid {

/// How far the world `anchor` may lie from part a's point before it counts
/// as edited, m per metre of distance from the origin (at least 1 um): Box2D
/// reports the anchor in single precision (about 1e-7 of the coordinate).
inline constexpr double kEditedAnchor = 1e-6;

/// How far part b's point may lie from the pivot while the hinge still counts
/// as the one defined, m: a solver's stretch (Box2D's swinging double
/// pendulum: 0.2 mm) is far below it, an edit or a paste far above.
inline constexpr double kStretchedHinge = 0.005;

/// How far a stored point may lie from the pivot and still be the pivot, per
/// metre from the origin: rounding in the last bits (ODE reports the pivot in
/// double precision), far below any stretch and below Box2D's single
/// precision, whose report must not move the stored points.
inline constexpr double kSameAnchor = 1e-12;

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
    const double scale = std::max({1.0, std::abs(pivot.x), std::abs(pivot.y), std::abs(pivot.z)});
    const double tol = kEditedAnchor * scale;
    auto near = [&](Vec3 p) {
      const Vec3 d = p - pivot;
      return std::abs(d.x) <= tol && std::abs(d.y) <= tol && std::abs(d.z) <= tol;
    };
    if (!anchor) return h;
    // Kept while `anchor` is where part a holds it (an engine reports it
    // there) and part b holds it no further than a solver's stretch: a pivot
    // moved by an edit, or a pasted copy's play-area point left at the
    // original's pivot, redefines both.
    const Vec3 d = h.on_b - pivot;
    if (near(h.on_a) && dot(d, d) <= kStretchedHinge * kStretchedHinge) {
      // A point that is the pivot to rounding (a part's pose rewritten by an
      // ulp when glue rebuilt its body) is the pivot: a world edited in place
      // and the same world saved and loaded build the same joint, to the bit.
      const double same = kSameAnchor * scale;
      auto same_point = [&](Vec3 p) {
        const Vec3 e = p - pivot;
        return std::abs(e.x) <= same && std::abs(e.y) <= same && std::abs(e.z) <= same;
      };
      if (same_point(h.on_a)) h.on_a = pivot;
      if (same_point(h.on_b)) h.on_b = pivot;
      return h;
    }
  }
  h.defined = true;
  h.local_a = has_a ? rotate(unturned(qa), pivot - xa) : pivot;
  h.local_b = has_b ? rotate(unturned(qb), pivot - xb) : pivot;
  h.on_a = h.on_b = pivot;
  return h;
}

}  // namespace alloy::rigid
