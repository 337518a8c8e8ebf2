// The rigid body on Box2D (resolvers/rigid_body_box2d): chosen with `use`,
// the closed-form cases at several steps (the error must not grow as the step
// falls), contacts published through the same ContactSet, refusals naming the
// object, and ODE's contact interaction kept off it. Each test prints its figures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
#include "tests/scenes/event_records.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;
const std::vector<double> kSteps = {1.0 / 240, 1.0 / 480, 1.0 / 960};

WorldDef on_box2d(double dt = 1.0 / 240) {
  WorldDef def;
  def.dt = dt;
  def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  return def;
}

box2d::Box2DEngine& engine_of(World& w) {
  return dynamic_cast<box2d::Box2DEngine&>(*w.stage("rigid_body.box2d"));
}

/// Every error no larger than the one at the step before (a 2 % allowance
/// for float rounding in Box2D), each printed.
void expect_not_growing(const char* name, const std::vector<double>& e) {
  for (std::size_t i = 0; i < e.size(); ++i) {
    std::printf("box2d %s at 1/%.0f s: %.4g\n", name, 1 / kSteps[i], e[i]);
    if (i > 0) EXPECT_LE(e[i], e[i - 1] * 1.02 + 1e-6) << name << " at 1/" << 1 / kSteps[i];
  }
}

TEST(Box2D, UseChoosesItAndKeepsOdesContactInteractionOff) {
  Sim s(on_box2d());
  add_floor(*s);
  add_sphere(*s, {0, 1, 0}, 0.05, 1.0, "ball");
  s.run_for(0.1);
  const auto stages = s->active_stages();
  auto has = [&](const char* n) {
    return std::find(stages.begin(), stages.end(), n) != stages.end();
  };
  EXPECT_TRUE(has("rigid_body.box2d"));
  EXPECT_TRUE(has("collisions.box2d"));
  EXPECT_TRUE(has("rigid_body_from_gravity"));  // targets whatever provides rigid_body
  EXPECT_FALSE(has("rigid_body"));
  EXPECT_FALSE(has("collisions"));
  EXPECT_FALSE(has("rigid_body_from_collisions"));  // ODE-only (StageInfo::exact)
}

TEST(Box2D, FreeFallErrorFallsWithTheStep) {
  // y(1 s) = y0 - g / 2; semi-implicit Euler lands low by g h T / 2.
  std::vector<double> e;
  for (double h : kSteps) {
    Sim s(on_box2d(h));
    const FreeFall f = build_free_fall(*s, 10);
    s.run_for(1.0);
    e.push_back(std::abs(s.position(f.ball).y - (10 - kG / 2)));
    EXPECT_LE(e.back(), kG * h / 2 * 1.05 + 1e-5);
    EXPECT_NEAR(s.velocity(f.ball).y, -kG, 1e-4);
  }
  expect_not_growing("free fall |y - y_exact| (m)", e);
}

/// A 1 m pendulum: a small disk hinged to the play area, released at 0.05 rad.
double pendulum_period(double h) {
  Sim s(on_box2d(h));
  const double L = 1, r = 0.02, th = 0.05;
  const ObjectId bob = add_sphere(*s, {L * std::sin(th), -L * std::cos(th), 0}, r, 1.0, "bob");
  add_hinge(*s, bob, {}, {0, 0, 0});
  // Period from the upward zero crossings of x over 4 periods.
  std::vector<double> crossings;
  double x_prev = s.position(bob).x;
  const auto n = std::uint64_t(std::llround(11.0 / h));
  for (std::uint64_t i = 1; i <= n && crossings.size() < 5; ++i) {
    s->step();
    const double x = s.position(bob).x;
    if (x_prev < 0 && x >= 0) crossings.push_back((i - 1) * h + h * (-x_prev) / (x - x_prev));
    x_prev = x;
  }
  EXPECT_EQ(crossings.size(), 5u);
  return (crossings.back() - crossings.front()) / 4;
}

TEST(Box2D, PendulumPeriod) {
  // Physical pendulum (a disk of radius r at L): T = 2 pi sqrt((L^2 + r^2/2) / (g L))
  // (a sphere in the plane is a disk: inertia 2/5 m r^2 as ODE's), times the
  // amplitude's 1 + theta0^2 / 16.
  const double L = 1, r = 0.02, th = 0.05;
  const double T = 2 * kPi * std::sqrt((L * L + 0.4 * r * r) / (kG * L)) * (1 + th * th / 16);
  std::vector<double> e;
  for (double h : kSteps) e.push_back(std::abs(pendulum_period(h) - T) / T);
  EXPECT_LE(e.front(), 2e-3);
  expect_not_growing("pendulum period relative error", e);
}

double slide_distance(double h, double mu) {
  Sim s(on_box2d(h));
  const ObjectId floor = add_floor(*s);
  const ObjectId box = add_box(*s, {0, 0.05, 0}, {0.1, 0.1, 0.1}, 1.0, {}, "sled");
  s->set(floor, "friction", mu);
  s->set(box, "friction", mu);
  s.run_for(0.05);  // settle on the floor
  const double x0 = s.position(box).x;
  s->set(box, "velocity", Vec3{1, 0, 0});
  for (int i = 0; i < int(2 / h) && s.velocity(box).x > 1e-9; ++i) s->step();
  return s.position(box).x - x0;
}

TEST(Box2D, SlidingBoxStopsAtTheClosedFormDistance) {
  // v0^2 / (2 mu g) with mu = sqrt(mu_a mu_b) = 0.3.
  const double mu = 0.3, d = 1.0 / (2 * mu * kG);
  std::vector<double> e;
  for (double h : kSteps) e.push_back(std::abs(slide_distance(h, mu) - d) / d);
  EXPECT_LE(e.front(), 0.02);
  expect_not_growing("sliding stop distance relative error", e);
}

double bounce_ratio(double h, double e) {
  Sim s(on_box2d(h));
  const ObjectId floor = add_floor(*s);
  const double r = 0.05, h0 = 1.0;
  const ObjectId ball = add_sphere(*s, {0, r + h0, 0}, r, 1.0, "ball");
  s->set(ball, "restitution", e);
  s->set(floor, "restitution", 0.0);  // mixed by max, as for ODE
  bool down = true;
  double top = 0;
  for (int i = 0; i < int(2 / h); ++i) {
    s->step();
    const double vy = s.velocity(ball).y;
    if (down && vy > 0) down = false;
    if (!down) {
      top = std::max(top, s.position(ball).y - r);
      if (vy < 0) break;
    }
  }
  return top / h0;
}

