#include "resolvers/rigid_body/rigid_body_from_springs.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

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
      {.name = "spring_slack",
       .kind = PropertyKind::Bool,
       .doc = "spring: true makes it a string: it pulls only while longer than its rest length "
              "and never pushes (shorter, it is slack and does nothing)"},
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

namespace {

/// The columns a spring reads, taken once per pass.
struct SpringColumns {
  explicit SpringColumns(const WorldView& world)
      : stiffness(world.column<double>("spring_stiffness")),
        part_a(world.column<ObjectId>("spring_a")),
        part_b(world.column<ObjectId>("spring_b")),
        anchor_a(world.column<Vec3>("spring_anchor_a")),
        anchor_b(world.column<Vec3>("spring_anchor_b")),
        rest(world.column<double>("spring_rest_length")),
        damping(world.column<double>("spring_damping")),
        slack(world.column<std::uint8_t>("spring_slack")),
        position(world.column<Vec3>("position")),
        orientation(world.column<Quat>("orientation")),
        velocity(world.column<Vec3>("velocity")),
        spin(world.column<Vec3>("angular_velocity")),
        mass(world.column<double>("mass")),
        is_static(world.column<std::uint8_t>("static")),
        pinned(world.column<std::uint8_t>("pinned")),
        store(world.store()) {}

  /// One end: its world point and velocity, and the part's mass as the
  /// spring sees it. No part: a fixed point of the board.
  struct End {
    ObjectId part;
    Vec3 at, v;
    double mass = kInfinite;
  };
  End end_of(ObjectId part, Vec3 anchor) const {
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
  }

  ColumnView<double> stiffness;
  ColumnView<ObjectId> part_a, part_b;
  ColumnView<Vec3> anchor_a, anchor_b;
  ColumnView<double> rest, damping;
  ColumnView<std::uint8_t> slack;
  ColumnView<Vec3> position;
  ColumnView<Quat> orientation;
  ColumnView<Vec3> velocity, spin;
  ColumnView<double> mass;
  ColumnView<std::uint8_t> is_static, pinned;
  const PropertyStore& store;
};

/// The energy a spring stores at length L: a string (slack) stores none while
/// it is not stretched.
double stored_energy(double k, double rest, double length, bool slack) {
  if (slack && length <= rest) return 0;
  return 0.5 * k * (length - rest) * (length - rest);
}

}  // namespace

void RigidBodyFromSprings::close_books(const WorldView& world) {
  if (held_.empty()) return;
  const SpringColumns col(world);
  for (const Held& h : held_) {
    // A spring or part removed since (an edit between steps): its step is not booked.
    if (!col.store.alive(h.spring) || (!h.a.is_null() && !col.store.alive(h.a)) ||
        (!h.b.is_null() && !col.store.alive(h.b)))
      continue;
    const Vec3 a1 = col.end_of(h.a, h.anchor_a).at, b1 = col.end_of(h.b, h.anchor_b).at;
    const Vec3 da = h.a.is_null() ? Vec3{} : a1 - h.at_a;
    const Vec3 db = h.b.is_null() ? Vec3{} : b1 - h.at_b;
    // The work the held force did on the parts, along their ends' moves.
    const double work = dot(h.force, da) - dot(h.force, db);
    // Its two parts, along the stretch the ends made (the force is along n).
    const Vec3 n = h.length > 0 ? (h.at_a - h.at_b) / h.length : Vec3{};
    const double stretch = dot(n, da - db);
    const double stored_before = stored_energy(h.stiffness, h.rest, h.length, h.slack);
    const double stored_after = stored_energy(h.stiffness, h.rest, length(a1 - b1), h.slack);
    given_ += work;
    heat_ += h.damper * stretch;
    // The elastic part gave -elastic * stretch; what the store lost beyond
    // that is the explicit scheme's (0 as the step goes to 0).
    integration_ -= -h.elastic * stretch + (stored_after - stored_before);
  }
  held_.clear();
}

