// Joints inside areas that have their own rigid-body engine (issue 15, item 4).
// A joint has no position: the world scopes it by the bodies it joins
// (World::split_areas). Inside one area it is that area's engine's; while its
// bodies are in two areas it is split and neither engine holds it (suspended,
// an "area_split" event naming it); it resumes when they are in one area again.
// Each test prints its figures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/engine.hpp"
#include "runtime/state_hash.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;

const std::vector<std::string> kBox2DArea = {"rigid_body.box2d", "collisions.box2d",
                                             "rigid_body_from_gravity"};
const std::vector<std::string> kOdeArea = {"rigid_body", "collisions", "rigid_body_from_collisions",
                                           "rigid_body_from_gravity"};

/// Area "right": x from 1 to 3, y from -1 to 3, with its own plugins. The
/// world's own engine is ODE unless `box2d_world`.
WorldDef with_area(std::vector<std::string> plugins, double dt = 1.0 / 240,
                   bool box2d_world = false) {
  WorldDef def;
  def.dt = dt;
  if (box2d_world)
    def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  AreaDef right;
  right.name = "right";
  right.center = {2, 1, 0};
  right.half_extents = {1, 2, 1};
  right.plugins = std::move(plugins);
  def.areas = {right};
  return def;
}

WorldDef alone(bool box2d, double dt) {
  WorldDef def;
  def.dt = dt;
  if (box2d) def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  return def;
}

rigid::RigidBodyEngine& engine(World& w, const char* stage) {
  return dynamic_cast<rigid::RigidBodyEngine&>(*w.stage(stage));
}

/// Events of type `type` about `a` in the last step.
int count_events(World& w, const std::string& type, ObjectId a, std::string* text = nullptr) {
  int n = 0;
  for (const Event& e : w.events())
    if (e.type == type && e.a == a) {
      ++n;
      if (text) *text = e.text;
    }
  return n;
}

// --- a pendulum inside an area --------------------------------------------------------

constexpr double kL = 1, kR = 0.02, kTheta = 0.05;
const Vec3 kPivot{2, 1.5, 0};  // inside "right"; the bob swings about 1 m below it

/// The period of a 1 m pendulum (a disk of 2 cm hinged to the play area at
/// kPivot, released at 0.05 rad), from the upward crossings of x over 4
/// periods; `hinge` receives the hinge's id.
double pendulum_period(Sim& s, ObjectId* hinge = nullptr) {
  const ObjectId bob = add_sphere(
      *s, kPivot + Vec3{kL * std::sin(kTheta), -kL * std::cos(kTheta), 0}, kR, 1.0, "bob");
  const ObjectId h = add_hinge(*s, bob, {}, kPivot, {0, 0, 1}, "pivot");
  if (hinge) *hinge = h;
  const double dt = s->dt();
  std::vector<double> crossings;
  double x_prev = s.position(bob).x - kPivot.x;
  const auto n = std::uint64_t(std::llround(11.0 / dt));
  for (std::uint64_t i = 1; i <= n && crossings.size() < 5; ++i) {
    s->step();
    const double x = s.position(bob).x - kPivot.x;
    if (x_prev < 0 && x >= 0) crossings.push_back((i - 1) * dt + dt * (-x_prev) / (x - x_prev));
    x_prev = x;
  }
  EXPECT_EQ(crossings.size(), 5u);
  return crossings.size() == 5 ? (crossings.back() - crossings.front()) / 4 : 0;
}

/// Physical pendulum of a disk (inertia 2/5 m r^2, as both engines give a
/// sphere in the plane): T = 2 pi sqrt((L^2 + 2/5 r^2) / (g L)), times the
/// amplitude's 1 + theta0^2 / 16.
double closed_form_period() {
  return 2 * kPi * std::sqrt((kL * kL + 0.4 * kR * kR) / (kG * kL)) * (1 + kTheta * kTheta / 16);
}

