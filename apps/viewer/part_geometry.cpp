#include "apps/viewer/part_geometry.hpp"

#include <algorithm>
#include <limits>
#include <numbers>

namespace alloy::viewer {

namespace {

std::optional<std::string> enum_name(const World& w, ObjectId id, const char* name) {
  const auto pid = w.properties().find(name);
  if (!pid || !w.store().has(id, *pid)) return std::nullopt;
  const PropertyValue v = w.store().get(id, *pid);
  const EnumValue* e = std::get_if<EnumValue>(&v);
  const auto& values = w.properties().def(*pid).enum_values;
  if (!e || e->index < 0 || std::size_t(e->index) >= values.size()) return std::nullopt;
  return values[std::size_t(e->index)];
}

}  // namespace

double Part2D::half_extent_x() const {
  switch (shape) {
    case Shape2D::Box:
      return half.x;
    case Shape2D::Disk:
      return radius;
    case Shape2D::Capsule:
      return half_length + radius;
  }
  return 0;
}

std::optional<Part2D> read_part(const World& world, ObjectId id) {
  if (!world.store().alive(id)) return std::nullopt;
  if (world.value<EnumValue>(id, "joint")) return std::nullopt;
  const auto shape = enum_name(world, id, "shape");
  const auto position = world.value<Vec3>(id, "position");
  if (!shape || !position) return std::nullopt;
  Part2D p;
  p.id = id;
  p.centre = xy(*position);
  if (auto q = world.value<Quat>(id, "orientation")) p.angle = angle_z(*q);
  p.is_static = world.value<bool>(id, "static").value_or(false);
  p.pinned = world.value<bool>(id, "pinned").value_or(false);
  if (*shape == "box") {
    const auto size = world.value<Vec3>(id, "size");
    if (!size) return std::nullopt;
    p.shape = Shape2D::Box;
    p.half = {size->x / 2, size->y / 2};
  } else if (*shape == "sphere" || *shape == "cylinder") {
    // A cylinder's axis is the part's z: seen along it, a disk.
    p.shape = Shape2D::Disk;
    p.radius = world.value<double>(id, "radius").value_or(0);
  } else if (*shape == "capsule") {
    p.shape = Shape2D::Capsule;
    p.radius = world.value<double>(id, "radius").value_or(0);
    p.half_length = world.value<double>(id, "length").value_or(0) / 2;
  } else {
    return std::nullopt;
  }
  if (!std::isfinite(p.centre.x) || !std::isfinite(p.centre.y) || !std::isfinite(p.angle))
    return std::nullopt;
  return p;
}

std::vector<Part2D> read_parts(const World& world) {
  std::vector<Part2D> out;
  const PropertyStore& store = world.store();
  for (std::uint32_t s = 0; s < store.slot_count(); ++s)
    if (const ObjectId id = store.id_at(s))
      if (auto p = read_part(world, id)) out.push_back(*p);
  return out;
}

std::vector<ObjectId> carriers(const PropertyStore& store, PropertyId property) {
  std::vector<ObjectId> out;
  for (std::uint32_t s = 0; s < store.slot_count(); ++s)
    if (const ObjectId id = store.id_at(s); id && store.has(id, property)) out.push_back(id);
  return out;
}

std::optional<SpringEnds> spring_ends(const World& world, ObjectId id) {
  const auto a = world.value<ObjectId>(id, "spring_a");
  if (!a || !world.store().alive(*a) || !world.value<double>(id, "spring_stiffness")) return {};
  auto end = [&](std::optional<ObjectId> part, const char* anchor) {
    const Vec3 local = world.value<Vec3>(id, anchor).value_or(Vec3{});
    if (!part || !world.store().alive(*part)) return xy(local);
    const Vec3 centre = world.value<Vec3>(*part, "position").value_or(Vec3{});
    const Quat q = world.value<Quat>(*part, "orientation").value_or(Quat{});
    return xy(centre + rotate(q, local));
  };
  return SpringEnds{end(a, "spring_anchor_a"),
                    end(world.value<ObjectId>(id, "spring_b"), "spring_anchor_b")};
}

double segment_distance(Vec2 point, Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double len2 = dot(d, d);
  const double t = len2 > 0 ? std::clamp(dot(point - a, d) / len2, 0.0, 1.0) : 0.0;
  return length(point - (a + d * t));
}

std::vector<Vec2> outline(const Part2D& p, int segments) {
  std::vector<Vec2> local;
  constexpr double pi = std::numbers::pi;
  switch (p.shape) {
    case Shape2D::Box:
      local = {{-p.half.x, -p.half.y},
               {p.half.x, -p.half.y},
               {p.half.x, p.half.y},
               {-p.half.x, p.half.y}};
      break;
    case Shape2D::Disk:
      for (int i = 0; i < segments; ++i) {
        const double a = 2 * pi * i / segments;
        local.push_back({p.radius * std::cos(a), p.radius * std::sin(a)});
      }
      break;
    case Shape2D::Capsule: {
      const int half_segments = std::max(2, segments / 2);
      for (int i = 0; i <= half_segments; ++i) {  // right end, -90 to +90 degrees
        const double a = -pi / 2 + pi * i / half_segments;
        local.push_back({p.half_length + p.radius * std::cos(a), p.radius * std::sin(a)});
      }
      for (int i = 0; i <= half_segments; ++i) {  // left end, +90 to 270 degrees
        const double a = pi / 2 + pi * i / half_segments;
        local.push_back({-p.half_length + p.radius * std::cos(a), p.radius * std::sin(a)});
      }
      break;
    }
  }
  for (Vec2& v : local) v = p.to_world(v);
  return local;
}

bool contains(const Part2D& p, Vec2 point, double margin) {
  const Vec2 l = p.to_local(point);
  switch (p.shape) {
    case Shape2D::Box:
      return std::abs(l.x) <= p.half.x + margin && std::abs(l.y) <= p.half.y + margin;
    case Shape2D::Disk:
      return length(l) <= p.radius + margin;
    case Shape2D::Capsule: {
      const double cx = std::clamp(l.x, -p.half_length, p.half_length);
      return length(Vec2{l.x - cx, l.y}) <= p.radius + margin;
    }
  }
  return false;
}

namespace {
// Projection interval of a polygon on an axis.
void project(const std::vector<Vec2>& poly, Vec2 axis, double& lo, double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (Vec2 v : poly) {
    const double d = dot(v, axis);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
}
}  // namespace

double overlap_depth(const Part2D& a, const Part2D& b) {
  const std::vector<Vec2> pa = outline(a, 24), pb = outline(b, 24);
  double best = std::numeric_limits<double>::infinity();
  for (const auto* poly : {&pa, &pb}) {
    for (std::size_t i = 0; i < poly->size(); ++i) {
      const Vec2 e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      const double len = length(e);
      if (len < 1e-12) continue;
      const Vec2 axis{-e.y / len, e.x / len};
      double alo, ahi, blo, bhi;
      project(pa, axis, alo, ahi);
      project(pb, axis, blo, bhi);
      const double o = std::min(ahi, bhi) - std::max(alo, blo);
      if (o <= 0) return o;
      best = std::min(best, o);
    }
  }
  return best;
}

double area(const Part2D& p) {
  switch (p.shape) {
    case Shape2D::Box:
      return 4 * p.half.x * p.half.y;
    case Shape2D::Disk:
      return std::numbers::pi * p.radius * p.radius;
    case Shape2D::Capsule:
      return std::numbers::pi * p.radius * p.radius + 4 * p.half_length * p.radius;
  }
  return 0;
}

}  // namespace alloy::viewer