void RigidBodyFromSprings::report_energy(const WorldView& world, EnergyReport& out) {
  // The forces held now act in the next step's advance: they are booked at
  // the next apply (which runs after that advance), not here.
  const SpringColumns col(world);
  double stored = 0;
  for (std::uint32_t s : col.stiffness.members()) {
    const ObjectId a_id = col.part_a.value_or(s, ObjectId{});
    if (a_id.is_null()) continue;
    const auto a = col.end_of(a_id, col.anchor_a.value_or(s, {}));
    const auto b = col.end_of(col.part_b.value_or(s, ObjectId{}), col.anchor_b.value_or(s, {}));
    if (a.part.is_null() && b.part.is_null()) continue;
    stored += stored_energy(col.stiffness[s], col.rest.value_or(s, 0), length(a.at - b.at),
                            col.slack.value_or(s, 0) != 0);
  }
  out.store("spring energy", stored);
  out.sink("damper heat", std::exchange(heat_, 0.0));
  out.sink("integration (explicit spring force)", std::exchange(integration_, 0.0));
  out.transfer("springs", -std::exchange(given_, 0.0));
}

void RigidBodyFromSprings::apply(const WorldView& world) {
  // The step's advance has just moved the parts under the forces held since
  // the last apply: their books first.
  close_books(world);
  const SpringColumns col(world);
  const PropertyStore& store = col.store;
  for (std::uint32_t s : col.stiffness.members()) {
    const ObjectId a_id = col.part_a.value_or(s, ObjectId{});
    if (a_id.is_null()) continue;  // a spring not yet fixed to anything
    const Vec3 anchor_a = col.anchor_a.value_or(s, {}), anchor_b = col.anchor_b.value_or(s, {});
    const auto a = col.end_of(a_id, anchor_a);
    const auto b = col.end_of(col.part_b.value_or(s, ObjectId{}), anchor_b);
    if (a.part.is_null() && b.part.is_null()) continue;
    const double k = col.stiffness[s], c = col.damping.value_or(s, 0);
    refuse_if_unstable(stability(a.mass, b.mass, k, c, world.dt()), store.describe(store.id_at(s)));
    const Vec3 d = a.at - b.at;
    const double L = length(d);
    // Both ends at one point: no direction to pull along (a rest length of
    // zero holds them there; any other pushes them apart once they move).
    if (!(L > 1e-12)) continue;
    const Vec3 n = d / L;
    const double rest = col.rest.value_or(s, 0);
    double elastic = k * (L - rest), damper = c * dot(a.v - b.v, n);
    const bool slack = col.slack.value_or(s, 0) != 0;
    if (slack) {
      // A string: nothing while it is not stretched, and its damper cannot
      // make it push (a string closing fast on a stretch goes slack sooner).
      if (elastic <= 0) elastic = 0, damper = 0;
      if (elastic + damper < 0) damper = -elastic;
    }
    const Vec3 f = -(elastic + damper) * n;
    if (!a.part.is_null()) target_.add_force(a.part, f, a.at);
    if (!b.part.is_null()) target_.add_force(b.part, -f, b.at);
    held_.push_back({.spring = store.id_at(s),
                     .a = a.part,
                     .b = b.part,
                     .anchor_a = anchor_a,
                     .anchor_b = anchor_b,
                     .at_a = a.at,
                     .at_b = b.at,
                     .force = f,
                     .elastic = elastic,
                     .damper = damper,
                     .stiffness = k,
                     .rest = rest,
                     .length = L,
                     .slack = slack});
  }
}

void register_rigid_body_from_springs(PluginRegistry& registry) {
  PluginDef def;
  def.info = {.name = RigidBodyFromSprings::kName,
              .kind = StageKind::Interaction,
              .reads = {"position", "orientation", "velocity", "angular_velocity", "mass", "static",
                        "pinned", "spring_a", "spring_b", "spring_anchor_a", "spring_anchor_b",
                        "spring_stiffness", "spring_rest_length", "spring_damping", "spring_slack"},
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
