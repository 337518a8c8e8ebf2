#include "tests/scenes/stress_scenes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "resolvers/rigid_body/rigid_body.hpp"

namespace alloy::scenes::stress {

// --- checks ------------------------------------------------------------------------------

namespace {

template <class T>
std::size_t scan_column(const PropertyStore& store, PropertyId id, std::string* first) {
  const Column<T>& c = store.typed<T>(id);
  std::size_t bad = 0;
  for (std::uint32_t slot : c.members()) {
    if (is_finite(c[slot])) continue;
    if (bad++ == 0 && first && first->empty())
      *first = store.describe(store.id_at(slot)) + "." + store.registry().def(id).name;
  }
  return bad;
}

/// The columns the energy needs, looked up once per call (cheap: a map lookup each).
struct BodyColumns {
  const PropertyStore& store;
  const Column<double>* mass = nullptr;
  const Column<std::uint8_t>* is_static = nullptr;
  const Column<Vec3>* position = nullptr;
  const Column<Vec3>* velocity = nullptr;
  const Column<Vec3>* angular_velocity = nullptr;
  const Column<Quat>* orientation = nullptr;
  const Column<Vec3>* gravity = nullptr;
  const Column<Vec3>* size = nullptr;
  const Column<double>* radius = nullptr;
  const Column<EnumValue>* shape = nullptr;
  int box = -1, sphere = -1;

  explicit BodyColumns(const World& w) : store(w.store()) {
    const PropertyRegistry& reg = w.properties();
    auto bind = [&](auto*& ptr, const char* name) {
      using C = std::remove_const_t<std::remove_pointer_t<std::remove_reference_t<decltype(ptr)>>>;
      using T = std::remove_cvref_t<decltype(std::declval<C>()[0])>;
      if (const auto id = reg.find(name); id && store.find_column(*id)) ptr = &store.typed<T>(*id);
    };
    bind(mass, "mass");
    bind(is_static, "static");
    bind(position, "position");
    bind(velocity, "velocity");
    bind(angular_velocity, "angular_velocity");
    bind(orientation, "orientation");
    bind(gravity, "gravity");
    bind(size, "size");
    bind(radius, "radius");
    bind(shape, "shape");
    if (const auto id = reg.find("shape")) {
      if (auto v = reg.enum_value(*id, "box")) box = v->index;
      if (auto v = reg.enum_value(*id, "sphere")) sphere = v->index;
    }
  }
  template <class T>
  static bool has(const Column<T>* c, std::uint32_t s) {
    return c && c->has(s);
  }
  bool movable(std::uint32_t s) const { return !(has(is_static, s) && (*is_static)[s]); }

  template <class F>
  void each_body(F&& f) const {
    if (!mass) return;
    for (std::uint32_t s : mass->members())
      if (movable(s) && has(position, s)) f(s);
  }