void pendulum_in_area_matches_alone(bool area_box2d) {
  const double T = closed_form_period();
  for (double h : {1.0 / 240, 1.0 / 480}) {
    Sim in_area(with_area(area_box2d ? kBox2DArea : kOdeArea, h, !area_box2d));
    ObjectId hinge;
    const double t_area = pendulum_period(in_area, &hinge);
    const char* stage = area_box2d ? "rigid_body.box2d@right" : "rigid_body@right";
    EXPECT_EQ(in_area->area_of(hinge), "right");
    EXPECT_EQ(engine(*in_area, stage).joint_count(), 1u) << "the area's engine holds the hinge";
    Sim by_itself(alone(area_box2d, h));
    const double t_alone = pendulum_period(by_itself);
    std::printf(
        "pendulum in a%s area of a%s world at 1/%.0f s: period %.6f s, alone on %s %.6f s, "
        "closed form %.6f s (error %.2e)\n",
        area_box2d ? " Box2D" : "n ODE", area_box2d ? "n ODE" : " Box2D", 1 / h, t_area,
        area_box2d ? "Box2D" : "ODE", t_alone, T, std::abs(t_area - T) / T);
    EXPECT_NEAR(t_area, t_alone, 1e-9 * T) << "the area's engine is that engine, nothing added";
    EXPECT_LE(std::abs(t_area - T) / T, 2e-3);
  }
}

TEST(AreaJoints, AHingedPendulumInABox2DAreaOfAnOdeWorldSwingsAsOnBox2DAlone) {
  pendulum_in_area_matches_alone(true);
}

TEST(AreaJoints, AHingedPendulumInAnOdeAreaOfABox2DWorldSwingsAsOnOdeAlone) {
  pendulum_in_area_matches_alone(false);
}

// --- a spring inside an area -----------------------------------------------------------

/// A 0.5 kg ball on a 50 N/m spring to the board at kPivot, stretched 0.1 m
/// past its 0.5 m rest length along x, no gravity; its period from the
/// upward crossings over 8 periods.
double spring_period(Sim& s, ObjectId* spring = nullptr) {
  const double rest = 0.5, stretch = 0.1;
  const ObjectId ball = add_sphere(*s, kPivot + Vec3{rest + stretch, 0, 0}, 0.02, 0.5, "ball");
  const ObjectId sp = s->create("spring");
  s->set(sp, "spring_a", ball);
  s->set(sp, "spring_anchor_a", Vec3{});
  s->set(sp, "spring_anchor_b", kPivot);
  s->set(sp, "spring_stiffness", 50.0);
  s->set(sp, "spring_rest_length", rest);
  if (spring) *spring = sp;
  const double dt = s->dt();
  std::vector<double> crossings;
  double x_prev = stretch;
  for (auto i = std::llround(8 * 0.6283 / dt); i > 0; --i) {
    s->step();
    const Vec3 d = s.position(ball) - kPivot;
    const double x = std::sqrt(dot(d, d)) - rest;
    if (x_prev < 0 && x >= 0)
      crossings.push_back(double(s->step_count() - 1) * dt + dt * (-x_prev) / (x - x_prev));
    x_prev = x;
  }
  return crossings.size() >= 2
             ? (crossings.back() - crossings.front()) / double(crossings.size() - 1)
             : 0;
}

