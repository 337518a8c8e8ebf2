// The play area seen from above: each part as a 2D shape (a rotated box, a
// disk, a capsule) read from its rigid-body properties, with the geometry the
// viewer needs to draw it, hit it with the mouse and tell whether a dropped
// part lies inside another. Pure functions of the world: no SDL, no ImGui.
#pragma once

#include <cmath>
#include <optional>
#include <vector>

#include "runtime/world.hpp"

namespace alloy::viewer {

struct Vec2 {
  double x = 0, y = 0;
  friend constexpr Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
  friend constexpr Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
  friend constexpr Vec2 operator*(Vec2 a, double s) { return {a.x * s, a.y * s}; }
  friend constexpr Vec2 operator*(double s, Vec2 a) { return {a.x * s, a.y * s}; }
  friend constexpr bool operator==(Vec2, Vec2) = default;
};
constexpr double dot(Vec2 a, Vec2 b) {
  return a.x * b.x + a.y * b.y;
}
inline double length(Vec2 a) {
  return std::sqrt(dot(a, a));
}
inline Vec2 rotate(Vec2 v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x - s * v.y, s * v.x + c * v.y};
}
inline Vec2 xy(Vec3 v) {
  return {v.x, v.y};
}

enum class Shape2D { Box, Disk, Capsule };

/// One part as drawn: its outline in the play area and how it is held.
struct Part2D {
  ObjectId id;
  Shape2D shape = Shape2D::Box;
  Vec2 centre;             ///< position, m
  double angle = 0;        ///< about +z, rad
  Vec2 half;               ///< box: half extents along the part's x and y, m
  double radius = 0;       ///< disk and capsule, m
  double half_length = 0;  ///< capsule: half the straight part, along the part's x, m
  bool is_static = false;
  bool pinned = false;

  /// A point of the part's frame in the play area.
  Vec2 to_world(Vec2 local) const { return centre + rotate(local, angle); }
  Vec2 to_local(Vec2 world) const { return rotate(world - centre, -angle); }
  /// Half the extent along the part's own x axis (where terminals and poles lie).
  double half_extent_x() const;
};

/// The part's 2D shape, or nullopt if the object is not a body (a joint, a
/// wire) or lacks what its shape needs.
std::optional<Part2D> read_part(const World& world, ObjectId id);
/// Every part, in slot order.
std::vector<Part2D> read_parts(const World& world);

/// The live objects that carry `property`, in slot order. (Not the column's
/// member list: the world refreshes that between phases, and the viewer
/// reads right after its own edits.)
std::vector<ObjectId> carriers(const PropertyStore& store, PropertyId property);

/// A spring's two ends in the play area (its anchors carried by its parts'
/// poses; an end with no part is a point of the board), or nullopt if `id`
/// is not a spring or its first part is gone.
struct SpringEnds {
  Vec2 a, b;
};
std::optional<SpringEnds> spring_ends(const World& world, ObjectId id);
/// Distance from `point` to the segment from `a` to `b`, m.
double segment_distance(Vec2 point, Vec2 a, Vec2 b);

/// Convex outline, counter-clockwise; disks and capsule ends with `segments`
/// points per full turn.
std::vector<Vec2> outline(const Part2D& p, int segments = 40);
/// Whether `point` lies inside the part, grown by `margin` m.
bool contains(const Part2D& p, Vec2 point, double margin = 0);
/// How deep two parts overlap, m (the smallest push that separates their
/// outlines, separating-axis test); 0 or less when they do not.
double overlap_depth(const Part2D& a, const Part2D& b);
/// Area of the part's outline, m^2 (picking prefers the smaller of two parts).
double area(const Part2D& p);

}  // namespace alloy::viewer