  /// Rotational kinetic energy 1/2 w . I w, with I of the shape in the body frame.
  double rotational(std::uint32_t s) const {
    if (!has(angular_velocity, s)) return 0;
    const double m = (*mass)[s];
    Vec3 inertia;  // principal moments, body frame
    const int kind = has(shape, s) ? (*shape)[s].index : -1;
    if (kind == box && has(size, s)) {
      const Vec3 d = (*size)[s];
      inertia =
          Vec3{d.y * d.y + d.z * d.z, d.x * d.x + d.z * d.z, d.x * d.x + d.y * d.y} * (m / 12);
    } else if (kind == sphere && has(radius, s)) {
      const double i = 0.4 * m * (*radius)[s] * (*radius)[s];
      inertia = {i, i, i};
    } else {
      return 0;
    }
    const Quat q = has(orientation, s) ? (*orientation)[s] : Quat{};
    const Vec3 wb = rotate(Quat{q.w, -q.x, -q.y, -q.z}, (*angular_velocity)[s]);
    return 0.5 * (inertia.x * wb.x * wb.x + inertia.y * wb.y * wb.y + inertia.z * wb.z * wb.z);
  }
};

}  // namespace

std::size_t count_non_finite(const World& w, std::string* first) {
  const PropertyStore& store = w.store();
  const PropertyRegistry& reg = w.properties();
  std::size_t bad = 0;
  for (PropertyId id = 0; id < reg.size(); ++id) {
    if (!store.find_column(id)) continue;
    switch (reg.def(id).kind) {
      case PropertyKind::Number:
        bad += scan_column<double>(store, id, first);
        break;
      case PropertyKind::Vec3:
        bad += scan_column<Vec3>(store, id, first);
        break;
      case PropertyKind::Quat:
        bad += scan_column<Quat>(store, id, first);
        break;
      default:
        break;  // integers, flags, strings, refs and enums cannot be NaN
    }
  }
  return bad;
}

Energy mechanical_energy(const World& w) {
  const BodyColumns c(w);
  Energy e;
  c.each_body([&](std::uint32_t s) {
    const double m = (*c.mass)[s];
    if (BodyColumns::has(c.velocity, s)) {
      const Vec3 v = (*c.velocity)[s];
      e.kinetic += 0.5 * m * dot(v, v);
    }
    e.kinetic += c.rotational(s);
    if (BodyColumns::has(c.gravity, s)) e.potential -= m * dot((*c.gravity)[s], (*c.position)[s]);
  });
  return e;
}

double max_speed(const World& w) {
  const BodyColumns c(w);
  double top = 0;
  c.each_body([&](std::uint32_t s) {
    if (BodyColumns::has(c.velocity, s)) top = std::max(top, length((*c.velocity)[s]));
  });
  return top;
}

Monitor::Monitor(World& w) {
  w.start();
  const Energy e = mechanical_energy(w);
  e0 = e_max = e_min = e_last = e.total();
  ke_max = e.kinetic;
}

void Monitor::observe(const World& w) {
  ++steps;
  std::string first;
  const std::size_t bad = count_non_finite(w, first_non_finite.empty() ? &first : nullptr);
  if (bad && first_non_finite.empty())
    first_non_finite = first + " at step " + std::to_string(w.step_count());
  non_finite += bad;
  const Energy e = mechanical_energy(w);
  e_last = e.total();
  e_max = std::max(e_max, e_last);
  e_min = std::min(e_min, e_last);
  ke_max = std::max(ke_max, e.kinetic);
  speed_max = std::max(speed_max, max_speed(w));
}

bool rigid_body_has_setting(const std::string& key) {
  const auto& keys = rigid::RigidBodyConfig::keys();
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

// --- scenes --------------------------------------------------------------------------------

std::vector<Vec3> positions(const World& w, const std::vector<ObjectId>& ids) {
  std::vector<Vec3> out;
  out.reserve(ids.size());
  for (ObjectId id : ids) out.push_back(std::get<Vec3>(w.get(id, "position")));
  return out;
}

double max_displacement(const World& w, const std::vector<ObjectId>& ids,
                        const std::vector<Vec3>& start) {
  double worst = 0;
  for (std::size_t i = 0; i < ids.size(); ++i)
    worst = std::max(worst, length(std::get<Vec3>(w.get(ids[i], "position")) - start[i]));
  return worst;
}

Pyramid build_pyramid(World& w, int base, double edge) {
  Pyramid p;
  add_floor(w);
  // A 1 % gap between neighbours in a row: touching side faces would make
  // contacts that only fight each other.
  const double pitch = edge * 1.01;
  for (int row = 0; row < base; ++row) {
    const int count = base - row;
    for (int k = 0; k < count; ++k) {
      const double x = (k - (count - 1) / 2.0) * pitch;
      p.boxes.push_back(add_box(w, {x, edge / 2 + row * edge, 0}, {edge, edge, edge}, 1.0, {},
                                "p" + std::to_string(row) + "_" + std::to_string(k)));
    }
  }
  return p;
}

HeavyOnLight build_heavy_on_light(World& w, int light, double ratio, double edge) {
  HeavyOnLight s;
  add_floor(w);
  for (int i = 0; i < light; ++i)
    s.light.push_back(add_box(w, {0, edge / 2 + i * edge, 0}, {edge, edge, edge}, 1.0, {},
                              "light" + std::to_string(i)));
  s.heavy = add_box(w, {0, edge / 2 + light * edge, 0}, {edge, edge, edge}, ratio, {}, "heavy");
  return s;
}

Chain build_chain(World& w, int links, double angle, double weight_ratio, double pitch,
                  double link_mass) {
  Chain c;
  c.pitch = pitch, c.link_mass = link_mass;
  // Down the chain, straight: hanging (-y) rotated by `angle` about z.
  const Quat q = Quat::from_angle_z(angle);
  const Vec3 down = rotate(q, Vec3{0, -1, 0});
  const Vec3 link_size{0.02, pitch * 0.9, 0.02};
  ObjectId previous;
  for (int i = 0; i < links; ++i) {
    const ObjectId l =
        add_box(w, down * (pitch * (i + 0.5)), link_size, link_mass, q, "link" + std::to_string(i));
    c.hinges.push_back(
        add_hinge(w, l, previous, down * (pitch * i), {0, 0, 1}, "hinge" + std::to_string(i)));
    c.links.push_back(l);
    previous = l;
  }
  if (weight_ratio > 0) {
    const double s = c.weight_size;
    const ObjectId wt = add_box(w, down * (pitch * links + s / 2), {s, s, s},
                                weight_ratio * link_mass, q, "weight");
    c.hinges.push_back(
        add_hinge(w, wt, previous, down * (pitch * links), {0, 0, 1}, "hinge_weight"));
    c.links.push_back(wt);
    c.weighted = true;
  }
  return c;
}

double Chain::joint_gap(const World& w) const {
  // Each hinge joins link i's top end to link i-1's bottom end (the play
  // area's origin for the first). Ends in the body frame: +-pitch/2 along y for
  // links, +size/2 for the weight.
  auto end = [&](std::size_t i, double local_y) {
    const Vec3 p = std::get<Vec3>(w.get(links[i], "position"));
    const Quat q = std::get<Quat>(w.get(links[i], "orientation"));
    return p + rotate(q, Vec3{0, local_y, 0});
  };
  double worst = 0;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const bool is_weight = weighted && i + 1 == links.size();
    const Vec3 top = end(i, is_weight ? weight_size / 2 : pitch / 2);
    const Vec3 above = i == 0 ? Vec3{} : end(i - 1, -pitch / 2);
    worst = std::max(worst, length(top - above));
  }
  return worst;
}

int Shot::side(const World& w) const {
  const double x = std::get<Vec3>(w.get(projectile, "position")).x;
  if (x > thickness + radius) return 1;
  if (x < -radius) return -1;
  return 0;
}

Shot build_shot(World& w, int k, int shots, double dt, double speed) {
  Shot s;
  s.speed = speed;
  s.wall = w.create("wall");
  w.set(s.wall, "shape", std::string("box"));
  w.set(s.wall, "size", Vec3{s.thickness, 4, 4});
  w.set(s.wall, "position", Vec3{s.thickness / 2, 0, 0});
  w.set(s.wall, "static", true);
  // Spread the shots evenly over angle, aim and phase with three co-prime
  // strides, so that no two share a combination.
  const double u = (k + 0.5) / shots;
  const double angle = (60.0 * std::numbers::pi / 180) * std::fmod(u * 7, 1.0);
  const double heading =
      2 * std::numbers::pi * std::fmod(u * 11, 1.0);  // which way the angle leans
  const Vec3 dir{std::cos(angle), std::sin(angle) * std::cos(heading),
                 std::sin(angle) * std::sin(heading)};
  const Vec3 aim{0, 1.0 * (std::fmod(u * 13, 1.0) - 0.5), 1.0 * (std::fmod(u * 17, 1.0) - 0.5)};
  const double phase = u;  // fraction of one step's travel added to the run-up
  s.start = aim - dir * (0.5 + s.radius + phase * speed * dt);
  s.velocity = dir * speed;
  s.projectile = add_sphere(w, s.start, s.radius, 0.05, "projectile");
  w.set(s.projectile, "velocity", s.velocity);
  return s;
}

MagnetPack build_magnet_pack(World& w, int n, double edge, double gap) {
  MagnetPack m;
  add_floor(w);
  constexpr double br = 1.2, density = 7500, mu0 = 4e-7 * std::numbers::pi, magnetic_length = 0.85;
  // As kit.magnet: magnetisation Br / mu0, moment M V carried by poles 0.85 L apart.
  m.pole_strength = br / mu0 * edge * edge / magnetic_length;
  const int side = std::max(1, int(std::ceil(std::cbrt(double(n)) - 1e-9)));
  const double pitch = edge + gap;
  const PropertyRegistry& reg = w.properties();
  const EnumValue permanent = *reg.enum_value(reg.id("magnet"), "permanent");
  for (int i = 0; i < n; ++i) {
    const int ix = i % side, iz = (i / side) % side, iy = i / (side * side);
    const Vec3 at{(ix - (side - 1) / 2.0) * pitch, edge / 2 + gap / 2 + iy * pitch,
                  (iz - (side - 1) / 2.0) * pitch};
    const ObjectId o = add_box(w, at, {edge, edge, edge}, density * edge * edge * edge, {},
                               "magnet" + std::to_string(i));
    w.set(o, "magnet", permanent);
    w.set(o, "pole_strength", ((iy + iz) % 2 ? -1.0 : 1.0) * m.pole_strength);
    w.set(o, "friction", 0.4);
    m.magnets.push_back(o);
  }
  return m;
}

StiffCircuit build_stiff_circuit(World& w, double tau, double e) {
  StiffCircuit c;
  constexpr double internal = 0.1, wire_r = 0.01;
  c.e = e;
  c.r_total = 6.0;
  c.l = tau * c.r_total;
  c.battery = w.create("battery");
  w.set(c.battery, "emf", e);
  w.set(c.battery, "internal_resistance", internal);
  c.coil = w.create("coil");
  w.set(c.coil, "inductance", c.l);
  w.set(c.coil, "resistance", c.r_total - internal - 2 * wire_r);
  const auto wire = [&](const char* name, ObjectId from, int ft, ObjectId to, int tt) {
    const ObjectId id = w.create(name);
    w.set(id, "wire_from", from);
    w.set(id, "wire_from_terminal", std::int64_t(ft));
    w.set(id, "wire_to", to);
    w.set(id, "wire_to_terminal", std::int64_t(tt));
    w.set(id, "resistance", wire_r);
  };
  wire("w1", c.battery, 1, c.coil, 0);
  wire("w2", c.coil, 1, c.battery, 0);
  return c;
}

}  // namespace alloy::scenes::stress