/// A block put down touching a floor and launched along it (adv F5): the
/// steps at which its floor pair ended while it slid, and its stop distance.
struct Slide {
  int ended = 0, began = 0, disconnected = 0, closed = 0, opened = 0, steps = 0;
  double distance = 0;
};
Slide slide_on_long_floor(double h, double v0) {
  Sim s(on_box2d(h));
  // Top at y = 0, 0.1 m thick and 20 m long; the block's skin meets the
  // floor's at zero overlap, where Box2D's touching test sits on its rounding.
  const ObjectId floor = add_floor(*s, 0, {20, 0.1, 1});
  const ObjectId block = add_box(*s, {0, 0.1, 0}, {0.2, 0.2, 0.2}, 1.0, {}, "block");
  // A circuit through the contact: battery + -> block, floor -> battery -;
  // electricity connects the two parts while they touch.
  for (const ObjectId o : {floor, block}) {
    s->set(o, "friction", 0.3);
    s->set(o, "conductive", true);
    s->set(o, "resistance", 1.0);
  }
  const ObjectId battery = s->create("battery");
  s->set(battery, "emf", 6.0);
  s->set(battery, "internal_resistance", 0.5);
  auto wire = [&](ObjectId from, int ft, ObjectId to, int tt) {
    const ObjectId w = s->create();
    s->set(w, "wire_from", from);
    s->set(w, "wire_from_terminal", std::int64_t(ft));
    s->set(w, "wire_to", to);
    s->set(w, "wire_to_terminal", std::int64_t(tt));
  };
  wire(battery, 1, block, 0);
  wire(floor, 0, battery, 0);
  s->set(block, "velocity", Vec3{v0, 0, 0});
  test::EventRecords events;
  events.record(*s);
  Slide r;
  const double x0 = s.position(block).x;
  for (; r.steps < int(2 / h) && s.velocity(block).x > 1e-9; ++r.steps) s->step();
  r.distance = s.position(block).x - x0;
  r.ended = int(events.of("contact_ended").size());
  r.began = int(events.of("contact_began").size());
  r.disconnected = int(events.of("disconnected").size());
  r.closed = int(events.of("circuit_closed", "battery").size());
  r.opened = int(events.of("circuit_opened", "battery").size());
  return r;
}

TEST(Box2D, ABlockSlidingOnAFloorKeepsItsContactEveryStep) {
  // Box2D 2.4's touching test (a manifold point where the separation is at
  // most the two skins) has no margin, and its solvers leave a contact made
  // at zero overlap there; as the block slides, the rounding of that test
  // changes with its transform, and Box2D dropped the contact for one step
  // (adv F5: steps 129/130 at 1/240 s, 358/359 at 1/480, 837/838 at 1/960).
  // The engine keeps a pair whose skins stay within a tenth of the linear
  // slop (box2d_engine.cpp, kept_contacts): the floor pair begins once, never
  // ends while the block slides, and the circuit through it never opens.
  // v0^2 / (2 mu g) with mu = 0.3 is the stop distance.
  for (double h : kSteps)
    for (double v0 : {1.5, 3.0}) {
      const Slide r = slide_on_long_floor(h, v0);
      const double d = v0 * v0 / (2 * 0.3 * kG);
      std::printf(
          "box2d block sliding at %.1f m/s on a long floor, 1/%.0f s: %d steps, pair began %d, "
          "ended %d, disconnected %d, the battery's circuit closed %d and opened %d times; stop "
          "distance %.5f m (closed form %.5f)\n",
          v0, 1 / h, r.steps, r.began, r.ended, r.disconnected, r.closed, r.opened, r.distance, d);
      EXPECT_EQ(r.began, 1) << v0 << " m/s at 1/" << 1 / h;
      EXPECT_EQ(r.ended, 0) << v0 << " m/s at 1/" << 1 / h;
      EXPECT_EQ(r.disconnected, 0) << v0 << " m/s at 1/" << 1 / h;
      EXPECT_EQ(r.closed, 1) << v0 << " m/s at 1/" << 1 / h;
      EXPECT_EQ(r.opened, 0) << v0 << " m/s at 1/" << 1 / h;
      EXPECT_NEAR(r.distance, d, 0.02 * d);
    }
}

TEST(Box2D, ItsStepsAreAtMostMaxSubstepLong) {
  // max(substeps, ceil(dt / max_substep)) Box2D steps a world step.
  box2d::Box2DConfig c;
  EXPECT_EQ(c.max_substep, 1.0 / 240);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 60), 4);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 120), 2);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 240), 1);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 960), 1);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 100), 3);  // 2.4 rounds up
  c.substeps = 3;
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 240), 3);
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 60), 4);
  c.max_substep = 0;  // no bound: the count alone
  EXPECT_EQ(box2d::substeps_for(c, 1.0 / 60), 3);
  PluginSettings bad;
  bad.where = {"scene.lua", 7, "rigid_body.box2d"};
  bad.set("max_substep", -0.01);
  try {
    box2d::Box2DConfig::from(bad);
    ADD_FAILURE() << "a negative max_substep was taken";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("max_substep"), std::string::npos) << what;
    EXPECT_NE(what.find("scene.lua"), std::string::npos) << what;
  }
}

TEST(Box2D, AColumnStandsAtTheCoarseStep) {
  // 20 boxes of 0.2 m stacked on a floor at 1/120 s: nothing should move.
  // Box2D's position solver stops once every contact is within three linear
  // slops (1.5 mm at scale 10), so the top box may sink by 20 of those, 3 cm
  // (at 1/240 s each contact sinks by 0.63 mm). With one Box2D step of 1/120 s the
  // contacts compressed by about 2.3 mm each in the first quarter second and
  // Box2D's position solver took seconds to lift them back (the top 4.0 cm
  // down at 0.5 s; alloy_bench_engines --pile-study); with Box2D steps of at
  // most max_substep (two at 1/120 s) 1.4 cm.
  Sim s(on_box2d(1.0 / 120));
  add_floor(*s);
  const int n = 20;
  const double a = 0.2;
  std::vector<ObjectId> boxes;
  for (int j = 0; j < n; ++j) {
    boxes.push_back(add_box(*s, {0, a / 2 + a * j, 0}, {a, a, a}, 1.0));
    s->set(boxes.back(), "planar", true);
  }
  s.run_for(0.5);
  const double sink = (n - 0.5) * a - s.position(boxes.back()).y;
  std::printf("box2d column of %d at 1/120 s: the top box sank %.4g m in 0.5 s\n", n, sink);
  EXPECT_LE(std::abs(sink), n * 1.5e-3);
}

