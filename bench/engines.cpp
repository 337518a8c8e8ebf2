// alloy_bench_engines: the rigid body's two engines side by side in one run
// (issue 15): ODE's `rigid_body` and Box2D's `rigid_body.box2d`, on
//
//   pile          1,000 boxes of 0.2 m and 1 kg in the plane (50 columns of 20,
//                 resting on a floor), 1 s. Closed form: nothing moves; the
//                 error is the RMS distance of the boxes from where they were
//                 put (how far the stack sinks and sways).
//   large_pyramid Box2D's own benchmark (v3 samples, "Large Pyramid"): a
//                 pyramid of base 100 (5,050 boxes of 1 m, 1 kg, friction 0.6)
//                 on a ground whose top is y = 0, boxes touching side by side,
//                 0.5 s. Error as for the pile (it should stand still). Box2D
//                 runs it at scale 1 (metres), as its own benchmark does.
//   chain         50 links of 0.1 m hinged end to end, the first to the play
//                 area, released level; 1 s. Error: the last link's position
//                 against the same engine at a fine step (1/3840 s).
//   doorbell      mods/doorbell: the strike period (bench/coupled_scenes.hpp),
//   motor         mods/motor: the steady speed; each against the same engine
//                 at a fine step.
//
// over the world's step, timing CPU seconds per step; the points of each
// scene, both engines together, are reduced to their Pareto front (cost,
// error) and the kit scenes' default engine is chosen from it (see choose()).
//
// Then the harness over raw Box2D on the pile: the world stepping the pile on
// rigid_body.box2d (its collisions.box2d, gravity and its interaction) against
// a loop written by hand over Box2D with the same bodies, units, iterations
// and step, stepped in lockstep rounds as alloy_bench_rigid does for ODE
// (whose ratio is the "overhead" section). Goal: <= 1.02 (session 18: 1.04
// and 1.02 in two runs at load 15, main's 1.08 and 1.06 alternated with them;
// docs/performance.md, "engines").
//
//   build/bench/alloy_bench_engines [--quick] [--out DIR] [--docs FILE] [--no-progress]
//                                   [--overhead-only | --pile-study | --substep-study]
//
// --overhead-only: the harness ratio alone (a few seconds). --pile-study: why
// the Box2D pile sank at 1/120 s with one Box2D step a step (its settings
// varied, sink and sway over 2 s; docs/performance.md). --substep-study: the
// Box2D scenes at 1/60, 1/120 and 1/240 s with 1, 2, 4 and 8 Box2D steps a
// step, work against error (how max_substep was chosen; docs/box2d.md);
// ALLOY_STUDY_SCENE=NAME runs one scene of it.
//
// Writes docs/bench/engines.csv and the "engines" section of
// docs/performance.md. Quick mode (ctest) runs small sizes and checks that
// every scene runs on both engines and that the resting pile stays within
// 1 cm on both; it exits 1 if not.
#include <box2d/box2d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/common/bench_common.hpp"
#include "bench/coupled_scenes.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"