TEST(AreaJoints, ASpringInABox2DAreaOfAnOdeWorldPullsAsOnBox2DAlone) {
  // A spring is scoped like a joint: by the parts it pulls. In the area it is
  // the area's spring interaction's, queued on the area's engine, whether the
  // area lists the interaction or not: an adversary's area listing only the
  // engine, its contacts and gravity (as mods/two_engines does) had left the
  // global spring interaction queuing on ODE, which does not hold the ball,
  // and the spring did nothing, silently.
  const double T = 2 * kPi * std::sqrt(0.5 / 50);
  WorldDef def_alone = alone(true, 1.0 / 240);
  def_alone.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  Sim by_itself(def_alone);
  const double t_alone = spring_period(by_itself);
  for (const bool listed : {true, false}) {
    std::vector<std::string> plugins = kBox2DArea;
    if (listed) plugins.push_back("rigid_body_from_springs");
    WorldDef def = with_area(plugins);
    def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
    Sim in_area(def);
    ObjectId spring;
    const double t_area = spring_period(in_area, &spring);
    std::printf(
        "spring in a Box2D area of an ODE world (%s): period %.6f s, alone on Box2D %.6f s, "
        "closed form %.6f s\n",
        listed ? "listed" : "not listed", t_area, t_alone, T);
    EXPECT_EQ(in_area->area_of(spring), "right");
    EXPECT_TRUE(in_area->has_stage("rigid_body_from_springs@right")) << listed;
    EXPECT_NEAR(t_area, t_alone, 1e-9) << listed;
    EXPECT_LT(std::abs(t_area - T) / T, 2e-3) << listed;
  }
}

// --- a glued pair crossing into a Box2D area -------------------------------------------

struct GluedPair {
  ObjectId a, b, glue;
};

/// Two tables meeting at x = 1, the left one the world's (ODE), the right one
/// in area "right" (Box2D); a glued pair of boxes sliding right at 2 m/s.
GluedPair build_glued_slide(World& w) {
  const ObjectId left = add_floor(w, 0, {3, 1, 1}, "left_table");
  w.set(left, "position", Vec3{-0.5, -0.5, 0});
  const ObjectId right = add_floor(w, 0, {2, 1, 1}, "right_table");
  w.set(right, "position", Vec3{2, -0.5, 0});
  GluedPair p;
  p.a = add_box(w, {0.3, 0.1, 0}, {0.2, 0.2, 0.2}, 1, {}, "box_a");
  p.b = add_box(w, {0.5, 0.1, 0}, {0.2, 0.2, 0.2}, 1, {}, "box_b");
  p.glue = add_glue(w, p.a, p.b, "glue");
  for (ObjectId o : {left, right, p.a, p.b}) w.set(o, "friction", 0.1);
  for (ObjectId o : {p.a, p.b}) {
    w.set(o, "planar", true);
    w.set(o, "velocity", Vec3{2, 0, 0});
  }
  return p;
}

TEST(AreaJoints, AGluedPairSlidesFromAnOdeAreaIntoABox2DAreaAndStaysGlued) {
  Sim s(with_area(kBox2DArea));
  const GluedPair p = build_glued_slide(*s);
  const Vec3 offset0 = s.position(p.b) - s.position(p.a);
  std::string split_text, whole_text;
  int split_events = 0, whole_events = 0, split_steps = 0;
  double drift_max = 0;
  s->start();
  for (int i = 0; i < 240; ++i) {
    s->step();
    split_events += count_events(*s, "area_split", p.glue, &split_text);
    whole_events += count_events(*s, "area_entered", p.glue, &whole_text);
    if (!s->split_areas(p.glue).empty()) ++split_steps;
    const Vec3 d = s.position(p.b) - s.position(p.a) - offset0;
    drift_max = std::max(drift_max, std::sqrt(dot(d, d)));
  }
  const Vec3 d_end = s.position(p.b) - s.position(p.a) - offset0;
  std::printf("glued pair drift at the end: {%.3g, %.3g, %.3g} m, turned %.3g rad\n", d_end.x,
              d_end.y, d_end.z, 2 * std::acos(std::min(1.0, std::abs(s.orientation(p.a).w))));
  std::printf(
      "glued pair ODE -> Box2D at 2 m/s: split for %d steps (%s), then %s; relative drift "
      "largest %.3g m, at the end %.3g m; pair at x = %.3f, %.3f\n",
      split_steps, split_text.c_str(), whole_text.c_str(), drift_max, std::sqrt(dot(d_end, d_end)),
      s.position(p.a).x, s.position(p.b).x);
  EXPECT_EQ(s->area_of(p.a), "right");
  EXPECT_EQ(s->area_of(p.b), "right");
  EXPECT_EQ(s->area_of(p.glue), "right");
  EXPECT_EQ(split_events, 1);
  EXPECT_EQ(split_text, "(no area), right");
  EXPECT_EQ(whole_events, 1);
  EXPECT_EQ(whole_text, "(split) -> right");
  // Both boxes on the table, glued into one Box2D body.
  EXPECT_EQ(engine(*s, "rigid_body.box2d@right").body_count(), 1u);
  EXPECT_EQ(engine(*s, "rigid_body").body_count(), 0u);
  EXPECT_GT(s.position(p.a).x, 1.1);
  // While split each part slides on its own engine: 6.9 mm apart after the
  // crossing at 2 m/s, friction 0.1 (measured; docs/architecture.md).
  EXPECT_LT(drift_max, 1e-2);
  // Glued: a push on one moves both as one body from here on.
  const Vec3 before = s.position(p.b) - s.position(p.a);
  s->set(p.a, "velocity", Vec3{0, 0, 0});
  s.run_for(0.2);
  const Vec3 after = s.position(p.b) - s.position(p.a) - before;
  std::printf("glued pair after one box was stopped: offset moved %.3g m\n",
              std::sqrt(dot(after, after)));
  EXPECT_LT(std::sqrt(dot(after, after)), 1e-4);
}

