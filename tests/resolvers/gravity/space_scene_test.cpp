// The space scene (mods/space, the paper's planet and orbit), loaded through
// the Lua scene loader with every native plugin: the probe fired from the
// planet area crosses into the orbit area, orbits, keeps its energy, and a
// swap of gravity model in the planet area changes no property but gravity.
//
// Energy is measured at apoapsis, once per orbit. Semi-implicit Euler keeps a
// modified energy H + (dt/2) v.grad(V) + O(dt^2) exactly, not H: the energy H
// of the probe swings by up to 0.2 % within each orbit at dt = 1/240 s (most
// on either side of periapsis) and comes back. The swing is proportional to the radial
// velocity, which is zero at apoapsis, so samples there show the drift from
// one orbit to the next (the quantity that matters: does the orbit decay or
// grow?) without the swing. Apoapsis is also the farthest point from the
// planet area, whose passes are what could change the orbit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "lua/scene_loader.hpp"
#include "resolvers/gravity/nbody_gravity.hpp"
#include "resolvers/plugins.hpp"

namespace alloy {
namespace {

constexpr double kPi = std::numbers::pi;

struct Space {
  PluginRegistry registry;
  lua::LoadedScene scene;
  ObjectId probe, planet, crate;
  double G = 0, gm = 0;