TEST(Box2D, BounceReboundsToRestitutionSquared) {
  const double e = 0.5;
  std::vector<double> err;
  for (double h : kSteps) err.push_back(std::abs(bounce_ratio(h, e) - e * e) / (e * e));
  // Not expect_not_growing: with the polygon skin inside the floor's surface
  // (box2d_engine.cpp, rounded_box) the error changes sign between 1/240 and
  // 1/960 s (2.5 %, 0.22 %, 0.64 %): what is left at small steps, about
  // +0.6 %, is Box2D's restitution (applied to the approach speed its
  // velocity solver sees before the contact's own impulse), not the flight.
  for (std::size_t i = 0; i < err.size(); ++i)
    std::printf("box2d bounce height ratio relative error at 1/%.0f s: %.4g\n", 1 / kSteps[i],
                err[i]);
  EXPECT_LE(err.front(), 0.03);
  for (double x : err) EXPECT_LE(x, 0.03);
  EXPECT_LE(err.back(), 0.01);
}

TEST(Box2D, ContactsArePublishedThroughTheContactSet) {
  Sim s(on_box2d());
  const ObjectId floor = add_floor(*s);
  const ObjectId ball = add_sphere(*s, {0, 0.3, 0}, 0.05, 1.0, "ball");
  int began = 0;
  double impact = 0;
  s->start();
  auto& set = dynamic_cast<const ContactSet&>(*s->stage("collisions.box2d"));
  const ImpulseDemand demand = set.demand_impulses();
  for (int i = 0; i < 240; ++i) {
    s->step();
    for (const ContactPair& p : set.began()) {
      ++began;
      impact = p.normal_speed;
      EXPECT_EQ(p.a, std::min(floor, ball));
    }
  }
  EXPECT_EQ(began, 1);
  // Dropped from 0.25 m: sqrt(2 g 0.25) = 2.21 m/s at the floor.
  EXPECT_NEAR(impact, std::sqrt(2 * kG * 0.25), 0.05);
  const ContactPair* p = set.find(ball, floor);
  ASSERT_NE(p, nullptr);
  ASSERT_TRUE(set.impulses_known());
  // At rest: the floor's impulse on the ball over a step is m g h, upward.
  const double on_ball = p->a == ball ? p->impulse.y : -p->impulse.y;
  EXPECT_NEAR(on_ball, kG / 240, 1e-3 * kG / 240);
  for (const ContactPoint& c : set.points(*p)) {
    // Normal from b towards a.
    const double up = p->a == ball ? 1 : -1;
    EXPECT_NEAR(c.normal.y, up, 1e-6);
    EXPECT_NEAR(c.position.y, 0, 1e-3);
  }
}

/// A floor with boxes and disks dropped on it and on each other: pairs begin,
/// bounce apart (end) and begin again in the first 0.6 s.
void bouncing_heap(World& w) {
  add_floor(w);
  for (int i = 0; i < 6; ++i) {
    const ObjectId d = add_sphere(w, {0.13 * i - 0.3, 0.2 + 0.07 * i, 0}, 0.05, 1.0);
    w.set(d, "restitution", 0.6);
    add_box(w, {0.13 * i - 0.33, 0.5 + 0.05 * i, 0}, {0.1, 0.08, 0.1}, 1.0);
  }
}

/// One step's contact lists as bits: every field of every pair and point.
std::vector<double> lists_of(const ContactSet& set, bool with_ended) {
  std::vector<double> out;
  auto pair = [&](const ContactPair& p) {
    for (double v : {double(p.a.index), double(p.b.index), double(p.first), double(p.count),
                     p.normal_speed, p.depth, p.impulse.x, p.impulse.y, p.normal_impulse,
                     p.total_impulse, double(p.began_step)})
      out.push_back(v);
  };
  for (const ContactPair& p : set.began()) pair(p);
  out.push_back(-1);
  for (const ContactPair& p : set.ongoing()) pair(p);
  out.push_back(-2);
  for (const ContactPair& p : set.touching()) {
    pair(p);
    for (const ContactPoint& c : set.points(p))
      for (double v : {c.position.x, c.position.y, c.normal.x, c.normal.y, c.depth})
        out.push_back(v);
  }
  out.push_back(-3);
  if (with_ended)
    for (const ContactPair& p : set.ended()) pair(p);
  return out;
}

TEST(Box2D, ContactGeometryMadeOnFirstReadIsBitForBitTheEagerOne) {
  // collisions.box2d makes its points (and each pair's depth and speed) when
  // first read in a step. A set with a declared reader makes them at every
  // update (eager); one read every step makes them at each first read; one
  // read every 7th step skips the others. The lists each reads, and every
  // contact event of the three runs, must be the same bits.
  struct Run {
    Sim s{on_box2d()};
    std::vector<std::string> events;
    const ContactSet* set = nullptr;
    explicit Run(bool eager) {
      bouncing_heap(*s);
      s->add_observer([this](const Event& e) {
        char line[200];
        std::snprintf(line, sizeof line, "%llu %s %u %u %.17g %.17g %.17g",
                      (unsigned long long)e.step, e.type.c_str(), e.a.index, e.b.index,
                      e.value("speed"), e.value("depth"), e.value("duration"));
        events.push_back(line);
      });
      s->start();
      set = &dynamic_cast<const ContactSet&>(*s->stage("collisions.box2d"));
      if (eager) const_cast<ContactSet*>(set)->add_reader();
    }
  };
  Run eager(true), every(false), sparse(false);
  EXPECT_TRUE(eager.set->has_readers());
  EXPECT_FALSE(every.set->has_readers());
  const ImpulseDemand d1 = eager.set->demand_impulses(), d2 = every.set->demand_impulses(),
                      d3 = sparse.set->demand_impulses();
  int began = 0, ended = 0;
  for (int i = 0; i < 144; ++i) {
    eager.s->step(), every.s->step(), sparse.s->step();
    const auto want = lists_of(*eager.set, true);
    ASSERT_EQ(lists_of(*every.set, true), want) << "step " << i;
    began += int(eager.set->began().size()), ended += int(eager.set->ended().size());
    // A began pair is the touching pair: the same points (made at publish for
    // the event, then placed among every pair's at the first read).
    for (const Run* r : {&eager, &every})
      for (const ContactPair& p : r->set->began()) {
        const ContactPair* t = r->set->find(p.a, p.b);
        ASSERT_NE(t, nullptr);
        EXPECT_EQ(p.first, t->first);
        EXPECT_EQ(p.count, t->count);
        EXPECT_GT(p.count, 0u);
      }
    // (Its ended pairs carry the depth of an update nobody read as 0: documented.)
    if (i % 7 == 0)
      ASSERT_EQ(lists_of(*sparse.set, false), lists_of(*eager.set, false)) << "step " << i;
  }
  std::printf("box2d lazy contact geometry: %d began, %d ended over 144 steps, %zu events\n", began,
              ended, eager.events.size());
  EXPECT_GT(began, 12);
  EXPECT_GT(ended, 3);
  EXPECT_EQ(every.events, eager.events);
  EXPECT_EQ(sparse.events, eager.events);
}

