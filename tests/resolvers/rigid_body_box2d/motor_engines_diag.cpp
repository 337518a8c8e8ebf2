// motor_engines_diag: why the motor (mods/motor) turns at another speed on
// Box2D than on ODE (issue 15; docs/box2d.md, "The motor on both engines").
// Runs the bundled scene on one engine and logs, step by step, what sets the
// rotor's speed: the coils' currents, whether the slider touches a spoke (the
// commutator's duty), the slider-spoke contact impulses (normal and
// tangential) and their torque on the rotor about the axle, and the magnets'
// drive torque, found as the rest of the rotor's torque balance
//
//   I dw = (T_magnets + T_bearing + T_drag) h + (r x J)_contacts
//
// with the bearing's Coulomb torque at its cap while the rotor turns (checked:
// the rotor does not stop in the window). Not a test: a measuring tool.
//
//   motor_engines_diag ENGINE [T0 T1] [object.property=value ...] [--dt H] [--csv FILE]
//
// ENGINE is rigid_body or rigid_body.box2d; the overrides are set before the
// first step (numbers only), e.g. slider.friction=0 bearing.joint_friction=0.
// Prints the means over [T0, T1] (default 2 to 4 s, the kit test's window).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

using namespace alloy;

namespace {

double number(World& w, ObjectId o, const char* p) {
  const auto v = w.get(o, p);
  return std::holds_alternative<double>(v) ? std::get<double>(v) : 0.0;
}

bool has(World& w, ObjectId o, const char* p) {
  return w.store().has(o, w.properties().id(p));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s ENGINE [T0 T1] [object.property=value ...] [--dt H] [--csv FILE]\n",
                 argv[0]);
    return 2;
  }
  const std::string engine = argv[1];
  double t0 = 2, t1 = 4;
  int a = 2;
  if (argc >= 4 && std::isdigit(static_cast<unsigned char>(argv[2][0]))) {
    t0 = std::atof(argv[2]), t1 = std::atof(argv[3]);
    a = 4;
  }
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(test::source("mods"));
  lua::LoadedScene loaded = lua::load_scene(test::source("mods/motor"), registry, load);
  World& world = *loaded.world;
  if (engine != "rigid_body") world.swap("", "rigid_body", engine);
  std::FILE* csv = nullptr;
  for (; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--csv" && a + 1 < argc) {
      csv = std::fopen(argv[++a], "w");
      continue;
    }
    if (arg == "--dt" && a + 1 < argc) {
      world.set_dt(std::atof(argv[++a]));
      continue;
    }
    const auto dot = arg.find('.'), eq = arg.find('=');
    if (dot == std::string::npos || eq == std::string::npos || eq < dot) {
      std::fprintf(stderr, "bad override '%s' (object.property=value)\n", arg.c_str());
      return 2;
    }
    world.set(world.find(arg.substr(0, dot)), arg.substr(dot + 1, eq - dot - 1),
              std::atof(arg.c_str() + eq + 1));
  }

  const ObjectId axle = world.find("axle"), slider = world.find("slider");
  const ObjectId coils[2] = {world.find("upper_coil"), world.find("lower_coil")};
  std::vector<ObjectId> spokes;
  for (const char* n : {"spoke_S1", "spoke_N1", "spoke_S2", "spoke_N2", "spoke_S3", "spoke_N3",
                        "spoke_S4", "spoke_N4"})
    spokes.push_back(world.find(n));
  auto is_spoke = [&](ObjectId o) {
    for (ObjectId s : spokes)
      if (s == o) return true;
    return false;
  };
  const double h = world.dt();
  const double bearing_friction = number(world, world.find("bearing"), "joint_friction");

  // Steps: world.step() runs the engine and its contact set; the set's
  // impulses are those of the engine's last advance once demanded.
  world.step();
  const ContactSet* contacts = nullptr;
  for (const char* name : {"collisions", "collisions.box2d"})
    if (auto* c = dynamic_cast<const ContactSet*>(world.stage(name))) contacts = c;
  if (!contacts) {
    std::fprintf(stderr, "no contact set\n");
    return 1;
  }
  ImpulseDemand demand = contacts->demand_impulses();

  // Sums over the window.
  double n = 0, w_sum = 0, i_abs = 0, closed = 0, jn = 0, jt = 0, jt_abs = 0, torque_contact = 0,
         torque_mag = 0, torque_drag = 0, speed_sq = 0, depth = 0, stuck = 0;
  int began = 0, switches = 0;
  bool was_closed = false;
  const double centre_x = std::get<Vec3>(world.get(axle, "position")).x,
               centre_y = std::get<Vec3>(world.get(axle, "position")).y;
  double w_prev = std::get<Vec3>(world.get(axle, "angular_velocity")).z;
  double angle0 = 0, angle1 = 0, last_angle = 0;
  bool have_angle = false;
  // The rotor's moment of inertia as the scene computed it (mods/motor/rotor.lua):
  // recovered from the drag rate, angular_damping = bearing_drag / I.
  const double inertia = 9e-5 / number(world, axle, "angular_damping");
  if (csv)
    std::fprintf(
        csv,
        "t,angle,spoke,w,i_upper,i_lower,closed,contact_pairs,normal_impulse,tangential_impulse,"
        "contact_torque,magnet_torque,depth\n");
  const auto steps = std::uint64_t(std::llround(t1 / h));
  for (std::uint64_t k = 1; k < steps; ++k) {
    world.step();
    const double t = world.time();
    const double w = std::get<Vec3>(world.get(axle, "angular_velocity")).z;
    double a_now = angle_z(std::get<Quat>(world.get(axle, "orientation")));
    if (have_angle) a_now = last_angle + std::remainder(a_now - last_angle, 2 * std::numbers::pi);
    last_angle = a_now, have_angle = true;
    double iu = 0, il = 0;
    if (has(world, coils[0], "current")) iu = number(world, coils[0], "current");
    if (has(world, coils[1], "current")) il = number(world, coils[1], "current");
    // The slider's pairs with the spokes: their impulses on the spoke, and
    // the torque of those about the axle.
    int pairs = 0, touched = -1;
    double pn = 0, pt = 0, tc = 0, dep = 0;
    for (const ContactPair& p : contacts->touching()) {
      const bool slider_a = p.a == slider && is_spoke(p.b),
                 slider_b = p.b == slider && is_spoke(p.a);
      if (!slider_a && !slider_b) continue;
      ++pairs;
      for (std::size_t q = 0; q < spokes.size(); ++q)
        if (spokes[q] == (slider_a ? p.b : p.a)) touched = int(q);
      dep = std::max(dep, p.depth);
      // impulse is on a; on the spoke it is -impulse when the slider is a.
      const Vec3 on_spoke = slider_a ? Vec3{} - p.impulse : p.impulse;
      const auto pts = contacts->points(p);
      Vec3 at{};
      for (const ContactPoint& q : pts) at += q.position;
      if (!pts.empty()) at = at / double(pts.size());
      const Vec3 nrm = pts.empty() ? Vec3{} : pts[0].normal;
      const double jn_here = std::abs(dot(on_spoke, nrm));
      pn += jn_here;
      const Vec3 tang = on_spoke - nrm * dot(on_spoke, nrm);
      const double tx = at.x - centre_x, ty = at.y - centre_y;
      tc += tx * on_spoke.y - ty * on_spoke.x;
      pt += (tx * tang.y - ty * tang.x) >= 0 ? std::sqrt(dot(tang, tang))
                                             : -std::sqrt(dot(tang, tang));
    }
    for (const ContactPair& p : contacts->began())
      if ((p.a == slider && is_spoke(p.b)) || (p.b == slider && is_spoke(p.a))) {
        if (t >= t0 && t < t1) ++began;
      }
    const double drag = -number(world, axle, "angular_damping") * inertia * w;
    const double bearing = w_prev > 0 ? -bearing_friction : (w_prev < 0 ? bearing_friction : 0);
    const double tm = (inertia * (w - w_prev) - tc) / h - bearing - drag;
    const bool is_closed = pairs > 0;
    if (t > t0 && t <= t1) {
      if (n == 0) angle0 = a_now;
      angle1 = a_now;
      ++n;
      w_sum += w;
      speed_sq += w * w;
      i_abs += std::abs(iu) + std::abs(il);
      closed += is_closed;
      jn += pn, jt += pt, jt_abs += std::abs(pt);
      torque_contact += tc;
      torque_mag += tm;
      torque_drag += drag;
      depth += dep;
      stuck += std::abs(w) < 1e-3;
      if (is_closed && !was_closed) ++switches;
    }
    was_closed = is_closed;
    if (csv)
      std::fprintf(csv, "%.6f,%.6f,%d,%.6f,%.6g,%.6g,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g\n", t, a_now,
                   touched, w, iu, il, int(is_closed), pairs, pn, pt, tc, tm, dep);
    w_prev = w;
  }
  if (csv) std::fclose(csv);
  const double T = n * h;
  std::printf("engine %s, %.2f-%.2f s (%g steps), rotor I %.4e kg m^2\n", engine.c_str(), t0, t1, n,
              inertia);
  std::printf("  speed from angle %.4f rad/s (mean of w %.4f, rms %.4f); steps with |w|<1e-3: %g\n",
              (angle1 - angle0) / (T - h), w_sum / n, std::sqrt(speed_sq / n), stuck);
  std::printf(
      "  coil current |I| mean %.4f mA; slider on a spoke %.1f %% of steps; %d closings, %d "
      "slider-spoke contacts began\n",
      1e3 * i_abs / n, 100 * closed / n, switches, began);
  std::printf(
      "  slider-spoke contact: mean normal force %.4f N, tangential %.4f N (|.| %.4f N), "
      "mean depth %.3f mm\n",
      jn / T, jt / T, jt_abs / T, 1e3 * depth / n);
  std::printf(
      "  mean torques on the rotor, N m: magnets %.5f, contacts %.5f, bearing %.5f, "
      "drag %.5f\n",
      torque_mag / n, torque_contact / T, -bearing_friction, torque_drag / n);
  return 0;
}
