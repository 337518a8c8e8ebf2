// The rigid body's cylinder (the kit's wheel, coin and pulley): its mass and
// inertia against the formulas, at rest on a floor, two disks colliding in
// the play area, and its contacts with every other shape (each pair found by
// ODE's colliders, libccd's or the side-by-side rule of collide_parts).
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/ode_support.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kPi = std::numbers::pi;

ObjectId add_cylinder(World& w, Vec3 position, double radius, double length,
                      const std::string& name, bool planar = true) {
  const ObjectId c = w.create(name);
  w.set(c, "shape", std::string("cylinder"));
  w.set(c, "radius", radius);
  w.set(c, "length", length);
  w.set(c, "density", 7800.0);
  w.set(c, "position", position);
  if (planar) w.set(c, "planar", true);
  return c;
}

WorldDef def_at(double dt, bool gravity = true) {
  WorldDef def;
  def.dt = dt;
  if (!gravity) def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  return def;
}

TEST(Cylinder, MassAndInertiaFollowTheFormulas) {
  constexpr double r = 0.1, len = 0.05, m = 2.0;
  EXPECT_DOUBLE_EQ(rigid::shape_volume(rigid::Shape::Cylinder, {}, r, len), kPi * r * r * len);
  const Vec3 i = rigid::cylinder_inertia(m, r, len);
  EXPECT_DOUBLE_EQ(i.x, m * (3 * r * r + len * len) / 12);
  EXPECT_DOUBLE_EQ(i.y, i.x);
  EXPECT_DOUBLE_EQ(i.z, m * r * r / 2);

  // Through the world: mass from density, and the inertia the body moves
  // with, seen in its torque-free motion. Spun about an axis tilted from its
  // own, a symmetric body's angular velocity turns about the symmetry axis,
  // in its own frame, at Omega = w3 (I3 - I1) / I1 (0.846 w3 here): a swapped
  // pair of moments turns it the other way, a sphere's not at all.
  std::vector<double> errors;
  for (double dt : {1.0 / 240, 1.0 / 480, 1.0 / 960}) {
    Sim s(def_at(dt, false));
    const ObjectId c = add_cylinder(*s, {0, 0, 0}, r, len, "top", false);
    const double w3 = 5, w1 = 1;
    s->set(c, "angular_velocity", Vec3{w1, 0, w3});
    s->start();
    EXPECT_NEAR(std::get<double>(s->get(c, "mass")), 7800 * kPi * r * r * len, 1e-9);
    // The moments written out, not cylinder_inertia's: a wrong formula there
    // must not move the reference with it.
    const double i1 = (3 * r * r + len * len) / 12, i3 = r * r / 2;
    const double omega = w3 * (i3 - i1) / i1, t = 1.0;
    double turned = 0, last = 0;
    for (std::uint64_t k = 0; k < std::uint64_t(std::llround(t / dt)); ++k) {
      s->step();
      const Quat q = s.orientation(c);
      const Vec3 wb =
          rotate(Quat{q.w, -q.x, -q.y, -q.z}, std::get<Vec3>(s->get(c, "angular_velocity")));
      const double a = std::atan2(wb.y, wb.x);
      double d = a - last;
      d -= 2 * kPi * std::round(d / (2 * kPi));
      turned += d, last = a;
    }
    errors.push_back(std::abs(turned / (omega * t) - 1));
    std::printf("cylinder precession at 1/%.0f s: %.6f rad (exact %.6f), relative error %.3g\n",
                1 / dt, turned, omega * t, errors.back());
  }
  EXPECT_LT(errors[0], 1e-3);
  // First order or better: halving the step at least halves the error.
  EXPECT_LT(errors[1], 0.55 * errors[0]);
  EXPECT_LT(errors[2], 0.55 * errors[1]);
}

TEST(Cylinder, RestsOnAFloorWithoutDrift) {
  // A planar disk on its rim, a coin lying flat (axis up) and a 3D cylinder
  // on its side (axis along z, free to roll along x): each set 0.1 mm into a
  // floor, left for 3 s. None creeps.
  Sim s(def_at(1.0 / 240));
  add_floor(*s);
  const ObjectId disk = add_cylinder(*s, {0, 0.1 - 1e-4, 0}, 0.1, 0.02, "disk");
  const ObjectId side = add_cylinder(*s, {1, 0.05 - 1e-4, 0}, 0.05, 0.2, "side", false);
  const ObjectId coin = add_cylinder(*s, {-1, 0.005 - 1e-4, 0}, 0.05, 0.01, "coin", false);
  s->set(coin, "orientation", Quat::from_axis_angle({1, 0, 0}, kPi / 2));
  const Vec3 d0 = s.position(disk), s0 = s.position(side), c0 = s.position(coin);
  s->start();
  s.run_for(3.0);
  for (auto [o, p0] : {std::pair{disk, d0}, std::pair{side, s0}, std::pair{coin, c0}}) {
    const Vec3 p = s.position(o);
    std::printf("%s moved (%.3g, %.3g, %.3g) m in 3 s\n", s->describe(o).c_str(), p.x - p0.x,
                p.y - p0.y, p.z - p0.z);
    EXPECT_NEAR(p.x, p0.x, 1e-5) << s->describe(o);
    EXPECT_NEAR(p.z, p0.z, 1e-5) << s->describe(o);
    EXPECT_NEAR(p.y, p0.y, 2e-4) << s->describe(o) << " sank or rose";
    EXPECT_LT(length(std::get<Vec3>(s->get(o, "angular_velocity"))), 1e-3) << s->describe(o);
  }
}