template <class F>
std::string refusal(F&& make) {
  Sim s(on_box2d());
  make(*s);
  try {
    s->step();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Box2D, WhatThePlaneCannotHoldIsRefusedByName) {
  EXPECT_NE(refusal([](World& w) {
              add_sphere(w, {0, 1, 0.2}, 0.05, 1, "floater");
            }).find("'floater' lies off the plane"),
            std::string::npos);
  EXPECT_NE(
      refusal([](World& w) {
        add_box(w, {0, 1, 0}, {0.1, 0.1, 0.1}, 1, Quat::from_axis_angle({1, 0, 0}, 0.3), "tilted");
      }).find("'tilted' is turned about an axis other than z"),
      std::string::npos);
  EXPECT_NE(refusal([](World& w) {
              const ObjectId b = add_box(w, {0, 1, 0}, {0.1, 0.1, 0.1}, 1, {}, "spinner");
              w.set(b, "angular_velocity", Vec3{1, 0, 0});
            }).find("'spinner' spins about an axis in the plane"),
            std::string::npos);
  EXPECT_NE(refusal([](World& w) {
              const ObjectId b = add_box(w, {0, 1, 0}, {0.1, 0.1, 0.1}, 1, {}, "door");
              add_hinge(w, b, {}, {0, 1, 0}, {1, 0, 0}, "sideways");
            }).find("'sideways' is a hinge whose axis {1, 0, 0} is not along z"),
            std::string::npos);
}

TEST(Box2D, GlueMakesOneBodyAndHingeLimitsHold) {
  Sim s(on_box2d());
  const ObjectId a = add_box(*s, {0.1, 0, 0}, {0.2, 0.02, 0.02}, 1, {}, "arm");
  const ObjectId b = add_box(*s, {0.25, 0, 0}, {0.1, 0.1, 0.02}, 1, {}, "weight");
  add_glue(*s, a, b);
  const ObjectId j = add_hinge(*s, a, {}, {0, 0, 0});
  s->set(j, "limit_low", -0.5);
  s->set(j, "limit_high", 0.5);
  s.run_for(1.0);
  EXPECT_EQ(engine_of(*s).body_count(), 1u);
  EXPECT_EQ(engine_of(*s).joint_count(), 1u);
  const Quat q = s.orientation(a);
  const double angle = 2 * std::atan2(q.z, q.w);
  std::printf("box2d glued arm on a limited hinge: angle %.4f rad after 1 s\n", angle);
  EXPECT_NEAR(angle, -0.5, 0.02);  // fell clockwise onto the low limit
  // The glued part keeps its place on the arm.
  const Vec3 pa = s.position(a), pb = s.position(b);
  EXPECT_NEAR(std::hypot(pb.x - pa.x, pb.y - pa.y), 0.15, 1e-5);
}

/// The spin after 0.1 s of a 1 N force along +y on the outer part of a glued
/// pair (a 1 kg ball at the origin, a 1 kg cube 0.1 m out along x) hinged
/// at its centre of mass, queued every step by add_force or by add_load.
double spin_from_an_off_centre_force(const char* engine, bool rated) {
  WorldDef def = on_box2d();
  if (std::string(engine) == "rigid_body") def.use.clear();
  Sim s(def);
  const ObjectId hub = add_sphere(*s, {0, 0, 0}, 0.02, 1, "hub");
  const ObjectId arm = add_box(*s, {0.1, 0, 0}, {0.02, 0.02, 0.02}, 1, {}, "arm");
  add_glue(*s, hub, arm);
  add_hinge(*s, hub, {}, {0.05, 0, 0});  // at the centre of mass: the weight does not turn it
  s->step();                             // the engine's stage exists from the first step
  auto& eng = dynamic_cast<rigid::RigidBodyEngine&>(*s->stage(engine));
  for (int i = 0; i < 24; ++i) {
    if (rated)
      eng.add_load(arm, {0, 1, 0}, {}, {}, {});
    else
      eng.add_force(arm, {0, 1, 0});
    s->step();
  }
  return std::get<Vec3>(s->get(hub, "angular_velocity")).z;
}

TEST(Box2D, AForceOnAGluedPartActsAtThePartAndTurnsTheBody) {
  // The torque is 0.05 m x 1 N about the hinge; I = 2/5 (1)(0.02^2) +
  // (0.02^2 + 0.02^2) / 12 + 2 (0.05^2) kg m^2, so 0.1 s of it gives 0.957
  // rad/s. Until session 16 Box2D applied a part's force at its body's centre
  // of mass: the glued body did not turn (0 rad/s), and the motor's magnets,
  // pulling on the spokes of its glued rotor, drove it 44 % slower than ODE.
  const double inertia = 0.4 * 0.02 * 0.02 + 2 * 0.02 * 0.02 / 12 + 2 * 0.05 * 0.05;
  const double expected = 0.05 * 1 * 0.1 / inertia;
  for (const bool rated : {false, true}) {
    const double ode = spin_from_an_off_centre_force("rigid_body", rated);
    const double b2 = spin_from_an_off_centre_force("rigid_body.box2d", rated);
    std::printf(
        "box2d %s on a glued part 0.05 m from the hinge: spin after 0.1 s ODE %.5f, "
        "Box2D %.5f, closed form %.5f rad/s\n",
        rated ? "add_load" : "add_force", ode, b2, expected);
    EXPECT_NEAR(b2, expected, 0.01 * expected) << (rated ? "add_load" : "add_force");
    EXPECT_NEAR(ode, expected, 0.01 * expected) << (rated ? "add_load" : "add_force");
  }
}

TEST(Box2D, DampingMeansWhatItMeansForOde) {
  // dv/dt = -c v: after 1 s, v0 e^-c to first order in h (the same factor as
  // ODE's engine, (1 - c h)^n).
  const double c = 2, h = 1.0 / 240;
  Sim s(on_box2d(h));
  const ObjectId b = add_sphere(*s, {0, 0, 0}, 0.05, 1.0, "drifter");
  s->set(b, "linear_damping", c);
  s->set(b, "velocity", Vec3{1, 0, 0});
  s.run_for(1.0);
  EXPECT_NEAR(s.velocity(b).x, std::pow(1 - c * h, 240), 1e-5);
}

TEST(Box2D, SwapFromOdeMidRunCarriesPoseVelocityAndHinge) {
  // A pendulum on ODE for 0.5 s, then swapped to Box2D everywhere: the bob's
  // pose and velocity carry over through the properties, the hinge is rebuilt
  // at its anchor, and the swing goes on: after another 0.5 s it is where the
  // same pendulum run on ODE throughout is.
  auto make = [](World& w) {
    const double L = 0.5, th = 0.3;
    const ObjectId bob = add_sphere(w, {L * std::sin(th), -L * std::cos(th), 0}, 0.02, 1.0, "bob");
    add_hinge(w, bob, {}, {0, 0, 0});
    return bob;
  };
  Sim ode;
  const ObjectId b0 = make(*ode);
  Sim swapped;
  const ObjectId b1 = make(*swapped);
  ode.run_for(0.5);
  swapped.run_for(0.5);
  EXPECT_EQ(swapped.position(b1).x, ode.position(b0).x);
  swapped->swap("", "rigid_body", "rigid_body.box2d");
  swapped->swap("", "collisions", "collisions.box2d");
  const Vec3 v_before = swapped.velocity(b1);
  swapped->step();
  ode->step();
  // One step after the swap: the same motion to within a step's change.
  EXPECT_NEAR(swapped.velocity(b1).x, ode.velocity(b0).x, 0.02 * std::abs(v_before.x) + 1e-3);
  ode.run_for(0.5);
  swapped.run_for(0.5);
  const Vec3 p0 = ode.position(b0), p1 = swapped.position(b1);
  std::printf("box2d swap at 0.5 s: bob at 1 s (%.5f, %.5f) vs ODE throughout (%.5f, %.5f)\n", p1.x,
              p1.y, p0.x, p0.y);
  // Box2D's hinge holds by its position iterations (no projection as ODE's
  // engine has): 0.2 mm of stretch at 1/240 s, and the phase drifts by it.
  EXPECT_NEAR(p1.x, p0.x, 4e-3);
  EXPECT_NEAR(std::hypot(p1.x, p1.y), 0.5, 5e-4);
  const auto stages = swapped->active_stages();
  EXPECT_NE(std::find(stages.begin(), stages.end(), "rigid_body.box2d"), stages.end());
  EXPECT_EQ(std::find(stages.begin(), stages.end(), "rigid_body_from_collisions"), stages.end());
}

TEST(Box2D, ABallRollsFromAnOdeTableOntoABox2DTable) {
  // mods/two_engines in C++: the area "right" (x >= 0) is Box2D's, the rest
  // ODE's. The tables' tops meet at x = 0, where the ball's centre crosses
  // into Box2D's area and Box2D takes it over with its velocity and spin.
  WorldDef def;
  AreaDef right;
  right.name = "right";
  right.center = {1, 0.5, 0};
  right.half_extents = {1, 1, 1};
  right.plugins = {"rigid_body.box2d", "collisions.box2d", "rigid_body_from_gravity"};
  def.areas = {right};
  Sim s(def);
  const ObjectId left_table = add_box(*s, {-0.75, 0.775, 0}, {1.5, 0.05, 0.2}, 1, {}, "left_table");
  s->set(left_table, "static", true);
  const ObjectId right_table =
      add_box(*s, {0.75, 0.775, 0}, {1.5, 0.05, 0.2}, 1, {}, "right_table");
  s->set(right_table, "static", true);
  const double r = 0.04, v0 = 0.6;
  const ObjectId ball = add_sphere(*s, {-0.3, 0.8 + r, 0}, r, 0.1, "ball");
  s->set(ball, "velocity", Vec3{v0, 0, 0});
  s->set(ball, "angular_velocity", Vec3{0, 0, -v0 / r});  // rolling without slipping
  s->step();
  EXPECT_EQ(s->area_of(ball), "");
  double crossed_at = -1;
  for (int i = 0; i < 240; ++i) {
    s->step();
    if (crossed_at < 0 && s->area_of(ball) == "right") crossed_at = s->time();
  }
  const Vec3 p = s.position(ball), v = s.velocity(ball);
  std::printf("two engines: crossed at %.4f s; at 1 s x = %.4f m, y = %.5f m, v = %.4f m/s\n",
              crossed_at, p.x, p.y, v.x);
  EXPECT_EQ(s->area_of(ball), "right");
  EXPECT_NEAR(crossed_at, 0.3 / v0, 0.03);
  EXPECT_NEAR(p.y, 0.8 + r, 2e-3);                      // on the right table, not through it
  EXPECT_NEAR(p.x, -0.3 + v0 * (1 + 1.0 / 240), 0.03);  // rolled on at its speed
  EXPECT_NEAR(v.x, v0, 0.03);
  const auto stages = s->active_stages();
  EXPECT_NE(std::find(stages.begin(), stages.end(), "rigid_body.box2d@right"), stages.end());
  EXPECT_NE(std::find(stages.begin(), stages.end(), "rigid_body"), stages.end());
}

// --- swaps bring the engine's contact set; areas; joints across engines; saves ----------

bool active(World& w, const char* stage) {
  const auto st = w.active_stages();
  return std::find(st.begin(), st.end(), stage) != st.end();
}

/// The largest speed of any box of the stack over `seconds`, and the top's
/// height change (m) over them.
struct StackMotion {
  double vmax = 0, drop = 0;
};
StackMotion watch_stack(Sim& s, const Stack& st, double seconds) {
  StackMotion m;
  const double y0 = s.position(st.boxes.back()).y;
  for (int i = 0; i < int(std::llround(seconds / s->dt())); ++i) {
    s->step();
    for (ObjectId b : st.boxes) {
      const Vec3 v = s.velocity(b);
      m.vmax = std::max(m.vmax, std::sqrt(dot(v, v)));
    }
  }
  m.drop = y0 - s.position(st.boxes.back()).y;
  return m;
}

TEST(Box2D, SwappingTheRigidBodyAloneBringsItsContactSetBothWays) {
  // Only `rigid_body` is named: ODE's `collisions` (which needs ODE) and its
  // contact joints must go, Box2D's contact set must come, and back again.
  Sim s;
  const Stack st = build_stack(*s, 5);
  // Planar, as the kit's parts: ODE then keeps them exactly in z = 0 (a 3D
  // stack drifts off the plane by 3e-5 m in 0.5 s, and Box2D refuses it).
  for (ObjectId b : st.boxes) s->set(b, "planar", true);
  std::vector<std::string> swapped;
  s->add_observer([&](const Event& e) {
    if (e.type == "resolver_swapped") swapped.push_back(e.text);
  });
  const StackMotion ode = watch_stack(s, st, 0.5);
  s->swap("", "rigid_body", "rigid_body.box2d");
  const StackMotion on_b2 = watch_stack(s, st, 0.5);
  EXPECT_TRUE(active(*s, "rigid_body.box2d"));
  EXPECT_TRUE(active(*s, "collisions.box2d"));
  EXPECT_FALSE(active(*s, "collisions"));
  EXPECT_FALSE(active(*s, "rigid_body_from_collisions"));
  s->swap("", "rigid_body.box2d", "rigid_body");
  const StackMotion back = watch_stack(s, st, 0.5);
  EXPECT_TRUE(active(*s, "rigid_body"));
  EXPECT_TRUE(active(*s, "collisions"));
  EXPECT_TRUE(active(*s, "rigid_body_from_collisions"));
  EXPECT_FALSE(active(*s, "collisions.box2d"));
  ASSERT_EQ(swapped.size(), 2u);
  EXPECT_EQ(swapped[0],
            "rigid_body -> rigid_body.box2d (everywhere); with collisions -> collisions.box2d");
  EXPECT_EQ(swapped[1],
            "rigid_body.box2d -> rigid_body (everywhere); with collisions.box2d -> collisions");
  std::printf(
      "box2d swap of a 5-box stack (0.2 m cubes): largest speed over 0.5 s on ODE %.3g m/s, "
      "after the swap to Box2D %.3g m/s, after the swap back %.3g m/s; the top sinks %.3g, "
      "%.3g, %.3g m\n",
      ode.vmax, on_b2.vmax, back.vmax, ode.drop, on_b2.drop, back.drop);
  // The stack stands through both swaps: nothing falls through a floor that
  // lost its contact set.
  EXPECT_LT(std::abs(on_b2.drop), 2e-3);
  EXPECT_LT(std::abs(back.drop), 2e-3);
  EXPECT_LT(on_b2.vmax, 0.05);
  EXPECT_LT(back.vmax, 0.05);
}

TEST(Box2D, UsingTheEngineAloneBringsItsContactSet) {
  WorldDef def;
  def.use = {{"rigid_body", "rigid_body.box2d"}};
  Sim s(def);
  add_floor(*s);
  const ObjectId ball = add_sphere(*s, {0, 0.3, 0}, 0.05, 1.0, "ball");
  s.run_for(1.0);
  EXPECT_TRUE(active(*s, "collisions.box2d"));
  EXPECT_FALSE(active(*s, "collisions"));
  EXPECT_NEAR(s.position(ball).y, 0.05, 2e-3);  // resting on the floor, not fallen through
}

WorldDef with_area(std::vector<std::string> plugins) {
  WorldDef def;
  AreaDef right;
  right.name = "right";
  right.center = {2, 1, 0};
  right.half_extents = {1, 2, 1};
  right.plugins = std::move(plugins);
  def.areas = {right};
  return def;
}

TEST(Box2D, AnAreasSwapReplacesItsContactStagesBothWays) {
  // An area on ODE (its own rigid body, collision set and contact joints)
  // swapped to Box2D and back; a stack on the area's floor stands throughout.
  Sim s(with_area(
      {"rigid_body", "collisions", "rigid_body_from_collisions", "rigid_body_from_gravity"}));
  const ObjectId floor = add_box(*s, {2, -0.5, 0}, {1.8, 1, 1}, 1, {}, "right_floor");
  s->set(floor, "static", true);
  Stack st;
  st.edge = 0.2;
  for (int i = 0; i < 4; ++i)
    st.boxes.push_back(add_box(*s, {2, 0.1 + 0.2 * i, 0}, {0.2, 0.2, 0.2}, 1.0));
  for (ObjectId b : st.boxes) s->set(b, "planar", true);
  const StackMotion ode = watch_stack(s, st, 0.5);
  EXPECT_TRUE(active(*s, "rigid_body_from_collisions@right"));
  s->swap("right", "rigid_body", "rigid_body.box2d");
  const StackMotion on_b2 = watch_stack(s, st, 0.5);
  EXPECT_TRUE(active(*s, "rigid_body.box2d@right"));
  EXPECT_TRUE(active(*s, "collisions.box2d@right"));
  EXPECT_FALSE(active(*s, "collisions@right"));
  EXPECT_FALSE(active(*s, "rigid_body_from_collisions@right"));
  s->swap("right", "rigid_body.box2d", "rigid_body");
  const StackMotion back = watch_stack(s, st, 0.5);
  EXPECT_TRUE(active(*s, "rigid_body@right"));
  EXPECT_TRUE(active(*s, "collisions@right"));
  EXPECT_TRUE(active(*s, "rigid_body_from_collisions@right"));
  std::printf(
      "box2d area swap of a 4-box stack: largest speed %.3g (ODE), %.3g (Box2D), %.3g "
      "(ODE again) m/s; top sinks %.3g, %.3g, %.3g m\n",
      ode.vmax, on_b2.vmax, back.vmax, ode.drop, on_b2.drop, back.drop);
  EXPECT_LT(std::abs(on_b2.drop), 2e-3);
  EXPECT_LT(std::abs(back.drop), 2e-3);
  EXPECT_EQ(s->area_of(st.boxes.back()), "right");
}

// Joints inside a Box2D area and across two engines: area_joints_test.cpp.

TEST(Box2D, ARestoreRebuildsFromPropertiesAndTheContinuationIsMeasured) {
  // Box2D keeps warm-start impulses and contact memory that properties do not
  // hold and that Box2D 2.4 cannot be given back: a restore rebuilds its
  // world from the properties, as a swap does. A swinging hinge with a box
  // hitting a floor: the continuation after a restore against the run that
  // went on.
  Sim s(on_box2d());
  add_floor(*s);
  const ObjectId bob = add_sphere(*s, {0.3, 0.5, 0}, 0.02, 1.0, "bob");
  add_hinge(*s, bob, {}, {0, 0.8, 0});
  const ObjectId box = add_box(*s, {1, 0.3, 0}, {0.1, 0.1, 0.1}, 1, {}, "box");
  s.run_for(0.5);
  const Snapshot snap = s->snapshot();
  s.run_for(0.5);
  const Vec3 bob_on = s.position(bob), box_on = s.position(box);
  s->restore(snap);
  s.run_for(0.5);
  const Vec3 bob_re = s.position(bob), box_re = s.position(box);
  const double dbob = std::sqrt(dot(bob_on - bob_re, bob_on - bob_re)),
               dbox = std::sqrt(dot(box_on - box_re, box_on - box_re));
  std::printf(
      "box2d restore at 0.5 s, 0.5 s on: bob %.3g m, resting box %.3g m from the run "
      "that went on\n",
      dbob, dbox);
  EXPECT_LT(dbob, 1e-4);
  EXPECT_LT(dbox, 1e-4);
}

TEST(Box2D, ARestoredHeapDoesNotReportItsContactLimitAgain) {
  // The contact_limit event is reported when pairs begin to be left out, not
  // each step while a heap lasts. A restore in the middle of a heap used to
  // forget that it had been reported (Box2D's flag was not saved, and its
  // rebuilt world asks the filter again for every overlapping pair), and the
  // event came again. On both engines: one event in the run, none after the
  // restore.
  for (const bool box2d : {true, false}) {
    WorldDef def = on_box2d();
    if (!box2d) def.use.clear();
    Sim s(def);
    add_floor(*s);
    // 120 balls of 5 cm within a millimetre of one spot: 7,140 pairs overlap.
    for (int i = 0; i < 120; ++i)
      add_sphere(*s, {1e-3 * std::cos(0.7 * i) * (i % 7) / 7, 0.3 + 1e-3 * std::sin(0.7 * i), 0},
                 0.05, 0.1);
    int events = 0;
    // (ODE's heap, since session 18, waits before any pair is left out: its
    // one report is `crowded`.)
    s->add_observer([&](const Event& ev) {
      events += ev.type == "contact_limit" || (!box2d && ev.type == "crowded");
    });
    s->run(3);
    const int before = events;
    const Snapshot snap = s->snapshot();
    s->run(3);
    const int went_on = events - before;
    s->restore(snap);
    const int at_restore = events;
    s->run(3);
    std::printf(
        "%s heap of 120: %d contact_limit events before the snapshot, %d after it, %d "
        "after the restore\n",
        box2d ? "box2d" : "ode", before, went_on, events - at_restore);
    EXPECT_EQ(before, 1) << (box2d ? "box2d" : "ode");
    // On Box2D the heap guard (session 17) takes buried balls out of the world
    // and lets them back as their spot clears; a return can leave pairs out
    // again, a new episode, reported once (1 event in the run that went on).
    // The restore must not add one for the episode already reported.
    EXPECT_EQ(went_on, box2d ? 1 : 0) << (box2d ? "box2d" : "ode");
    EXPECT_LE(events - at_restore, went_on) << (box2d ? "box2d" : "ode");
  }
}

TEST(Box2D, UniformGravityIsTakenWholeOnlyWhenEveryMovingPartIsInIt) {
  // rigid_body_from_gravity offers a uniform field whole; the engine takes it
  // only if it weighs every part of every moving body and lies in the plane
  // (a part left out would get no weight from either path), and one field a
  // window. The scene's own field is zero here (rigid_body_from_gravity then
  // offers nothing), so that the offers below are the only ones.
  WorldDef def = on_box2d();
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  Sim s(def);
  add_floor(*s);
  const ObjectId a = add_sphere(*s, {0, 1, 0}, 0.05, 1.0, "a");
  const ObjectId b = add_sphere(*s, {1, 1, 0}, 0.05, 2.0, "b");
  // Two steps: the first one's writes give the balls their velocity columns,
  // a change of structure the second rebuilds for (until then it declines).
  s->run(2);
  box2d::Box2DEngine& e = engine_of(*s);
  const std::vector<std::uint32_t> both = {a.index, b.index}, one = {a.index};
  EXPECT_FALSE(e.add_uniform_gravity({0, -kG, 0}, one));
  EXPECT_FALSE(e.add_uniform_gravity({0, -kG, 1.0}, both));  // off the plane: loads report it
  EXPECT_TRUE(e.add_uniform_gravity({0, -kG, 0}, both));
  // A second offer in the same window (another stage's field) is declined,
  // to come as forces, and does not replace the first.
  EXPECT_FALSE(e.add_uniform_gravity({0, -2 * kG, 0}, both));
  const double va = s.velocity(a).y, vb = s.velocity(b).y;
  s->step();
  const double dva = s.velocity(a).y - va, dvb = s.velocity(b).y - vb;
  std::printf("box2d uniform gravity taken for a step: dv %.6g and %.6g m/s (g dt = %.6g)\n", dva,
              dvb, -kG * s->dt());
  EXPECT_NEAR(dva, -kG * s->dt(), 1e-6);
  EXPECT_NEAR(dvb, -kG * s->dt(), 1e-6);
  // For the next advance only, as a queued load.
  const double vb2 = s.velocity(b).y;
  s->step();
  EXPECT_EQ(s.velocity(b).y, vb2);
}

TEST(Box2D, FastBodiesAreFollowedNotClampedAndTooFastOnesRefused) {
  // Box2D moves a body at most b2_maxTranslation (2 of its units, 0.2 m at
  // scale 10) and turns it at most pi/2 a step, and clamps anything faster
  // without a word: 100 m/s came out as 48 m/s at 1/240 s. The engine takes
  // the substeps that keep every body within the limits.
  Sim s(on_box2d());
  const ObjectId bullet = add_sphere(*s, {0, 100, 0}, 0.01, 0.01, "bullet");
  s->set(bullet, "velocity", Vec3{100, 0, 0});
  const ObjectId wheel = add_sphere(*s, {0, 200, 0}, 0.05, 1.0, "wheel");
  s->set(wheel, "angular_velocity", Vec3{0, 0, 1000});
  s.run_for(0.5);
  std::printf("box2d bullet at 100 m/s: %.4f m in 0.5 s; wheel at 1000 rad/s: %.2f rad/s\n",
              s.position(bullet).x, s->value<Vec3>(wheel, "angular_velocity")->z);
  EXPECT_NEAR(s.position(bullet).x, 50.0, 0.01);
  EXPECT_NEAR(s->value<Vec3>(wheel, "angular_velocity")->z, 1000.0, 0.5);
  // 90 km/s would need about 2,000 substeps of 1/240 s: refused by name.
  const ObjectId meteor = add_sphere(*s, {0, 300, 0}, 0.01, 0.01, "meteor");
  s->set(meteor, "velocity", Vec3{9e4, 0, 0});
  s.run_for(0.1);
  EXPECT_TRUE(s->frozen(meteor));
  EXPECT_FALSE(s->frozen(bullet));
}

TEST(Box2D, BodiesOutsideTheMassBoundsAndOffPlaneEditsAreRefusedNotMadeNaN) {
  Sim s(on_box2d());
  add_floor(*s);
  // A steel grain of 1 um: 3e-14 kg, below the 1e-9 kg a moving body may
  // have (ODE's bound); Box2D inverted it in single precision to NaN.
  const ObjectId grain = add_sphere(*s, {0, 0.5, 0}, 1e-6, 1.0, "grain");
  s->set(grain, "density", 7800.0);
  // Friction of 1e80 overflowed Box2D's single-precision mix to inf, then NaN.
  const ObjectId sticky = add_box(*s, {0.5, 0.05, 0}, {0.1, 0.1, 0.1}, 1, {}, "sticky");
  s->set(sticky, "friction", 1e80);
  s->set(sticky, "velocity", Vec3{1, 0, 0});
  const ObjectId box = add_box(*s, {-0.5, 0.05, 0}, {0.1, 0.1, 0.1}, 1, {}, "box");
  // Refused by its bounds (out_of_bounds), not caught as a NaN afterwards
  // (non_finite), which froze it too.
  // The engine's first build happens as the world starts (step 0), and
  // start publishes what it raised.
  std::string grain_event;
  s->start();
  for (int i = 0; i < 48; ++i) {
    for (const Event& e : s->events())
      if (e.a == grain) grain_event += e.type + " ";
    s->step();
  }
  EXPECT_EQ(grain_event, "out_of_bounds ");
  EXPECT_TRUE(s->frozen(grain));
  EXPECT_FALSE(s->frozen(sticky));
  const Vec3 p = s.position(sticky);
  EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y)) << p.x << " " << p.y;
  // An edit that tilts a part out of the plane: refused as at the build, not
  // projected back into the plane unseen.
  s->set(box, "orientation", Quat::from_axis_angle({1, 0, 0}, 0.5));
  s.run_for(0.1);
  EXPECT_TRUE(s->frozen(box));
}