// --- a hinge whose bodies are on two engines -------------------------------------------

TEST(AreaJoints, AHingeAcrossTwoEnginesIsSuspendedWithAnEventAndResumesWhenTheyMeet) {
  // Box left on ODE (the world's), box right in the Box2D area, a hinge
  // between them. Suspended: right moves off at 1 m/s and left stays.
  Sim s(with_area(kBox2DArea));
  const ObjectId left = add_box(*s, {0.5, 1, 0}, {0.2, 0.2, 0.2}, 1, {}, "left_box");
  const ObjectId right = add_box(*s, {1.5, 1, 0}, {0.2, 0.2, 0.2}, 1, {}, "right_box");
  s->set(right, "velocity", Vec3{1, 0, 0});
  const ObjectId link = add_hinge(*s, left, right, {1, 1, 0}, {0, 0, 1}, "link");
  s->start();
  std::string text;
  EXPECT_EQ(count_events(*s, "area_split", link, &text), 1) << "told at the start";
  EXPECT_EQ(text, "(no area), right");
  s.run_for(0.2);
  EXPECT_EQ(s->split_areas(link), (std::vector<std::string>{"", "right"}));
  EXPECT_EQ(s->area_of(link), "");
  EXPECT_EQ(engine(*s, "rigid_body").joint_count(), 0u);
  EXPECT_EQ(engine(*s, "rigid_body.box2d@right").joint_count(), 0u);
  std::printf("hinge across engines after 0.2 s: left x %.6f (vx %.3g), right x %.6f\n",
              s.position(left).x, s.velocity(left).x, s.position(right).x);
  EXPECT_EQ(s.position(left).x, 0.5) << "suspended: nothing pulls the left box";
  EXPECT_NEAR(s.position(right).x, 1.7, 1e-3);
  // They meet: the left box is moved into the area (an edit), the pivot put
  // between them. The hinge resumes on Box2D, built from the properties.
  const Vec3 r = s.position(right);
  s->set(left, "position", r - Vec3{0.3, 0, 0});
  s->set(left, "velocity", Vec3{0, s.velocity(right).y, 0});
  s->set(link, "anchor", r - Vec3{0.15, 0, 0});
  s->step();
  EXPECT_EQ(count_events(*s, "area_entered", link, &text), 1);
  EXPECT_EQ(text, "(split) -> right");
  EXPECT_TRUE(s->split_areas(link).empty());
  EXPECT_EQ(s->area_of(link), "right");
  EXPECT_EQ(engine(*s, "rigid_body.box2d@right").joint_count(), 1u);
  s.run_for(0.1);
  std::printf("hinge resumed in the Box2D area: left vx %.3f m/s, right vx %.3f m/s\n",
              s.velocity(left).x, s.velocity(right).x);
  // The hinge shares the right box's momentum with the left one.
  EXPECT_GT(s.velocity(left).x, 0.3);
  EXPECT_LT(s.velocity(right).x, 0.7);
}