namespace {

using namespace alloy;
using alloy::bench::Csv;
using alloy::bench::fmt;
using alloy::bench::Table;

enum class Engine { Ode, Box2D };
constexpr Engine kEngines[] = {Engine::Ode, Engine::Box2D};
const char* name_of(Engine e) {
  return e == Engine::Ode ? "ODE" : "Box2D";
}
const char* key_of(Engine e) {
  return e == Engine::Ode ? "rigid_body" : "rigid_body.box2d";
}

/// `box2d_substeps` > 0: Box2D takes that many steps a world step, whatever
/// its max_substep (the substep study); 0: the engine's defaults.
WorldDef world_def(Engine e, double dt, double box2d_scale = 0, int box2d_substeps = 0) {
  WorldDef def;
  def.dt = dt;
  if (e == Engine::Box2D) {
    def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
    if (box2d_scale > 0) def.settings["rigid_body.box2d"].set("scale", box2d_scale);
    if (box2d_substeps > 0) {
      def.settings["rigid_body.box2d"].set("substeps", std::int64_t(box2d_substeps));
      def.settings["rigid_body.box2d"].set("max_substep", 0.0);
    }
  }
  return def;
}

struct Box {
  Vec3 position;
  Vec3 size;
  double mass;
};

/// A box scene laid out once and built on either engine (or by hand on Box2D).
struct Layout {
  std::vector<Box> boxes;
  Box floor;
  double friction = 0.5;
};

/// `columns` columns of `rows` boxes of 0.2 m, 1 kg, 2 cm apart, on a floor at y = 0.
Layout pile_layout(int columns, int rows) {
  Layout l;
  const double a = 0.2, pitch = 0.22;
  for (int i = 0; i < columns; ++i)
    for (int j = 0; j < rows; ++j)
      l.boxes.push_back({{(i - (columns - 1) / 2.0) * pitch, a / 2 + a * j, 0}, {a, a, a}, 1.0});
  l.floor = {{0, -0.5, 0}, {pitch * columns + 2, 1, 1}, 0};
  return l;
}

/// Box2D's large_pyramid: base `base`, boxes of 1 m touching, ground top at y = 0.
Layout pyramid_layout(int base) {
  Layout l;
  const double h = 0.5;
  for (int i = 0; i < base; ++i)
    for (int j = i; j < base; ++j)
      l.boxes.push_back(
          {{(i + 1) * h + 2 * (j - i) * h - h * base, (2 * i + 1) * h, 0}, {1, 1, 1}, 1.0});
  l.floor = {{0, -1, 0}, {200, 2, 1}, 0};
  l.friction = 0.6;
  return l;
}

std::vector<ObjectId> build(World& w, const Layout& l) {
  const ObjectId f = w.create("floor");
  w.set(f, "shape", std::string("box"));
  w.set(f, "size", l.floor.size);
  w.set(f, "position", l.floor.position);
  w.set(f, "static", true);
  w.set(f, "friction", l.friction);
  std::vector<ObjectId> out;
  for (const Box& b : l.boxes) {
    const ObjectId o = w.create();
    w.set(o, "shape", std::string("box"));
    w.set(o, "size", b.size);
    w.set(o, "mass", b.mass);
    w.set(o, "position", b.position);
    w.set(o, "planar", true);  // ODE: kept in the plane, as the kit's parts are
    w.set(o, "friction", l.friction);
    out.push_back(o);
  }
  return out;
}

/// The engine's plugins and everything native, as `alloy run` has them.
struct Harness {
  PluginRegistry registry;
  std::unique_ptr<World> world;
  explicit Harness(WorldDef def) {
    register_native_plugins(registry);
    world = std::make_unique<World>(registry, std::move(def));
  }
};

Vec3 position(const World& w, ObjectId o) {
  return std::get<Vec3>(w.get(o, "position"));
}

// --- the baseline: Box2D by hand ---------------------------------------------------

/// What a programmer writes with Box2D alone: a world with gravity, a static
/// ground, a body and a fixture per box, Step, and the poses read back (as
/// the harness writes them to its columns). The same units (x scale), mass,
/// friction, iterations and step as rigid_body.box2d's defaults.
class RawBox2DPile {
 public:
  RawBox2DPile(const Layout& l, double dt, double scale, int velocity_iterations,
               int position_iterations, int substeps)
      : world_(b2Vec2(0, float(-9.81 * scale))),
        dt_(float(dt / substeps)),
        substeps_(substeps),
        vi_(velocity_iterations),
        pi_(position_iterations),
        s_(scale) {
    world_.SetAllowSleeping(false);
    b2BodyDef gd;
    gd.position.Set(float(l.floor.position.x * s_), float(l.floor.position.y * s_));
    b2Body* ground = world_.CreateBody(&gd);
    b2PolygonShape gs = box(l.floor.size);
    b2FixtureDef gf;
    gf.shape = &gs;
    gf.friction = float(l.friction);
    ground->CreateFixture(&gf);
    for (const Box& b : l.boxes) {
      b2BodyDef bd;
      bd.type = b2_dynamicBody;
      bd.position.Set(float(b.position.x * s_), float(b.position.y * s_));
      b2Body* body = world_.CreateBody(&bd);
      b2PolygonShape shape = box(b.size);
      b2FixtureDef fd;
      fd.shape = &shape;
      fd.friction = float(l.friction);
      fd.density = float(b.mass / (b.size.x * b.size.y * s_ * s_));
      body->CreateFixture(&fd);
      bodies_.push_back(body);
    }
    poses_.resize(bodies_.size());
  }
  /// A box whose skin (b2_polygonRadius) lies inside its size, as
  /// rigid_body.box2d builds it, so that both piles have the same geometry
  /// (a plain SetAsBox stands 1 mm proud at scale 10, and the raw pile spread
  /// 3.4 cm from the harness's).
  b2PolygonShape box(Vec3 size) const {
    const float hx = float(size.x / 2 * s_), hy = float(size.y / 2 * s_);
    const float skin = std::min(b2_polygonRadius, 0.5f * std::min(hx, hy));
    b2PolygonShape shape;
    shape.SetAsBox(hx - skin, hy - skin);
    shape.m_radius = skin;
    return shape;
  }
  void step() {
    for (int k = 0; k < substeps_; ++k) world_.Step(dt_, vi_, pi_);
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const b2Vec2 p = bodies_[i]->GetPosition(), v = bodies_[i]->GetLinearVelocity();
      poses_[i] = {p.x / s_, p.y / s_, bodies_[i]->GetAngle(),
                   v.x / s_, v.y / s_, bodies_[i]->GetAngularVelocity()};
    }
  }
  int contacts() {
    int n = 0;
    for (b2Contact* c = world_.GetContactList(); c; c = c->GetNext()) n += c->IsTouching();
    return n;
  }
  Vec3 position(std::size_t i) const { return {poses_[i][0], poses_[i][1], 0}; }