  explicit Space(double dt = 0, const std::filesystem::path& mod = std::filesystem::path(ALLOY_SOURCE_DIR) / "mods/space") {
    register_native_plugins(registry);
    scene = lua::load_scene(mod, registry);
    if (dt > 0) scene.world->set_dt(dt);
    probe = w().find("probe"), planet = w().find("planet"), crate = w().find("crate");
    G = scene.def.settings.at("gravity.nbody").number("G", 0);
    gm = G * std::get<double>(w().get(planet, "mass"));
  }
  World& w() { return *scene.world; }
  Vec3 vec(ObjectId o, const char* p) { return std::get<Vec3>(w().get(o, p)); }
  Vec3 x() { return vec(probe, "position"); }
  Vec3 v() { return vec(probe, "velocity"); }
  /// Specific orbital energy of the probe about the immovable planet, J/kg.
  double energy() {
    const Vec3 u = v();
    return 0.5 * dot(u, u) - gm / length(x());
  }
};

struct Apoapsis {
  double time, r, angle, energy;
};

struct Flight {
  std::vector<Apoapsis> apoapses;
  std::vector<double> launch_passes;  // the probe's distance from the planet each time it passes over the tower
  std::vector<std::string> areas;     // the probe's areas in order of visit
  int longest_stay_in_planet = 0;     // steps, after the launch
  double swing = 0;                   // range of the energy between the first two apoapses, J/kg
};

/// Steps until the probe has passed `orbits` apoapses.
Flight fly(Space& s, int orbits) {
  Flight f;
  World& w = s.w();
  w.start();
  f.areas.push_back(w.area_of(s.probe));
  Vec3 last = s.x();
  double last_vr = dot(last, s.v());
  int stay = 0;
  double lo = 1e300, hi = -1e300;
  while (int(f.apoapses.size()) < orbits && w.time() < orbits * 20.0) {
    w.step();
    const std::string area = w.area_of(s.probe);
    if (area != f.areas.back()) f.areas.push_back(area);
    stay = area == "planet" ? stay + 1 : 0;
    if (f.areas.size() > 2) f.longest_stay_in_planet = std::max(f.longest_stay_in_planet, stay);
    const Vec3 x = s.x();
    const double vr = dot(x, s.v());
    if (area == "orbit" && last_vr > 0 && vr <= 0) {
      // The time at which the radial velocity crossed zero, between the steps.
      const double t = w.time() - w.dt() * (-vr / (last_vr - vr));
      f.apoapses.push_back({t, length(x), std::atan2(x.y, x.x), s.energy()});
    }
    if (area == "orbit" && f.apoapses.size() == 1) {
      lo = std::min(lo, s.energy()), hi = std::max(hi, s.energy());
      f.swing = hi - lo;
    }
    if (last.x > 0 && x.x <= 0 && x.y > 0) f.launch_passes.push_back(length(x));  // over the tower (+y axis)
    last = x, last_vr = vr;
  }
  return f;
}

double drift(const Flight& f) {
  double worst = 0;
  for (const Apoapsis& a : f.apoapses)
    worst = std::max(worst, std::abs(a.energy - f.apoapses.front().energy) / std::abs(f.apoapses.front().energy));
  return worst;
}

TEST(SpaceScene, LoadsWithAPlanetAreaUnderUniformGravityAndAnOrbitAreaUnderNBody) {
  Space s;
  s.w().start();
  EXPECT_TRUE(s.w().has_stage("gravity.uniform@planet"));
  EXPECT_TRUE(s.w().has_stage("gravity.nbody@orbit"));
  EXPECT_FALSE(s.w().has_stage("gravity.uniform"));  // the scene uses gravity.nbody globally
  EXPECT_EQ(s.w().area_of(s.probe), "planet");
  EXPECT_EQ(s.w().area_of(s.crate), "planet");
  EXPECT_EQ(s.w().area_of(s.planet), "orbit");
  // On the tower top: the area's constant g, Newton's value at the launch point.
  const Vec3 g = s.vec(s.crate, "gravity");
  EXPECT_EQ(g.x, 0);
  EXPECT_NEAR(g.y, -s.gm / 36, 1e-12);
  EXPECT_THROW(s.w().get(s.planet, "gravity"), AccessError);  // static: a source only
}

TEST(SpaceScene, TheProbeLeavesThePlanetAreaAndOrbitsTenTimesKeepingItsEnergy) {
  Space s;
  const Flight f = fly(s, 10);
  ASSERT_EQ(f.apoapses.size(), 10u);
  // From the planet area into the orbit area, then once per orbit briefly
  // back through the planet area as it passes over the tower.
  ASSERT_GE(f.areas.size(), 3u);
  EXPECT_EQ(f.areas[0], "planet");
  EXPECT_EQ(f.areas[1], "orbit");
  for (std::size_t i = 1; i < f.areas.size(); ++i) EXPECT_EQ(f.areas[i], i % 2 ? "orbit" : "planet");
  EXPECT_LE(f.longest_stay_in_planet, 5);  // 10 cm at 5.9 m/s: 4 steps of 1/240 s
  // Closed: every pass over the tower is at the launch height (6 m), and the
  // apoapsis stays where it was.
  ASSERT_EQ(f.launch_passes.size(), 9u);  // between the first and the tenth apoapsis
  for (double r : f.launch_passes) EXPECT_NEAR(r, 6.0, 0.01);
  for (const Apoapsis& a : f.apoapses) {
    EXPECT_NEAR(a.r, f.apoapses[0].r, 0.005);
    EXPECT_NEAR(a.angle, f.apoapses[0].angle, 0.01);
  }
  // The criterion: the energy in the orbit area drifts by less than
  // 0.1 % over ten orbits.
  const double worst = drift(f);
  std::printf("energy at apoapsis over %zu orbits: worst change %.2e of %.6f J/kg\n", f.apoapses.size(), worst,
              f.apoapses[0].energy);
  EXPECT_LT(worst, 1e-3);
  // Kepler's third law for the orbit the probe is on (a from its energy).
  const double a = -s.gm / (2 * f.apoapses[0].energy);
  const double kepler = 2 * kPi * std::sqrt(a * a * a / s.gm);
  const double period = (f.apoapses.back().time - f.apoapses.front().time) / double(f.apoapses.size() - 1);
  EXPECT_NEAR(period, kepler, 1e-3 * kepler);
}

// The figures of docs/gravity.md (not run by ctest: 2 s, and the criterion is
// checked at the scene's own dt above):
//   build-space/tests/resolvers/gravity/space_scene_tests
//     --gtest_also_run_disabled_tests --gtest_filter='SpaceScene.DISABLED_Figures*'
TEST(SpaceScene, DISABLED_Figures) {
  std::printf("%-8s %-14s %-14s %-14s %-14s %-14s\n", "dt", "drift/orbit", "worst of 10", "swing in orbit",
              "period-Kepler", "apsis turn/orbit");
  for (double dt : {1.0 / 240, 1.0 / 960}) {
    Space s(dt);
    const Flight f = fly(s, 10);
    ASSERT_EQ(f.apoapses.size(), 10u);
    const Apoapsis &a0 = f.apoapses.front(), &a9 = f.apoapses.back();
    const double e = std::abs(a0.energy);
    const double a = -s.gm / (2 * a0.energy);
    const double kepler = 2 * kPi * std::sqrt(a * a * a / s.gm);
    const double period = (a9.time - a0.time) / 9;
    std::printf("1/%-6.0f %-14.2e %-14.2e %-14.2e %-14.2e %-14.2e\n", 1 / dt, (a9.energy - a0.energy) / 9 / e,
                drift(f), f.swing / e, (period - kepler) / kepler, (a9.angle - a0.angle) / 9);
    EXPECT_LT(drift(f), 1e-3);
  }
}

/// A copy of mods/space whose planet area is `half_width` m wide on each side.
std::filesystem::path space_with_planet_area(const std::string& half_width) {
  namespace fs = std::filesystem;
  const fs::path source = fs::path(ALLOY_SOURCE_DIR) / "mods/space";
  const fs::path dir = fs::temp_directory_path() / ("alloy_space_" + half_width) / "space";
  fs::create_directories(dir);
  fs::copy_file(source / "mod.lua", dir / "mod.lua", fs::copy_options::overwrite_existing);
  std::ifstream in(source / "scene.lua");
  std::stringstream text;
  text << in.rdbuf();
  std::string scene = text.str();
  const std::string key = "half_extents = { 0.05,";
  const auto at = scene.find(key);
  if (at == std::string::npos) throw std::runtime_error("the planet area of mods/space is not 0.05 m wide any more");
  scene.replace(at, key.size(), "half_extents = { " + half_width + ",");
  std::ofstream(dir / "scene.lua") << scene;
  return dir;
}

// Wider planet areas: the passes over the tower do more work (same command).
TEST(SpaceScene, DISABLED_FiguresByAreaWidth) {
  std::printf("%-12s %-14s %-14s\n", "half width", "drift/orbit", "worst of 10");
  for (const char* half_width : {"0.05", "0.15", "0.5"}) {
    Space s(0, space_with_planet_area(half_width));
    const Flight f = fly(s, 10);
    ASSERT_EQ(f.apoapses.size(), 10u);
    const Apoapsis &a0 = f.apoapses.front(), &a9 = f.apoapses.back();
    std::printf("%-12s %-14.2e %-14.2e\n", half_width, (a9.energy - a0.energy) / 9 / std::abs(a0.energy), drift(f));
  }
}

// --- swapping the planet area's gravity model --------------------------------------------

/// Every property of every object, as raw bytes, by (slot, property).
std::map<std::pair<std::uint32_t, PropertyId>, std::string> snapshot(const World& w) {
  std::map<std::pair<std::uint32_t, PropertyId>, std::string> out;
  const PropertyStore& store = w.store();
  for (PropertyId p = 0; p < w.properties().size(); ++p) {
    const ColumnBase* c = store.find_column(p);
    if (!c) continue;
    for (std::uint32_t slot : c->members()) {
      std::string bytes = std::visit(
          [](const auto& v) {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, std::string>) return v;
            else if constexpr (std::is_same_v<T, RefList>)
              return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(ObjectId));
            else return std::string(reinterpret_cast<const char*>(&v), sizeof v);
          },
          c->get_value(slot));
      out[{slot, p}] = std::move(bytes);
    }
  }
  return out;
}