// --- swaps ---------------------------------------------------------------------------

TEST(AreaJoints, APendulumAreasSwapMidSwingKeepsItsHingeOnEachEngine) {
  // The pendulum of the first test, its area swapped Box2D -> ODE -> Box2D
  // mid-swing: the hinge goes with it (the bob stays 1 m from the pivot and
  // keeps swinging with the closed-form period's phase).
  Sim s(with_area(kBox2DArea));
  const ObjectId bob = add_sphere(
      *s, kPivot + Vec3{kL * std::sin(kTheta), -kL * std::cos(kTheta), 0}, kR, 1.0, "bob");
  const ObjectId hinge = add_hinge(*s, bob, {}, kPivot, {0, 0, 1}, "pivot");
  double worst = 0;
  auto watch = [&](double seconds) {
    for (auto i = std::llround(seconds / s->dt()); i > 0; --i) {
      s->step();
      const Vec3 d = s.position(bob) - kPivot;
      worst = std::max(worst, std::abs(std::sqrt(dot(d, d)) - kL));
    }
  };
  watch(0.7);
  s->swap("right", "rigid_body.box2d", "rigid_body");
  watch(0.1);
  EXPECT_EQ(engine(*s, "rigid_body@right").joint_count(), 1u);
  watch(0.6);
  s->swap("right", "rigid_body", "rigid_body.box2d");
  watch(0.1);
  EXPECT_EQ(engine(*s, "rigid_body.box2d@right").joint_count(), 1u);
  EXPECT_EQ(s->area_of(hinge), "right");
  watch(0.5);
  // At t = 2.0 s: theta(t) = theta0 cos(2 pi t / T).
  const Vec3 d = s.position(bob) - kPivot;
  const double theta = std::atan2(d.x, -d.y);
  const double expected = kTheta * std::cos(2 * kPi * s->time() / closed_form_period());
  std::printf(
      "pendulum area swapped Box2D -> ODE -> Box2D: bob off its 1 m by at most %.3g m; at "
      "t = %.3f s theta %.5f rad, closed form %.5f\n",
      worst, s->time(), theta, expected);
  EXPECT_LT(worst, 1e-4);
  EXPECT_NEAR(theta, expected, 2e-3);
}

// --- saves ---------------------------------------------------------------------------

/// Every joint situation on two ODE instances (the world's and the area's):
/// a pendulum inside the area, a hinge split across the border, and a glued
/// pair crossing it.
void build_all_situations(World& w) {
  GluedPair p = build_glued_slide(w);
  (void)p;
  const ObjectId bob = add_sphere(
      w, kPivot + Vec3{kL * std::sin(kTheta), -kL * std::cos(kTheta), 0}, kR, 1.0, "bob");
  add_hinge(w, bob, {}, kPivot, {0, 0, 1}, "pivot");
  // Far from the others: each falls onto its own table, split all along.
  const ObjectId left = add_box(w, {-1, 2.5, 0}, {0.2, 0.2, 0.2}, 1, {}, "left_box");
  const ObjectId right = add_box(w, {2.9, 2.5, 0}, {0.2, 0.2, 0.2}, 1, {}, "right_box");
  add_hinge(w, left, right, {1, 2.5, 0}, {0, 0, 1}, "link");
}