 private:
  b2World world_;
  float dt_;  // of one Box2D step
  int substeps_;
  int vi_, pi_;
  double s_;
  std::vector<b2Body*> bodies_;
  std::vector<std::array<double, 6>> poses_;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? NAN : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

struct Overhead {
  int boxes = 0, steps = 0, rounds = 0;
  double raw_s = 0, harness_s = 0;  ///< summed CPU seconds
  double ratio = NAN;               ///< median of the rounds' ratios
  int raw_contacts = 0, harness_pairs = 0;
  double drift = NAN;  ///< largest distance between the two runs' boxes at the end, m
  std::size_t stages = 0;
  int substeps = 1;  ///< Box2D steps a world step, on both sides
};

Overhead measure_overhead(const Layout& l, int settle, int rounds, int per_round,
                          bench::Progress& progress) {
  constexpr double dt = 1.0 / 240;
  const box2d::Box2DConfig cfg;  // rigid_body.box2d's defaults, which the harness runs
  // Box2D stepped as the engine steps it: as many steps a world step as its
  // substeps and max_substep make (one at 1/240 s).
  RawBox2DPile raw(l, dt, cfg.scale, cfg.velocity_iterations, cfg.position_iterations,
                   box2d::substeps_for(cfg, dt));
  Harness h(world_def(Engine::Box2D, dt));
  const std::vector<ObjectId> ids = build(*h.world, l);
  h.world->start();
  for (int i = 0; i < settle; ++i) raw.step(), h.world->step();
  Overhead r;
  r.boxes = int(l.boxes.size()), r.rounds = rounds, r.steps = rounds * per_round;
  r.stages = h.world->active_stages().size();
  r.substeps = box2d::substeps_for(cfg, dt);
  std::vector<double> ratios;
  for (int round = 0; round < rounds; ++round) {
    double t_raw = 0, t_h = 0;
    for (int k = 0; k < 2; ++k) {  // who goes first alternates
      if ((round + k) % 2 == 0)
        t_raw = bench::cpu_time([&] {
          for (int i = 0; i < per_round; ++i) raw.step();
        });
      else
        t_h = bench::cpu_time([&] {
          for (int i = 0; i < per_round; ++i) h.world->step();
        });
    }
    r.raw_s += t_raw, r.harness_s += t_h;
    ratios.push_back(t_h / t_raw);
    progress.tick();
  }
  r.ratio = median(ratios);
  r.raw_contacts = raw.contacts();
  if (const auto* set = dynamic_cast<const ContactSet*>(h.world->stage("collisions.box2d")))
    r.harness_pairs = int(set->began().size() + set->ongoing().size());
  r.drift = 0;
  for (std::size_t i = 0; i < ids.size(); ++i)
    r.drift = std::max(r.drift, length(position(*h.world, ids[i]) - raw.position(i)));
  return r;
}

// --- work and error ------------------------------------------------------------------

struct Point {
  std::string scene;
  Engine engine;
  double dt;
  double cpu_per_step = NAN;  ///< CPU s
  double cost = NAN;          ///< CPU s per simulated s
  double error = NAN;         ///< NaN: the run failed (the scene did not work)
  std::string unit;           ///< of the error
  bool front = false;
};

/// The resting box scenes: RMS distance of the boxes from their start after `seconds`.
Point resting(const std::string& scene, const Layout& l, Engine e, double dt, double seconds,
              double box2d_scale, int box2d_substeps = 0) {
  Harness h(world_def(e, dt, box2d_scale, box2d_substeps));
  const std::vector<ObjectId> ids = build(*h.world, l);
  h.world->start();
  const auto steps = std::uint64_t(std::llround(seconds / dt));
  Point p{scene, e, dt};
  const double cpu = bench::cpu_time([&] { h.world->run(steps); });
  p.cpu_per_step = cpu / double(steps);
  p.cost = cpu / seconds;
  double sum = 0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Vec3 d = position(*h.world, ids[i]) - l.boxes[i].position;
    sum += dot(d, d);
  }
  p.error = std::sqrt(sum / double(ids.size()));
  p.unit = "m RMS from rest";
  return p;
}