/// Swaps gravity.uniform for gravity.nbody in the planet area and checks that
/// every property of every object is bit for bit what it was, except the
/// `gravity` of the objects in the planet area, which is now Newton's.
void swap_and_compare(Space& s) {
  World& w = s.w();
  const auto before = snapshot(w);
  w.swap("planet", "gravity.uniform", "gravity.nbody");
  const auto after = snapshot(w);
  ASSERT_TRUE(w.has_stage("gravity.nbody@planet"));
  ASSERT_FALSE(w.has_stage("gravity.uniform@planet"));
  const PropertyId gravity = w.properties().id("gravity");
  EXPECT_GT(before.size(), 40u);  // position, orientation, velocity, mass, shape, ... of every object
  EXPECT_NE(before.at({s.crate.index, gravity}), after.at({s.crate.index, gravity}));  // now Newton's
  std::vector<std::string> changed;
  for (const auto& [key, bytes] : before) {
    const auto it = after.find(key);
    const std::string what = w.describe(w.store().id_at(key.first)) + "." + w.properties().def(key.second).name;
    if (it == after.end()) {
      changed.push_back(what + " (gone)");
    } else if (it->second != bytes && !(key.second == gravity && w.area_of(w.store().id_at(key.first)) == "planet")) {
      changed.push_back(what);
    }
  }
  for (const auto& [key, bytes] : after)
    if (!before.count(key)) changed.push_back(w.describe(w.store().id_at(key.first)) + "." +
                                              w.properties().def(key.second).name + " (new)");
  EXPECT_TRUE(changed.empty()) << [&] {
    std::string all;
    for (const auto& c : changed) all += " " + c;
    return "changed:" + all;
  }();
  // The planet area's bodies now feel Newton's field of every mass.
  for (ObjectId o : {s.crate, s.probe}) {
    if (w.area_of(o) != "planet") continue;
    std::vector<Vec3> xs;
    std::vector<double> ms;
    for (ObjectId src : {s.planet, s.crate, s.probe}) {
      xs.push_back(s.vec(src, "position"));
      ms.push_back(std::get<double>(w.get(src, "mass")));
    }
    std::vector<Vec3> a(1);
    gravity::accelerations(std::vector<Vec3>{s.vec(o, "position")}, xs, ms, s.G, 0.01, a);
    EXPECT_EQ(s.vec(o, "gravity"), a[0]) << w.describe(o);
  }
}

TEST(SpaceScene, SwappingUniformForNBodyInThePlanetAreaKeepsEveryProperty) {
  Space s;
  World& w = s.w();
  w.run(20 * 240);  // in orbit, past the first apoapsis
  ASSERT_EQ(w.area_of(s.probe), "orbit");
  const Vec3 crate = s.vec(s.crate, "position");
  swap_and_compare(s);
  // The orbit goes on, now without uniform gravity anywhere: its energy at
  // apoapsis is kept to rounding, and the crate stays on the tower.
  const Flight f = fly(s, 3);
  ASSERT_EQ(f.apoapses.size(), 3u);
  EXPECT_LT(drift(f), 1e-6);
  EXPECT_LT(length(s.vec(s.crate, "position") - crate), 1e-3);
}

TEST(SpaceScene, SwappingWhileTheProbeCrossesThePlanetAreaKeepsEveryProperty) {
  Space s;
  World& w = s.w();
  w.run(10 * 240);
  while (w.area_of(s.probe) != "planet") w.step();  // passing over the tower
  swap_and_compare(s);
  w.step();
  EXPECT_NE(w.area_of(s.probe), "");
}

}  // namespace
}  // namespace alloy