TEST(AreaJoints, SnapshotsOfJointsInAndAcrossAreasContinueBitForBit) {
  // ODE's restore is bit for bit (docs/saves.md): with the joints scoped by
  // their bodies, a restore at any moment (before the glued pair reaches the
  // border, while it straddles it, after) into the same world or a fresh one
  // continues as the run that was not interrupted, bit for bit.
  const std::vector<std::uint64_t> moments = {1, 40, 70, 80, 120};
  Sim s(with_area(kOdeArea));
  build_all_situations(*s);
  s->start();
  std::vector<Snapshot> snaps;
  std::vector<std::vector<std::uint64_t>> hashes(moments.size());
  std::vector<std::size_t> split_at;
  const ObjectId glue = s->find("glue");
  for (std::uint64_t step = 1; step <= 240; ++step) {
    s->step();
    for (std::size_t m = 0; m < moments.size(); ++m) {
      if (step == moments[m]) {
        snaps.push_back(s->snapshot());
        split_at.push_back(s->split_areas(glue).size());
      }
      if (step > moments[m] && step <= moments[m] + 120) hashes[m].push_back(hash_state(*s).world);
    }
  }
  std::printf(
      "snapshots at steps 1, 40, 70, 80, 120: the glue split at each: %zu %zu %zu %zu %zu\n",
      split_at[0], split_at[1], split_at[2], split_at[3], split_at[4]);
  EXPECT_TRUE(std::find(split_at.begin(), split_at.end(), 2u) != split_at.end())
      << "one moment has the pair straddling the border";
  for (std::size_t m = 0; m < moments.size(); ++m)
    for (bool fresh : {false, true}) {
      Sim other(with_area(kOdeArea));
      if (fresh) build_all_situations(*other);
      World& w = fresh ? *other : *s;
      w.restore(snaps[m]);
      EXPECT_EQ(w.split_areas(glue).size(), split_at[m]) << "step " << moments[m];
      for (std::size_t i = 0; i < hashes[m].size(); ++i) {
        w.step();
        if (hash_state(w).world != hashes[m][i]) {
          ADD_FAILURE() << "restored at step " << moments[m] << (fresh ? " (fresh world)" : "")
                        << ": differs " << i + 1 << " steps on";
          break;
        }
      }
    }
}

TEST(AreaJoints, ABox2DAreasJointsComeBackFromASnapshotWithinItsRebuild) {
  // Box2D cannot be given back its warm starts: a restore rebuilds it, as a
  // swap does (docs/saves.md). The same situations with the area on Box2D,
  // restored while the glued pair straddles the border: 0.5 s on, every
  // body within 0.1 mm of the run that went on, the glue split and whole again
  // at the same steps.
  Sim s(with_area(kBox2DArea));
  build_all_situations(*s);
  s->start();
  s.run_for(75.0 / 240);
  const ObjectId glue = s->find("glue");
  ASSERT_EQ(s->split_areas(glue).size(), 2u);
  const Snapshot snap = s->snapshot();
  std::vector<int> whole_on, whole_re;
  std::vector<Vec3> on, re;
  auto run = [&](std::vector<int>& whole, std::vector<Vec3>& at) {
    for (int i = 1; i <= 120; ++i) {
      s->step();
      if (count_events(*s, "area_entered", glue)) whole.push_back(i);
    }
    for (const char* n : {"box_a", "box_b", "bob", "left_box", "right_box"})
      at.push_back(s.position(s->find(n)));
  };
  run(whole_on, on);
  s->restore(snap);
  run(whole_re, re);
  double worst = 0;
  for (std::size_t i = 0; i < on.size(); ++i) {
    const Vec3 d = on[i] - re[i];
    worst = std::max(worst, std::sqrt(dot(d, d)));
  }
  std::printf(
      "box2d area restored mid-crossing: glue whole again at step +%d (+%d on), bodies "
      "within %.3g m after 0.5 s\n",
      whole_re.empty() ? -1 : whole_re[0], whole_on.empty() ? -1 : whole_on[0], worst);
  EXPECT_EQ(whole_on, whole_re);
  EXPECT_EQ(whole_on.size(), 1u);
  EXPECT_LT(worst, 1e-4);
}

}  // namespace
}  // namespace alloy::scenes
