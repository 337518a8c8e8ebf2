// doorbell_engines_diag: why the doorbell (mods/doorbell) strikes at uneven
// intervals on one engine and steadily on another (issue 15; docs/box2d.md,
// "The doorbell on both engines"). Runs the bundled scene and logs, step by
// step, what sets a strike cycle: the lever's angle and spin, the hammer's
// height and vertical speed, the contact finger's angle on the lever, whether
// its tip touches the interrupter (pairs, points, depth, normal impulse), the
// coil's current, the bell's strikes, and on Box2D how many times its world
// was rebuilt. Not a test: a measuring tool.
//
//   doorbell_engines_diag ENGINE [T0 T1] [--to ENGINE2 --at T] [--csv FILE]
//
// ENGINE is rigid_body or rigid_body.box2d (from the start); --to swaps to
// ENGINE2 at time T. Prints the strike times and intervals in [T0, T1]
// (default 0.5 to 3 s, the kit test's run) and their spread.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/event_records.hpp"

using namespace alloy;

namespace {

double number(World& w, ObjectId o, const char* p) {
  if (!w.store().has(o, w.properties().id(p))) return 0;
  const auto v = w.get(o, p);
  return std::holds_alternative<double>(v) ? std::get<double>(v) : 0.0;
}

Vec3 vec(World& w, ObjectId o, const char* p) {
  if (!w.store().has(o, w.properties().id(p))) return {};
  return std::get<Vec3>(w.get(o, p));
}

double angle(World& w, ObjectId o) {
  return angle_z(std::get<Quat>(w.get(o, "orientation")));
}

const ContactSet* contact_set(World& w) {
  for (const char* name : {"collisions", "collisions.box2d"})
    if (auto* c = dynamic_cast<const ContactSet*>(w.stage(name))) return c;
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s ENGINE [T0 T1] [--to ENGINE2 --at T] [--csv FILE]\n", argv[0]);
    return 2;
  }
  const std::string engine = argv[1];
  double t0 = 0.5, t1 = 3;
  std::string to;
  double at = 0;
  std::FILE* csv = nullptr;
  int a = 2;
  if (argc >= 4 && std::isdigit(static_cast<unsigned char>(argv[2][0]))) {
    t0 = std::atof(argv[2]), t1 = std::atof(argv[3]);
    a = 4;
  }
  for (; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--csv" && a + 1 < argc) {
      csv = std::fopen(argv[++a], "w");
    } else if (arg == "--to" && a + 1 < argc) {
      to = argv[++a];
    } else if (arg == "--at" && a + 1 < argc) {
      at = std::atof(argv[++a]);
    } else {
      std::fprintf(stderr, "bad argument '%s'\n", arg.c_str());
      return 2;
    }
  }
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions load;
  load.mod_paths.push_back(test::source("mods"));
  lua::LoadedScene loaded = lua::load_scene(test::source("mods/doorbell"), registry, load);
  World& world = *loaded.world;
  if (engine != "rigid_body") world.swap("", "rigid_body", engine);
  if (!to.empty()) world.schedule_swap(at, "", engine, to);
  test::EventRecords events;
  events.record(world);

  const ObjectId arm = world.find("arm"), hammer = world.find("hammer"),
                 finger = world.find("finger"), interrupter = world.find("interrupter"),
                 coil = world.find("coil");
  const double h = world.dt();
  if (csv)
    std::fprintf(csv,
                 "step,t,arm_angle,arm_w,hammer_y,hammer_vy,finger_on_arm,finger_w,touch,pairs,"
                 "points,depth,normal_impulse,current,strike,rebuilds,touching\n");
  std::vector<double> strikes;
  std::size_t seen = 0;
  const auto steps = std::uint64_t(std::llround(t1 / h));
  for (std::uint64_t k = 1; k <= steps; ++k) {
    world.step();
    const double t = world.time();
    const ContactSet* contacts = contact_set(world);
    static ImpulseDemand demand;
    static const ContactSet* demanded = nullptr;
    if (contacts && contacts != demanded) demand = contacts->demand_impulses(), demanded = contacts;
    int pairs = 0, points = 0;
    double depth = 0, jn = 0;
    if (contacts)
      for (const ContactPair& p : contacts->touching()) {
        if (!((p.a == finger && p.b == interrupter) || (p.a == interrupter && p.b == finger)))
          continue;
        ++pairs;
        points += int(p.count);
        depth = std::max(depth, p.depth);
        jn += std::abs(p.normal_impulse);
      }
    // Every touching pair but the switch's, by name, with its normal impulse.
    std::string touching;
    if (contacts)
      for (const ContactPair& p : contacts->touching()) {
        const std::string na = world.describe(p.a), nb = world.describe(p.b);
        if (na.find("contact_") == 0 || nb.find("contact_") == 0) continue;
        char buf[128];
        std::snprintf(buf, sizeof buf, " %s-%s:%u:%.3g:%.2g", na.c_str(), nb.c_str(), p.count,
                      p.normal_impulse, p.depth);
        touching += buf;
      }
    bool struck = false;
    for (; seen < events.events.size(); ++seen)
      if (events.events[seen].type == "sound" && events.events[seen].a == "bell") {
        struck = true;
        if (t >= t0 && t <= t1) strikes.push_back(events.events[seen].time);
      }
    std::uint64_t rebuilds = 0;
    if (auto* b = dynamic_cast<box2d::Box2DEngine*>(world.stage("rigid_body.box2d")))
      rebuilds = b->rebuild_count();
    if (csv && t >= t0 && t <= t1)
      std::fprintf(
          csv, "%llu,%.6f,%.7f,%.5f,%.7f,%.5f,%.6f,%.5f,%d,%d,%d,%.3g,%.4g,%.5f,%d,%llu,%s\n",
          (unsigned long long)k, t, angle(world, arm), vec(world, arm, "angular_velocity").z,
          vec(world, hammer, "position").y, vec(world, hammer, "velocity").y,
          std::remainder(angle(world, finger) - angle(world, arm), 2 * std::numbers::pi),
          vec(world, finger, "angular_velocity").z, int(pairs > 0), pairs, points, depth, jn,
          number(world, coil, "current"), int(struck), (unsigned long long)rebuilds,
          touching.c_str());
  }
  if (csv) std::fclose(csv);
  std::printf("doorbell on %s%s%s: %zu strikes in %.2f-%.2f s\n", engine.c_str(),
              to.empty() ? "" : ", then ", to.c_str(), strikes.size(), t0, t1);
  double lo = 1e9, hi = 0, sum = 0;
  std::printf("  intervals:");
  for (std::size_t i = 1; i < strikes.size(); ++i) {
    const double d = strikes[i] - strikes[i - 1];
    std::printf(" %.4f", d);
    lo = std::min(lo, d), hi = std::max(hi, d), sum += d;
  }
  if (strikes.size() > 1)
    std::printf("\n  mean %.4f s, spread (max - min) %.4f s = %.1f %% of the mean\n",
                sum / double(strikes.size() - 1), hi - lo,
                100 * (hi - lo) / (sum / double(strikes.size() - 1)));
  else
    std::printf("\n");
  return 0;
}
