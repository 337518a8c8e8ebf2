#include "lua/value_rules.hpp"

#include <cmath>
#include <sstream>

namespace alloy::lua {

namespace {

enum class Rule { Positive, NonNegative, UnitInterval, PositiveComponents, NonZero };

struct ValueRule {
  const char* property;
  Rule rule;
};

// Ideally each owner would declare these with its property types (an
// exclusive minimum and a maximum on PropertyDef); until then they live here,
// for the names of the rigid-body contract.
constexpr ValueRule kRules[] = {
    {"mass", Rule::Positive},
    {"density", Rule::Positive},
    {"radius", Rule::Positive},
    {"length", Rule::NonNegative},
    {"size", Rule::PositiveComponents},
    {"friction", Rule::NonNegative},
    {"restitution", Rule::UnitInterval},
    {"linear_damping", Rule::NonNegative},
    {"angular_damping", Rule::NonNegative},
    {"joint_friction", Rule::NonNegative},
    {"axis", Rule::NonZero},
    {"orientation", Rule::NonZero},
};

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void fail(const PropertyDef& def, const std::string& what) {
  throw InputError("'" + def.name + "' " + what);
}

void check_finite(const PropertyDef& def, const PropertyValue& value) {
  if (const double* d = std::get_if<double>(&value); d && !std::isfinite(*d))
    fail(def, "must be a finite number, got " + num(*d));
  if (const Vec3* v = std::get_if<Vec3>(&value); v && !is_finite(*v))
    fail(def, "must have finite components, got {" + num(v->x) + ", " + num(v->y) + ", " +
                  num(v->z) + "}");
  if (const Quat* q = std::get_if<Quat>(&value); q && !is_finite(*q))
    fail(def, "must have finite components");
}

double number_of(const PropertyValue& v) {
  if (const double* d = std::get_if<double>(&v)) return *d;
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return double(*i);
  return 0;
}

bool has(const World& w, ObjectId id, const char* property) {
  auto p = w.properties().find(property);
  return p && w.store().has(id, *p);
}

template <class T>
std::optional<T> get(const World& w, ObjectId id, const char* property) {
  if (!has(w, id, property)) return std::nullopt;
  const PropertyValue v = w.get(id, property);
  if (const T* t = std::get_if<T>(&v)) return *t;
  return std::nullopt;
}

std::string enum_name(const World& w, ObjectId id, const char* property) {
  auto e = get<EnumValue>(w, id, property);
  if (!e) return "";
  const auto& values = w.properties().def(*w.properties().find(property)).enum_values;
  return e->index >= 0 && std::size_t(e->index) < values.size() ? values[e->index] : "";
}

}  // namespace

void check_value(const PropertyDef& def, const PropertyValue& value) {
  check_finite(def, value);
  for (const ValueRule& r : kRules) {
    if (def.name != r.property) continue;
    switch (r.rule) {
      case Rule::Positive:
        if (!(number_of(value) > 0))
          fail(def, "must be greater than 0, got " + num(number_of(value)));
        break;
      case Rule::NonNegative:
        if (!(number_of(value) >= 0))
          fail(def, "must not be negative, got " + num(number_of(value)));
        break;
      case Rule::UnitInterval:
        if (!(number_of(value) >= 0 && number_of(value) <= 1))
          fail(def, "must lie between 0 and 1, got " + num(number_of(value)));
        break;
      case Rule::PositiveComponents:
        if (const Vec3* v = std::get_if<Vec3>(&value); v && !(v->x > 0 && v->y > 0 && v->z > 0))
          fail(def, "must be positive in every direction, got {" + num(v->x) + ", " + num(v->y) +
                        ", " + num(v->z) + "}");
        break;
      case Rule::NonZero:
        if (const Vec3* v = std::get_if<Vec3>(&value); v && length(*v) == 0)
          fail(def, "must not be the zero vector");
        if (const Quat* q = std::get_if<Quat>(&value);
            q && q->w == 0 && q->x == 0 && q->y == 0 && q->z == 0)
          fail(def, "must not be the zero quaternion");
        break;
    }
  }
}

void check_object(const World& w, ObjectId id) {
  if (has(w, id, "joint")) {
    auto a = get<ObjectId>(w, id, "body_a");
    if (!a || a->is_null()) throw InputError("a joint needs 'body_a', the body it holds");
    auto b = get<ObjectId>(w, id, "body_b");
    if (b && *b == *a) throw InputError("a joint cannot join '" + w.describe(*a) + "' to itself");
    for (ObjectId body : {*a, b.value_or(ObjectId{})}) {
      if (body.is_null()) continue;
      if (has(w, body, "joint"))
        throw InputError("a joint can only hold bodies, and '" + w.describe(body) + "' is a joint");
      if (!has(w, body, "shape"))
        throw InputError("a joint can only hold bodies, and '" + w.describe(body) +
                         "' has no shape");
    }
    auto lo = get<double>(w, id, "limit_low");
    auto hi = get<double>(w, id, "limit_high");
    if (lo && hi && *lo > *hi)
      throw InputError("'limit_low' (" + num(*lo) + ") is above 'limit_high' (" + num(*hi) + ")");
    return;
  }
  const std::string shape = enum_name(w, id, "shape");
  if (shape.empty()) return;
  if (shape == "box" && !has(w, id, "size"))
    throw InputError("a box needs a 'size' (full extents {x, y, z})");
  if (shape == "sphere" && !has(w, id, "radius")) throw InputError("a sphere needs a 'radius'");
  if (shape == "capsule" && !(has(w, id, "radius") && has(w, id, "length")))
    throw InputError("a capsule needs a 'radius' and a 'length'");
  const bool is_static = get<bool>(w, id, "static").value_or(false);
  if (!is_static && !has(w, id, "mass") && !has(w, id, "density"))
    throw InputError(
        "a moving body needs a 'mass' (or 'density'); give one, or make it static = true");
}

}  // namespace alloy::lua