TEST(Cylinder, TwoDisksCollideInThePlane) {
  // Equal planar disks (r = 5 cm, 2 cm thick, restitution 1, no friction)
  // meet head on at 1 m/s: they swap velocities, v' = (0, 1) m/s.
  for (double dt : {1.0 / 240, 1.0 / 480, 1.0 / 960}) {
    Sim s(def_at(dt, false));
    const ObjectId a = add_cylinder(*s, {0, 0, 0}, 0.05, 0.02, "a");
    const ObjectId b = add_cylinder(*s, {0.2, 0, 0}, 0.05, 0.02, "b");
    for (ObjectId o : {a, b}) s->set(o, "restitution", 1.0), s->set(o, "friction", 0.0);
    s->set(a, "velocity", Vec3{1, 0, 0});
    s->start();
    s.run_for(0.3);
    const Vec3 va = s.velocity(a), vb = s.velocity(b);
    std::printf("disks at 1/%.0f s: v' = (%.9f, %.9f) m/s\n", 1 / dt, va.x, vb.x);
    EXPECT_NEAR(va.x, 0, 1e-6);
    EXPECT_NEAR(vb.x, 1, 1e-6);
    EXPECT_NEAR(va.y, 0, 1e-9);
    EXPECT_NEAR(vb.y, 0, 1e-9);
  }
}

TEST(Cylinder, BouncesOnAFloorAsABallDoes) {
  // Dropped 1 m onto a floor (restitution 0.5), a planar disk touches it
  // along a line (a point at each face) and a ball at one point: both
  // rebound to the same height, e^2 of the drop up to the bounce's own
  // first-order error (the same for both).
  double rebound[2] = {};
  for (const bool disk : {false, true}) {
    Sim s(def_at(1.0 / 240));
    s->set(add_floor(*s), "restitution", 0.5);
    const ObjectId o = disk ? add_cylinder(*s, {0, 1.1, 0}, 0.1, 0.02, "disk")
                            : add_sphere(*s, {0, 1.1, 0}, 0.1, 1.0, "ball");
    s->set(o, "planar", true);
    s->set(o, "restitution", 0.5);
    s->start();
    bool up = false;
    for (int i = 0; i < 600; ++i) {
      s->step();
      const double vy = s.velocity(o).y;
      if (!up && vy > 0) up = true;
      if (up && vy < 0) break;
      if (up) rebound[disk] = std::max(rebound[disk], s.position(o).y - 0.1);
    }
    EXPECT_LT(length(std::get<Vec3>(s->get(o, "angular_velocity"))), 1e-9)
        << (disk ? "disk" : "ball");
  }
  std::printf("rebound / drop: ball %.6f, disk %.6f (e^2 = 0.25)\n", rebound[0], rebound[1]);
  EXPECT_NEAR(rebound[1], rebound[0], 1e-6);
  EXPECT_NEAR(rebound[1], 0.25, 0.01);
}

TEST(Cylinder, DisksOverlappingDeeperThanTheirThicknessArePushedApartInThePlane) {
  // Two 2 cm thick disks of 5 cm put 4, 7 and 9 cm into each other (an edit,
  // a spawn): the way out is across their axes, not along them (libccd's
  // answer when the overlap is deeper than the thickness, which planar disks
  // cannot follow: they would stay inside each other).
  for (const double apart : {0.06, 0.03, 0.01}) {
    Sim s(def_at(1.0 / 240, false));
    const ObjectId a = add_cylinder(*s, {0, 0, 0}, 0.05, 0.02, "a");
    const ObjectId b = add_cylinder(*s, {apart, 0.001, 0}, 0.05, 0.02, "b");
    s->start();
    s.run_for(1.0);
    const double gap = length(s.position(b) - s.position(a));
    std::printf("centres %.2f m apart pushed to %.5f m (touching: 0.1 m)\n", apart, gap);
    EXPECT_GT(gap, 0.0995) << "put " << apart << " m apart";
  }
}