TEST(Box2D, ItsContactSetAloneBringsItsEngineAndAMixIsRefused) {
  // collisions.box2d reads Box2D's world: without rigid_body.box2d it would
  // stay out, and every body fall through the floor with no word.
  {
    WorldDef def;
    def.use = {{"collisions", "collisions.box2d"}};
    Sim s(def);
    add_floor(*s);
    const ObjectId ball = add_sphere(*s, {0, 0.3, 0}, 0.05, 1.0, "ball");
    s.run_for(1.0);
    EXPECT_TRUE(active(*s, "rigid_body.box2d"));
    EXPECT_NEAR(s.position(ball).y, 0.05, 2e-3);
  }
  {
    WorldDef def;
    def.use = {{"collisions", "collisions.box2d"}, {"rigid_body", "rigid_body"}};
    try {
      Sim s(def);
      ADD_FAILURE() << "a contact set of one engine with the rigid body of another";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'collisions.box2d' is written against "
                                           "'rigid_body.box2d', but the scene uses 'rigid_body'"),
                std::string::npos)
          << e.what();
    }
  }
  {
    Sim s;  // ODE
    add_floor(*s);
    add_sphere(*s, {0, 0.3, 0}, 0.05, 1.0, "ball");
    s.run_for(0.1);
    try {
      s->swap("", "collisions", "collisions.box2d");
      s.run_for(0.1);
      ADD_FAILURE() << "swapped in Box2D's contact set on ODE";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("swap 'rigid_body' to 'rigid_body.box2d'"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Box2D, APartLeavingThePlaneInARunIsFrozenAndTheWorldGoesOn) {
  // Mid-run, a part that leaves the plane through a rebuild (here an edit of
  // its mass with its position, as a mod's write can make) is refused by
  // name and frozen; at the scene's load the same part is an error.
  Sim s(on_box2d());
  add_floor(*s);
  const ObjectId stray = add_sphere(*s, {0, 0.5, 0}, 0.05, 1.0, "stray");
  const ObjectId ball = add_sphere(*s, {0.5, 0.5, 0}, 0.05, 1.0, "ball");
  s.run_for(0.1);
  s->set(stray, "position", Vec3{0, 0.5, 0.5});
  s->set(stray, "mass", 2.0);
  s.run_for(0.5);
  EXPECT_TRUE(s->frozen(stray));
  EXPECT_FALSE(s->frozen(ball));
  EXPECT_NEAR(s.position(ball).y, 0.05, 2e-3);
}

}  // namespace
}  // namespace alloy::scenes