/// Why the resting pile moves on Box2D at a large step (`--pile-study`): the
/// pile at 1/120 and 1/240 s under variations of rigid_body.box2d's
/// settings, each printed with the RMS distance from rest, the mean sink (y)
/// and the RMS sideways sway (x).
void pile_study(const Layout& l) {
  struct Variant {
    const char* name;
    std::vector<std::pair<const char*, double>> settings;
  };
  const Variant variants[] = {
      {"one Box2D step", {}},
      {"position_iterations 3", {{"position_iterations", 3}}},
      {"position_iterations 30", {{"position_iterations", 30}}},
      {"velocity_iterations 8", {{"velocity_iterations", 8}}},
      {"velocity_iterations 60", {{"velocity_iterations", 60}}},
      {"substeps 2", {{"substeps", 2}}},
      {"scale 5", {{"scale", 5}}},
      {"scale 20", {{"scale", 20}}},
      {"scale 20, position 30", {{"scale", 20}, {"position_iterations", 30}}}};
  for (double dt : {1.0 / 120, 1.0 / 240})
    for (const Variant& v : variants) {
      // One Box2D step a world step unless a variant says otherwise (what
      // the engine took before max_substep).
      WorldDef def = world_def(Engine::Box2D, dt, 0, 1);
      for (const auto& [k, x] : v.settings) def.settings["rigid_body.box2d"].set(k, x);
      Harness h(std::move(def));
      const std::vector<ObjectId> ids = build(*h.world, l);
      h.world->start();
      double at = 0;
      for (double t : {0.25, 0.5, 1.0, 2.0}) {
        h.world->run(std::uint64_t(std::llround((t - at) / dt)));
        at = t;
        double sum = 0, sink = 0, sway = 0;
        for (std::size_t i = 0; i < ids.size(); ++i) {
          const Vec3 d = position(*h.world, ids[i]) - l.boxes[i].position;
          sum += dot(d, d), sink += d.y, sway += d.x * d.x;
        }
        const double n = double(ids.size());
        std::printf("pile 1/%.0f %-24s at %.2f s: RMS %.4g m, mean dy %.4g m, RMS dx %.4g m\n",
                    1 / dt, v.name, t, std::sqrt(sum / n), sink / n, std::sqrt(sway / n));
      }
    }
}

/// The chain: `links` links, the last one's position after `seconds`.
Point chain(int links, Engine e, double dt, double seconds, Vec3* end, int box2d_substeps = 0) {
  Harness h(world_def(e, dt, 0, box2d_substeps));
  World& w = *h.world;
  const double len = 0.1, y = 1.0;
  ObjectId prev;
  for (int k = 0; k < links; ++k) {
    const ObjectId o = w.create();
    w.set(o, "shape", std::string("box"));
    w.set(o, "size", Vec3{len, 0.02, 0.02});
    w.set(o, "mass", 0.05);
    w.set(o, "position", Vec3{len * (k + 0.5), y, 0});
    w.set(o, "planar", true);
    const ObjectId j = w.create();
    w.set(j, "joint", std::string("hinge"));
    w.set(j, "body_a", o);
    if (!prev.is_null()) w.set(j, "body_b", prev);
    w.set(j, "anchor", Vec3{len * k, y, 0});
    w.set(j, "axis", Vec3{0, 0, 1});
    prev = o;
  }
  w.start();
  const auto steps = std::uint64_t(std::llround(seconds / dt));
  Point p{"chain", e, dt};
  const double cpu = bench::cpu_time([&] { w.run(steps); });
  p.cpu_per_step = cpu / double(steps);
  p.cost = cpu / seconds;
  *end = position(w, prev);
  p.unit = "m (last link vs fine step)";
  return p;
}

