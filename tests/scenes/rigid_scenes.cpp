#include "tests/scenes/rigid_scenes.hpp"

#include <cmath>
#include <numbers>

#include "resolvers/plugins.hpp"

namespace alloy::scenes {

Sim::Sim(WorldDef def) {
  register_native_plugins(registry);
  world = std::make_unique<World>(registry, std::move(def));
}

ObjectId add_floor(World& w, double top, Vec3 extent, const std::string& name) {
  const ObjectId f = w.create(name);
  w.set(f, "shape", std::string("box"));
  w.set(f, "size", extent);
  w.set(f, "position", Vec3{0, top - extent.y / 2, 0});
  w.set(f, "static", true);
  return f;
}

ObjectId add_box(World& w, Vec3 position, Vec3 size, double mass, Quat orientation, const std::string& name) {
  const ObjectId b = w.create(name);
  w.set(b, "shape", std::string("box"));
  w.set(b, "size", size);
  w.set(b, "mass", mass);
  w.set(b, "position", position);
  w.set(b, "orientation", orientation);
  return b;
}

ObjectId add_sphere(World& w, Vec3 position, double radius, double mass, const std::string& name) {
  const ObjectId b = w.create(name);
  w.set(b, "shape", std::string("sphere"));
  w.set(b, "radius", radius);
  w.set(b, "mass", mass);
  w.set(b, "position", position);
  return b;
}

ObjectId add_hinge(World& w, ObjectId a, ObjectId b, Vec3 anchor, Vec3 axis, const std::string& name) {
  const ObjectId j = w.create(name);
  w.set(j, "joint", std::string("hinge"));
  w.set(j, "body_a", a);
  if (!b.is_null()) w.set(j, "body_b", b);
  w.set(j, "anchor", anchor);
  w.set(j, "axis", axis);
  return j;
}

ObjectId add_glue(World& w, ObjectId a, ObjectId b, const std::string& name) {
  const ObjectId j = w.create(name);
  w.set(j, "joint", std::string("fixed"));
  w.set(j, "body_a", a);
  if (!b.is_null()) w.set(j, "body_b", b);
  return j;
}

FreeFall build_free_fall(World& w, double y0) {
  const Vec3 start{0, y0, 0};
  return {add_sphere(w, start, 0.1, 1.0, "ball"), start};
}

double BarPendulum::analytic_period(double g) const {
  // Box of length L (x) and width w (y) rotating about z through one end.
  const double d = length / 2;
  const double inertia = mass * (length * length + width * width) / 12 + mass * d * d;
  const double t0 = 2 * std::numbers::pi * std::sqrt(inertia / (mass * g * d));
  const double a2 = theta0 * theta0;
  return t0 * (1 + a2 / 16 + 11 * a2 * a2 / 3072);
}

BarPendulum build_bar_pendulum(World& w, double length, double theta0) {
  BarPendulum p;
  p.length = length, p.theta0 = theta0;
  // The bar's local x runs along it; hanging down means rotated -90 degrees,
  // then swung by theta0 about z.
  const double angle = -std::numbers::pi / 2 + theta0;
  const Vec3 centre{length / 2 * std::cos(angle), length / 2 * std::sin(angle), 0};
  p.bar = add_box(w, centre, {length, p.width, p.width}, p.mass, Quat::from_angle_z(angle), "bar");
  w.set(p.bar, "planar", true);
  p.hinge = add_hinge(w, p.bar, {}, {0, 0, 0}, {0, 0, 1}, "pivot");
  return p;
}

Bounce build_bounce(World& w, double drop, double restitution) {
  Bounce b;
  b.drop = drop, b.restitution = restitution;
  b.floor = add_floor(w);
  b.ball = add_sphere(w, {0, b.radius + drop, 0}, b.radius, 0.5, "ball");
  w.set(b.ball, "restitution", restitution);
  return b;
}

Stack build_stack(World& w, int n, double edge) {
  Stack s;
  s.edge = edge;
  add_floor(w);
  for (int i = 0; i < n; ++i)
    s.boxes.push_back(add_box(w, {0, edge / 2 + i * edge, 0}, {edge, edge, edge}, 1.0, {},
                              "box" + std::to_string(i)));
  return s;
}

PileLayout pile_layout(int count, std::uint32_t seed) {
  PileLayout L;
  constexpr double edge = 0.2, pitch = 0.26;
  constexpr int per_row = 8;
  const double half = per_row * pitch / 2 + 0.05;  // inner half-width of the bin
  L.statics.push_back({{0, -0.5, 0}, {}, {10, 1, 10}, 0});
  L.statics.push_back({{half + 0.1, 2, 0}, {}, {0.2, 4, 2 * half + 0.4}, 0});
  L.statics.push_back({{-half - 0.1, 2, 0}, {}, {0.2, 4, 2 * half + 0.4}, 0});
  L.statics.push_back({{0, 2, half + 0.1}, {}, {2 * half + 0.4, 4, 0.2}, 0});
  L.statics.push_back({{0, 2, -half - 0.1}, {}, {2 * half + 0.4, 4, 0.2}, 0});
  std::uint32_t r = seed;
  auto jitter = [&] {  // deterministic LCG in [-1, 1)
    r = r * 1664525u + 1013904223u;
    return double(r >> 8) / double(1u << 23) - 1.0;
  };
  for (int i = 0; i < count; ++i) {
    const int layer = i / (per_row * per_row), k = i % (per_row * per_row);
    const int ix = k % per_row, iz = k / per_row;
    const Vec3 p{(ix - (per_row - 1) / 2.0) * pitch + 0.02 * jitter(), 0.15 + layer * pitch + 0.02 * jitter(),
                 (iz - (per_row - 1) / 2.0) * pitch + 0.02 * jitter()};
    const Quat q = Quat::from_axis_angle({0, 1, 0}, 0.3 * jitter()) * Quat::from_axis_angle({1, 0, 0}, 0.05 * jitter());
    L.boxes.push_back({p, q, {edge, edge, edge}, 1.0});
  }
  return L;
}

void build_pile(World& w, const PileLayout& layout) {
  int i = 0;
  for (const BoxSpec& s : layout.statics) {
    const ObjectId o = w.create("static" + std::to_string(i++));
    w.set(o, "shape", std::string("box"));
    w.set(o, "size", s.size);
    w.set(o, "position", s.position);
    w.set(o, "orientation", s.orientation);
    w.set(o, "static", true);
    w.set(o, "friction", layout.friction);
  }
  for (const BoxSpec& s : layout.boxes) {
    const ObjectId o = add_box(w, s.position, s.size, s.mass, s.orientation);
    w.set(o, "friction", layout.friction);
  }
}

void build_tumble(World& w) {
  add_floor(w);
  for (int i = 0; i < 6; ++i) {
    const ObjectId s = add_sphere(w, {-1.0 + 0.4 * i, 1.0 + 0.3 * i, 0.05 * i}, 0.1, 0.5);
    w.set(s, "restitution", 0.3);
    add_box(w, {-0.9 + 0.4 * i, 2.0 + 0.25 * i, -0.05 * i}, {0.2, 0.1, 0.3}, 0.8,
            Quat::from_axis_angle({1, 0, 0}, 0.2 * i));
  }
  const ObjectId cap = w.create("capsule");
  w.set(cap, "shape", std::string("capsule"));
  w.set(cap, "radius", 0.05);
  w.set(cap, "length", 0.6);
  w.set(cap, "density", 700.0);
  w.set(cap, "position", Vec3{0.2, 3.0, 0});
  w.set(cap, "orientation", Quat::from_axis_angle({0, 0, 1}, 0.4));
  // A glued L-shape on a hinge to the play area.
  const ObjectId arm = add_box(w, {1.5, 1.5, 0}, {0.8, 0.05, 0.05}, 1.0, {}, "arm");
  const ObjectId tip = add_box(w, {1.9, 1.3, 0}, {0.05, 0.4, 0.05}, 0.5, {}, "tip");
  add_glue(w, arm, tip);
  add_hinge(w, arm, {}, {1.1, 1.5, 0}, {0, 0, 1}, "shoulder");
}

}  // namespace alloy::scenes
