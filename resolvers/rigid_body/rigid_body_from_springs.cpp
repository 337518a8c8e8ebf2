#include "resolvers/rigid_body/rigid_body_from_springs.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include "resolvers/rigid_body/engine.hpp"
#include "runtime/error.hpp"

namespace alloy::rigid {

namespace {

constexpr double kInfinite = std::numeric_limits<double>::infinity();

/// A part's mass as a spring sees it: a static or pinned part, or one the
/// rigid body has not given a mass, does not move (infinitely heavy).
double moving_mass(bool fixed, const double* mass) {
  if (fixed || !mass || !(*mass > 0)) return kInfinite;
  return *mass;
}

SpringStability stability(double ma, double mb, double k, double c, double h) {
  SpringStability s;
  s.stiffness = k, s.damping = c, s.dt = h;
  const double inv = (std::isinf(ma) ? 0 : 1 / ma) + (std::isinf(mb) ? 0 : 1 / mb);
  s.mass = inv > 0 ? 1 / inv : kInfinite;
  s.figure = inv > 0 ? (h * h * k + 2 * h * c) * inv : 0;
  return s;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

/// Throws when the spring is past the limit: the message names it and gives
/// the figures and the ways out.
void refuse_if_unstable(const SpringStability& s, const std::string& name) {
  if (s.figure <= kSpringStabilityLimit) return;
  const double hw = s.dt * std::sqrt(s.stiffness / s.mass);
  throw InputError(
      ErrorLocation{"", 0, name},
      "spring '" + name + "' is too stiff for the step: (h w)^2 + 2 h c / m = " + num(s.figure) +
          " (h = " + num(s.dt) + " s, k = " + num(s.stiffness) + " N/m, c = " + num(s.damping) +
          " N s/m, m = " + num(s.mass) + " kg, the two parts' reduced mass, h w = " + num(hw) +
          "); a spring is worked out explicitly and is kept under " + num(kSpringStabilityLimit) +
          ": lower its stiffness or damping, make its parts heavier, or take a smaller step "
          "(the world's dt)");
}

}  // namespace

std::vector<PropertyDef> spring_properties() {
  return {
      {.name = "spring_a", .kind = PropertyKind::Ref, .doc = "spring: the first part it pulls"},
      {.name = "spring_b",
       .kind = PropertyKind::Ref,
       .doc = "spring: the second part; absent or null: the board"},
      {.name = "spring_anchor_a",
       .kind = PropertyKind::Vec3,
       .unit = "m",
       .doc = "spring: its end on part a, in a's frame from a's centre of mass"},
      {.name = "spring_anchor_b",
       .kind = PropertyKind::Vec3,
       .unit = "m",
       .doc = "spring: its end on part b, in b's frame from b's centre; with no part b, a point "
              "of the board (world frame)"},
      {.name = "spring_stiffness",
       .kind = PropertyKind::Number,
       .unit = "N/m",
       .doc = "spring: force per metre of stretch (k)",
       .min = 0.0},
      {.name = "spring_rest_length",
       .kind = PropertyKind::Number,
       .unit = "m",
       .doc = "spring: its length with no force (L0)",
       .min = 0.0},
      {.name = "spring_damping",
       .kind = PropertyKind::Number,
       .unit = "N s/m",
       .doc = "spring: the damper's force per m/s of stretching (c)",
       .min = 0.0},
  };
}

SpringStability spring_stability(const World& w, ObjectId id) {
  auto mass_of = [&](std::optional<ObjectId> part) {
    if (!part || part->is_null() || !w.store().alive(*part)) return kInfinite;
    const bool fixed = w.value<bool>(*part, "static").value_or(false) ||
                       w.value<bool>(*part, "pinned").value_or(false);
    const auto m = w.value<double>(*part, "mass");
    return moving_mass(fixed, m ? &*m : nullptr);
  };
  return stability(mass_of(w.value<ObjectId>(id, "spring_a")),
                   mass_of(w.value<ObjectId>(id, "spring_b")),
                   w.value<double>(id, "spring_stiffness").value_or(0),
                   w.value<double>(id, "spring_damping").value_or(0), w.dt());
}

void RigidBodyFromSprings::apply(const WorldView& world) {
  const auto stiffness = world.column<double>("spring_stiffness");
  const auto part_a = world.column<ObjectId>("spring_a");
  const auto part_b = world.column<ObjectId>("spring_b");
  const auto anchor_a = world.column<Vec3>("spring_anchor_a");
  const auto anchor_b = world.column<Vec3>("spring_anchor_b");
  const auto rest = world.column<double>("spring_rest_length");
  const auto damping = world.column<double>("spring_damping");
  const auto position = world.column<Vec3>("position");
  const auto orientation = world.column<Quat>("orientation");
  const auto velocity = world.column<Vec3>("velocity");
  const auto spin = world.column<Vec3>("angular_velocity");
  const auto mass = world.column<double>("mass");
  // Flags are stored as bytes (no vector<bool>).
  const auto is_static = world.column<std::uint8_t>("static");
  const auto pinned = world.column<std::uint8_t>("pinned");
  const PropertyStore& store = world.store();

  // One end: its world point and velocity, and the part's mass as the spring
  // sees it. No part: a fixed point of the board.
  struct End {
    ObjectId part;
    Vec3 at, v;
    double mass = kInfinite;
  };
  auto end_of = [&](ObjectId part, Vec3 anchor) {
    End e;
    if (part.is_null() || !store.alive(part) || !position.has(part.index)) {
      e.at = anchor;
      return e;
    }
    const std::uint32_t s = part.index;
    const Vec3 r = orientation.has(s) ? rotate(orientation[s], anchor) : anchor;
    e.part = part;
    e.at = position[s] + r;
    e.v = velocity.value_or(s, {}) + cross(spin.value_or(s, {}), r);
    const bool fixed = is_static.value_or(s, 0) != 0 || pinned.value_or(s, 0) != 0;
    e.mass = moving_mass(fixed, mass.has(s) ? &mass[s] : nullptr);
    return e;
  };

  for (std::uint32_t s : stiffness.members()) {
    const ObjectId a_id = part_a.value_or(s, ObjectId{});
    if (a_id.is_null()) continue;  // a spring not yet fixed to anything
    const End a = end_of(a_id, anchor_a.value_or(s, {}));
    const End b = end_of(part_b.value_or(s, ObjectId{}), anchor_b.value_or(s, {}));
    if (a.part.is_null() && b.part.is_null()) continue;
    const double k = stiffness[s], c = damping.value_or(s, 0);
    refuse_if_unstable(stability(a.mass, b.mass, k, c, world.dt()), store.describe(store.id_at(s)));
    const Vec3 d = a.at - b.at;
    const double L = length(d);
    // Both ends at one point: no direction to pull along (a rest length of
    // zero holds them there; any other pushes them apart once they move).
    if (!(L > 1e-12)) continue;
    const Vec3 n = d / L;
    const double tension = k * (L - rest.value_or(s, 0)) + c * dot(a.v - b.v, n);
    const Vec3 f = -tension * n;
    if (!a.part.is_null()) target_.add_force(a.part, f, a.at);
    if (!b.part.is_null()) target_.add_force(b.part, -f, b.at);
  }
}

void register_rigid_body_from_springs(PluginRegistry& registry) {
  PluginDef def;
  def.info = {.name = RigidBodyFromSprings::kName,
              .kind = StageKind::Interaction,
              .reads = {"position", "orientation", "velocity", "angular_velocity", "mass", "static",
                        "pinned", "spring_a", "spring_b", "spring_anchor_a", "spring_anchor_b",
                        "spring_stiffness", "spring_rest_length", "spring_damping"},
              .needs = {"spring_stiffness"},
              .target = "rigid_body",
              .doc = "springs with dampers between two parts (or a part and the board)"};
  def.properties = spring_properties();
  def.check = [](const World& w, ObjectId id) {
    if (!w.store().has(id, w.properties().id("spring_stiffness"))) return;
    const auto a = w.value<ObjectId>(id, "spring_a");
    if (!a || a->is_null()) throw InputError("a spring needs 'spring_a', the part it pulls");
    const auto b = w.value<ObjectId>(id, "spring_b");
    if (b && *b == *a) throw InputError("a spring cannot join '" + w.describe(*a) + "' to itself");
    refuse_if_unstable(spring_stability(w, id), w.describe(id));
  };
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known(RigidBodyFromSprings::kName, {});
    return std::make_unique<RigidBodyFromSprings>(ctx.target<RigidBodyEngine>());
  };
  registry.add(std::move(def));
}

}  // namespace alloy::rigid