/// A kit scene through bench/coupled_scenes.hpp, on engine `e`.
Point kit(const bench::coupled::Scene& scene, Engine e, double dt, double* value,
          int box2d_substeps = 0) {
  bench::coupled::Rates r;
  r.dt = dt;
  if (e == Engine::Box2D) r.engine = "box2d", r.box2d_substeps = box2d_substeps;
  const bench::coupled::Measure m = scene.measure(r);
  Point p{scene.mod, e, dt};
  p.cpu_per_step = m.steps ? m.cpu / double(m.steps) : NAN;
  p.cost = m.cost();
  *value = m.value;
  p.unit = "relative, " + scene.quantity + " vs fine step";
  return p;
}

/// How many Box2D steps a world step should take (`--substep-study`):
/// every Box2D scene at 1/60, 1/120 and 1/240 s with 1, 2, 4 and 8 Box2D
/// steps a world step, CPU per world step against the error (the resting
/// scenes' RMS from rest; the chain's and the kit scenes' against the same
/// engine at 1/3840 s with one Box2D step a step). Printed as a table
/// (docs/box2d.md, "Box2D's step and the world's"); `only` names one scene,
/// or empty for all.
void substep_study(const Layout& pile, const Layout& pyramid, int links,
                   const std::vector<bench::coupled::Scene>& kits, const std::string& only) {
  const double steps[] = {1.0 / 60, 1.0 / 120, 1.0 / 240};
  const int counts[] = {1, 2, 4, 8};
  const double reference_dt = 1.0 / 3840;
  Table t({"scene", "step", "Box2D steps", "internal step", "CPU ms/step", "error"});
  auto row = [&](const Point& p, int n) {
    t.row({p.scene, bench::coupled::step_name(p.dt), std::to_string(n),
           bench::coupled::step_name(p.dt / n), fmt(1e3 * p.cpu_per_step, 3),
           std::isfinite(p.error) ? fmt(p.error, 3) : std::string("fails")});
    std::printf("%s 1/%.0f x%d: %.4g ms/step, error %.4g (%s)\n", p.scene.c_str(), 1 / p.dt, n,
                1e3 * p.cpu_per_step, p.error, p.unit.c_str());
    std::fflush(stdout);
  };
  auto wanted = [&](const char* s) { return only.empty() || only == s; };
  if (wanted("pile"))
    for (double dt : steps)
      for (int n : counts) row(resting("pile", pile, Engine::Box2D, dt, 0.5, 0, n), n);
  if (wanted("large_pyramid"))
    for (double dt : steps)
      for (int n : counts) row(resting("large_pyramid", pyramid, Engine::Box2D, dt, 0.25, 1, n), n);
  if (wanted("chain")) {
    Vec3 ref;
    chain(links, Engine::Box2D, reference_dt, 1.0, &ref, 1);
    for (double dt : steps)
      for (int n : counts) {
        Vec3 end;
        Point p = chain(links, Engine::Box2D, dt, 1.0, &end, n);
        p.error = length(end - ref);
        row(p, n);
      }
  }
  for (const auto& scene : kits) {
    if (!wanted(scene.mod.c_str())) continue;
    double ref = NAN, v = NAN;
    kit(scene, Engine::Box2D, reference_dt, &ref, 1);
    for (double dt : steps)
      for (int n : counts) {
        Point p = kit(scene, Engine::Box2D, dt, &v, n);
        p.error = std::isfinite(ref) && std::isfinite(v) ? std::abs(v - ref) / std::abs(ref) : NAN;
        row(p, n);
      }
  }
  std::printf("\n%s", t.str().c_str());
}