// A cylinder without its length, or with a length of 0, is refused with a
// message naming the object (not a zero-volume geom in ODE).
TEST(Cylinder, ACylinderWithoutALengthIsRefused) {
  for (const bool give_zero : {false, true}) {
    Sim s(def_at(1.0 / 240));
    std::string message = "accepted";
    try {
      const ObjectId c = s->create("coin");
      s->set(c, "shape", std::string("cylinder"));
      s->set(c, "radius", 0.05);
      if (give_zero) s->set(c, "length", 0.0);
      s->set(c, "mass", 1.0);
      s->set(c, "position", Vec3{0, 1, 0});
      s->start();
      s->step();
    } catch (const InputError& e) {
      message = e.what();
    }
    std::printf("%s\n", message.c_str());
    EXPECT_NE(message.find("coin"), std::string::npos) << message;
    EXPECT_NE(message.find("a cylinder needs a"), std::string::npos) << message;
  }
}

// collide_parts finds a cylinder's contact with every shape, with the
// normal ODE's convention asks for (it pushes g1 out of g2).
TEST(Cylinder, EveryShapePairTouches) {
  rigid::ensure_ode();
  const dGeomID disk = dCreateCylinder(nullptr, 0.1, 0.02);  // at the origin, axis z
  struct Other {
    const char* name;
    dGeomID geom;
    Vec3 at;
    Vec3 out;  // the normal that pushes the disk out of it
  };
  dGeomID cap = dCreateCapsule(nullptr, 0.05, 0.2);
  dQuaternion q;
  dQFromAxisAndAngle(q, 0, 1, 0, kPi / 2);  // the kit's capsule: along x
  dGeomSetQuaternion(cap, q);
  const Other others[] = {
      {"box", dCreateBox(nullptr, 2, 1, 1), {0, -0.599, 0}, {0, 1, 0}},
      {"sphere", dCreateSphere(nullptr, 0.05), {0.149, 0, 0}, {-1, 0, 0}},
      {"capsule", cap, {0, 0.149, 0}, {0, -1, 0}},
      {"cylinder",
       dCreateCylinder(nullptr, 0.1, 0.02),
       {0.14, 0.14, 0},
       {-std::sqrt(0.5), -std::sqrt(0.5), 0}},
  };
  dContactGeom c[8];
  for (const Other& o : others) {
    dGeomSetPosition(o.geom, o.at.x, o.at.y, o.at.z);
    for (const bool swapped : {false, true}) {
      const int n = swapped ? rigid::collide_parts(o.geom, disk, 8, c)
                            : rigid::collide_parts(disk, o.geom, 8, c);
      ASSERT_GT(n, 0) << o.name << (swapped ? " against the disk" : "");
      for (int k = 0; k < n; ++k) {
        const Vec3 normal = rigid::to_vec3(c[k].normal) * (swapped ? -1.0 : 1.0);
        EXPECT_NEAR(length(normal - o.out), 0, 1e-3) << o.name << " point " << k;
        EXPECT_GT(c[k].depth, 0) << o.name;
      }
    }
    dGeomDestroy(o.geom);
  }
  dGeomDestroy(disk);
}

// A round part's contact point lies on its own surface (so that the surface
// layer's overlap does not shorten its rolling radius), whichever side ODE's
// collider put it on (sphere on box: on the box).
TEST(Cylinder, RoundPartsTouchOnTheirOwnSurface) {
  rigid::ensure_ode();
  const dGeomID box = dCreateBox(nullptr, 2, 1, 1);
  dGeomSetPosition(box, 0, -0.5, 0);  // top face at y = 0
  const dGeomID ball = dCreateSphere(nullptr, 0.05);
  dGeomSetPosition(ball, 0, 0.05 - 1e-4, 0);  // 0.1 mm into the box
  const dGeomID disk = dCreateCylinder(nullptr, 0.05, 0.02);
  dGeomSetPosition(disk, 0, 0.05 - 1e-4, 0);
  dContactGeom c[4];
  for (const dGeomID round : {ball, disk})
    for (const bool swapped : {false, true}) {
      const int n =
          swapped ? rigid::collide_parts(box, round, 4, c) : rigid::collide_parts(round, box, 4, c);
      ASSERT_GT(n, 0);
      for (int k = 0; k < n; ++k)
        EXPECT_NEAR(c[k].pos[1], -1e-4, 1e-12)
            << (round == ball ? "ball" : "disk") << (swapped ? ", swapped" : "");
    }
  for (const dGeomID g : {box, ball, disk}) dGeomDestroy(g);
}

}  // namespace
}  // namespace alloy::scenes