/// Marks each scene's Pareto front over both engines' points.
void mark_fronts(std::vector<Point>& pts) {
  std::vector<std::string> scenes;
  for (const Point& p : pts)
    if (std::find(scenes.begin(), scenes.end(), p.scene) == scenes.end()) scenes.push_back(p.scene);
  for (const std::string& s : scenes) {
    std::vector<std::size_t> idx;
    std::vector<double> cost, err;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (pts[i].scene == s && std::isfinite(pts[i].error) && std::isfinite(pts[i].cost))
        idx.push_back(i), cost.push_back(pts[i].cost),
            err.push_back(std::max(pts[i].error, 1e-300));
    for (std::size_t k : bench::pareto_front(cost, err)) pts[idx[k]].front = true;
  }
}

/// The cheapest point of `engine` on `scene` whose error is within `tolerance`, or null.
const Point* cheapest_within(const std::vector<Point>& pts, const std::string& scene, Engine e,
                             double tolerance) {
  const Point* best = nullptr;
  for (const Point& p : pts)
    if (p.scene == scene && p.engine == e && std::isfinite(p.error) && p.error <= tolerance &&
        (!best || p.cost < best->cost))
      best = &p;
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options o = bench::Options::parse(
      argc, argv, "alloy_bench_engines", {"--overhead-only", "--pile-study", "--substep-study"});
  const bool quick = o.quick;
  // Sizes: the in full; small ones for CI.
  const Layout pile = quick ? pile_layout(10, 10) : pile_layout(50, 20);
  const Layout pyramid = pyramid_layout(quick ? 10 : 100);
  const int links = quick ? 10 : 50;
  const std::vector<double> box_steps =
      quick ? std::vector<double>{1.0 / 240}
            : std::vector<double>{1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480};
  const std::vector<double> pyramid_steps =
      quick ? std::vector<double>{1.0 / 240} : std::vector<double>{1.0 / 60, 1.0 / 240};
  const std::vector<double> fine_steps =
      quick ? std::vector<double>{1.0 / 240}
            : std::vector<double>{1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480, 1.0 / 960};
  const double reference_dt = quick ? 1.0 / 960 : 1.0 / 3840;
  const double pile_s = quick ? 0.25 : 0.5, pyramid_s = 0.25, chain_s = 1.0;
  const std::vector<bench::coupled::Scene> kit_scenes =
      quick ? std::vector<bench::coupled::Scene>{bench::coupled::doorbell_scene()}
            : std::vector<bench::coupled::Scene>{bench::coupled::doorbell_scene(),
                                                 bench::coupled::motor_scene()};
  const int rounds = quick ? 6 : 90, per_round = quick ? 4 : 8, settle = quick ? 60 : 240;

  std::size_t total = rounds + 2 * (box_steps.size() + pyramid_steps.size() + fine_steps.size() +
                                    1 + kit_scenes.size() * (fine_steps.size() + 1));
  bench::Progress progress("engines", total, o.progress);

  std::vector<Point> pts;
  // Cheapest first, each point printed as it is measured, so that a run cut
  // short still tells: the overhead, the kit scenes, the chain, then the
  // pile and the pyramid (ODE's 5,050 boxes are the longest part).
  auto add = [&](Point p) {
    std::printf("%s %s 1/%.0f: %.4g ms/step, error %.4g (%s)\n", p.scene.c_str(), name_of(p.engine),
                1 / p.dt, 1e3 * p.cpu_per_step, p.error, p.unit.c_str());
    std::fflush(stdout);
    pts.push_back(p);
    progress.tick();
  };
  if (o.flag("--pile-study")) {
    pile_study(pile);
    return 0;
  }
  if (o.flag("--substep-study")) {
    const char* only = std::getenv("ALLOY_STUDY_SCENE");  // one scene of the study
    substep_study(pile, pyramid, links,
                  {bench::coupled::doorbell_scene(), bench::coupled::motor_scene()},
                  only ? only : "");
    return 0;
  }
  const Overhead oh = measure_overhead(pile, settle, rounds, per_round, progress);
  std::printf("harness / raw Box2D: %.4f (goal <= 1.02: %s)\n", oh.ratio,
              oh.ratio <= 1.02 ? "met" : "missed");
  if (o.flag("--overhead-only")) {
    // The harness ratio alone (a few seconds), for work on the harness: the
    // raw and harness CPU ms a step, printed; nothing written.
    std::printf(
        "raw %.4f ms/step, harness %.4f ms/step, %d Box2D step(s) a step, %zu stages, drift "
        "%.3g m\n",
        1e3 * oh.raw_s / oh.steps, 1e3 * oh.harness_s / oh.steps, oh.substeps, oh.stages, oh.drift);
    return 0;
  }
  for (Engine e : kEngines)
    for (const auto& scene : kit_scenes) {
      double ref = NAN, v = NAN;
      kit(scene, e, reference_dt, &ref);
      progress.tick();
      for (double dt : fine_steps) {
        Point p = kit(scene, e, dt, &v);
        p.error = std::isfinite(ref) && std::isfinite(v) ? std::abs(v - ref) / std::abs(ref) : NAN;
        add(p);
      }
    }
  for (Engine e : kEngines) {
    Vec3 ref_end;
    chain(links, e, reference_dt, chain_s, &ref_end);
    progress.tick();
    for (double dt : fine_steps) {
      Vec3 end;
      Point p = chain(links, e, dt, chain_s, &end);
      p.error = length(end - ref_end);
      add(p);
    }
  }
  for (Engine e : kEngines)
    for (double dt : box_steps) add(resting("pile", pile, e, dt, pile_s, 0));
  for (Engine e : kEngines)
    for (double dt : pyramid_steps) add(resting("large_pyramid", pyramid, e, dt, pyramid_s, 1));
  mark_fronts(pts);

  Csv csv(o.file("engines.csv"), {"scene", "engine", "dt", "cpu_ms_per_step", "cpu_per_simulated_s",
                                  "error", "error_unit", "pareto_front"});
  for (const Point& p : pts)
    csv.row({p.scene, key_of(p.engine), Csv::cell(p.dt), Csv::cell(1e3 * p.cpu_per_step),
             Csv::cell(p.cost), Csv::cell(p.error), p.unit, Csv::cell(int(p.front))});

  std::string md =
      "\nCommand: `build/bench/alloy_bench_engines` (or `make bench`); raw data "
      "`docs/bench/engines.csv`.\n\n";
  md += "Scenes: the pile (" + std::to_string(pile.boxes.size()) + " boxes of 0.2 m in " +
        (quick ? "10 columns of 10" : "50 columns of 20") + ", resting, " + fmt(pile_s, 2) +
        " s), Box2D's large_pyramid (base " + std::to_string(quick ? 10 : 100) + ", " +
        std::to_string(pyramid.boxes.size()) + " boxes of 1 m, " + fmt(pyramid_s, 2) +
        " s; Box2D at scale 1), a " + std::to_string(links) +
        "-link chain released level (1 s), and the kit scenes (doorbell to 5 s, motor to 8 s). "
        "Error of the resting scenes: RMS distance from rest (closed form); of the others: "
        "against the same engine at " +
        bench::coupled::step_name(reference_dt) +
        " s. \"front\": on the scene's Pareto front of (CPU per simulated second, error) over "
        "both engines; \"fails\": the scene does not work on that engine (the doorbell does "
        "not ring, the motor does not turn).\n\n";
  Table t({"scene", "step", "ODE CPU ms/step", "ODE error", "Box2D CPU ms/step", "Box2D error",
           "front"});
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Point& a = pts[i];
    if (a.engine != Engine::Ode) continue;
    const Point* b = nullptr;
    for (const Point& q : pts)
      if (q.engine == Engine::Box2D && q.scene == a.scene && q.dt == a.dt) b = &q;
    if (!b) continue;
    auto err = [](const Point& p) {
      return std::isfinite(p.error) ? fmt(p.error, 3) : std::string("fails");
    };
    std::string front = a.front && b->front ? "both" : a.front ? "ODE" : b->front ? "Box2D" : "";
    t.row({a.scene, bench::coupled::step_name(a.dt), fmt(1e3 * a.cpu_per_step, 3), err(a),
           fmt(1e3 * b->cpu_per_step, 3), err(*b), front});
  }
  md += t.str();

  // The kit scenes' default engine: for each scene, the cheapest run of each
  // engine within 1 % of its fine-step figure (the kit's accuracy target for
  // these figures); an engine is chosen only if it is cheaper on every kit
  // scene, else the default stays ODE (the engine every scene was tuned on).
  const double tolerance = 0.01;
  Table c({"kit scene", "ODE: cheapest within 1 %", "Box2D: cheapest within 1 %", "cheaper"});
  int box2d_wins = 0, decided = 0;
  for (const auto& scene : kit_scenes) {
    const Point* a = cheapest_within(pts, scene.mod, Engine::Ode, tolerance);
    const Point* b = cheapest_within(pts, scene.mod, Engine::Box2D, tolerance);
    auto cell = [](const Point* p) {
      return p ? bench::coupled::step_name(p->dt) + ", " + fmt(p->cost, 3) + " s/s"
               : std::string("none");
    };
    const char* win = !a && !b            ? "neither"
                      : !b                ? "ODE"
                      : !a                ? "Box2D"
                      : b->cost < a->cost ? "Box2D"
                                          : "ODE";
    box2d_wins += std::string(win) == "Box2D";
    decided += std::string(win) != "neither";
    c.row({scene.mod, cell(a), cell(b), win});
  }
  const bool box2d_default = decided == int(kit_scenes.size()) && box2d_wins == decided;
  md +=
      "\nThe kit scenes' default engine, from the front: the cheapest run (CPU s per simulated s) "
      "of each engine whose error is within 1 %.\n\n" +
      c.str() + "\nChosen default for the kit scenes: **" +
      (box2d_default ? "rigid_body.box2d" : "rigid_body (ODE)") + "**.\n";

  char line[600];
  std::snprintf(
      line, sizeof line,
      "\nHarness over raw Box2D on the pile (%d boxes, %d steps of 1/240 s in %d rounds after "
      "%d untimed, %d Box2D step(s) a step on both; %zu stages active): raw %.4g ms/step (%d "
      "touching contacts), harness %.4g "
      "ms/step (%d pairs); ratio %.4f (median of rounds; of the sums %.4f), goal <= 1.02: "
      "%s. The two runs' boxes end within %.2g m of each other.\n",
      oh.boxes, oh.steps, oh.rounds, settle, oh.substeps, oh.stages, 1e3 * oh.raw_s / oh.steps,
      oh.raw_contacts, 1e3 * oh.harness_s / oh.steps, oh.harness_pairs, oh.ratio,
      oh.harness_s / oh.raw_s, oh.ratio <= 1.02 ? "met" : "missed", oh.drift);
  md += line;
  std::printf("\n%s", md.c_str());
  std::printf("ratio harness/raw_box2d = %.4f (goal <= 1.02: %s)\n", oh.ratio,
              oh.ratio <= 1.02 ? "met" : "missed");

  // Checks: the box scenes run on both engines (a failed run is NaN) and
  // the resting pile stays within 2 cm of rest on both at 1/120 s and finer
  // (at 1/60 s ODE's sinks 3 cm) (Box2D lets each contact sink by its linear
  // slop, 0.5 mm at scale 10: 20 layers, 1 cm). Box2D's pile depends on its
  // own step, not the world's (--substep-study): one Box2D step of 1/120 s
  // let each of a column's 20 contacts compress by about 2.3 mm in the first
  // quarter second, which its position solver took seconds to lift back (2.6
  // cm at 0.5 s; --pile-study). Since session 19 the engine takes Box2D
  // steps of at most max_substep = 1/240 s (two at 1/120 s): 7.8 mm.
  // A kit scene that does not work on an engine is reported as "fails" in
  // the table, not checked here: the kit scenes on Box2D are issue 15's own
  // item, tested in tests/ (docs/box2d.md).
  int failures = 0;
  for (const Point& p : pts) {
    const bool kit_scene = p.scene == "doorbell" || p.scene == "motor";
    const bool bad = !std::isfinite(p.cost) || (!kit_scene && !std::isfinite(p.error)) ||
                     (p.scene == "pile" && p.dt <= 1.0 / 120 && p.error > 0.02);
    if (bad)
      std::printf("check failed: %s on %s at %s: error %g %s\n", p.scene.c_str(), name_of(p.engine),
                  bench::coupled::step_name(p.dt).c_str(), p.error, p.unit.c_str()),
          ++failures;
  }
  if (!quick) bench::splice(o.docs, "engines", md);
  std::printf("checks: %s\n", failures ? "failed" : "passed");
  // The ratio's goal is a figure reported, not a check: on a shared machine a
  // run's noise is of its order (as for alloy_bench_rigid in quick mode).
  return failures ? 1 : quick || oh.ratio <= 1.02 ? 0 : 1;
}
