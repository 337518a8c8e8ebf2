// The collisions set's broad phase (its own uniform grid, collisions.cpp)
// against brute force: every pair of a few thousand parts whose bounds
// overlap is put through the same narrow phase (collide_parts), with no
// spatial structure at all, and the set must report exactly those pairs,
// with the same points, in (a, b) order.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/ode_support.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

using rigid::CollisionSet;
using rigid::ContactPair;
using rigid::ContactPoint;

enum class Kind { Box, Sphere, Capsule, Cylinder };

struct Part {
  Kind kind;
  Vec3 at;
  Quat q;
  Vec3 size;  // box: extents; others: (radius, length, 0)
  bool fixed = false;
};

/// One found pair, with its points, for comparing the set with brute force.
struct Found {
  ObjectId a, b;
  std::vector<ContactPoint> points;
};

ObjectId add(World& w, const Part& p) {
  const ObjectId id = w.create();
  switch (p.kind) {
    case Kind::Box:
      w.set(id, "shape", std::string("box"));
      w.set(id, "size", p.size);
      break;
    case Kind::Sphere:
      w.set(id, "shape", std::string("sphere"));
      w.set(id, "radius", p.size.x);
      break;
    case Kind::Capsule:
    case Kind::Cylinder:
      w.set(id, "shape", std::string(p.kind == Kind::Capsule ? "capsule" : "cylinder"));
      w.set(id, "radius", p.size.x);
      w.set(id, "length", p.size.y);
      break;
  }
  if (p.fixed)
    w.set(id, "static", true);
  else
    w.set(id, "mass", 1.0);
  w.set(id, "position", p.at);
  w.set(id, "orientation", p.q);
  return id;
}

/// The part as an ODE geom in no space, placed as the collision set places it.
dGeomID geom_of(const Part& p) {
  dGeomID g = nullptr;
  Quat q = rigid::normalized(p.q);
  switch (p.kind) {
    case Kind::Box:
      g = dCreateBox(nullptr, p.size.x, p.size.y, p.size.z);
      break;
    case Kind::Sphere:
      g = dCreateSphere(nullptr, p.size.x);
      break;
    case Kind::Capsule:
      g = dCreateCapsule(nullptr, p.size.x, p.size.y);
      q = q * rigid::capsule_axis_rotation();  // alloy's capsule lies along its x
      break;
    case Kind::Cylinder:
      g = dCreateCylinder(nullptr, p.size.x, p.size.y);
      break;
  }
  dGeomSetPosition(g, p.at.x, p.at.y, p.at.z);
  dQuaternion oq;
  rigid::to_ode(q, oq);
  dGeomSetQuaternion(g, oq);
  return g;
}

/// Every pair (a < b, not both static) whose bounds overlap, through the
/// narrow phase: O(n^2), no grid, no space.
std::vector<Found> brute_force(const std::vector<Part>& parts, const std::vector<ObjectId>& ids,
                               int max_contacts) {
  rigid::ensure_ode();
  std::vector<dGeomID> g;
  std::vector<std::array<dReal, 6>> box(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    g.push_back(geom_of(parts[i]));
    dGeomGetAABB(g[i], box[i].data());
  }
  std::vector<dContactGeom> buffer(static_cast<std::size_t>(max_contacts));
  std::vector<Found> found;
  for (std::size_t i = 0; i < parts.size(); ++i)
    for (std::size_t j = i + 1; j < parts.size(); ++j) {
      if (parts[i].fixed && parts[j].fixed) continue;
      bool apart = false;
      for (int k = 0; k < 3; ++k)
        apart = apart || box[i][2 * k] > box[j][2 * k + 1] || box[j][2 * k] > box[i][2 * k + 1];
      if (apart) continue;
      const bool i_first = ids[i] < ids[j];
      const int n = rigid::collide_parts(i_first ? g[i] : g[j], i_first ? g[j] : g[i], max_contacts,
                                         buffer.data());
      if (n <= 0) continue;
      Found& f = found.emplace_back();
      f.a = i_first ? ids[i] : ids[j], f.b = i_first ? ids[j] : ids[i];
      for (int k = 0; k < n; ++k)
        f.points.emplace_back(rigid::to_vec3(buffer[std::size_t(k)].pos),
                              rigid::to_vec3(buffer[std::size_t(k)].normal),
                              buffer[std::size_t(k)].depth);
    }
  for (dGeomID x : g) dGeomDestroy(x);
  std::sort(found.begin(), found.end(),
            [](const Found& x, const Found& y) { return rigid::pair_less(x.a, x.b, y.a, y.b); });
  return found;
}

std::vector<Found> reported(const CollisionSet& c) {
  std::vector<Found> out;
  for (const ContactPair& p : c.touching()) {
    Found& f = out.emplace_back();
    f.a = p.a, f.b = p.b;
    for (const ContactPoint& q : c.points(p)) f.points.push_back(q);
  }
  return out;
}

/// Builds the parts in a world (rigid body and collisions only, no gravity),
/// primes it (the set's first update, at the parts' initial poses) and
/// returns what the set reports; ids receives the parts' ids.
std::vector<Found> collide_in_world(std::vector<Part>& parts, std::vector<ObjectId>& ids,
                                    int& max_contacts) {
  WorldDef def;
  def.plugins = {"rigid_body", "collisions", "rigid_body_from_collisions"};
  Sim sim(def);
  ids.clear();
  for (const Part& p : parts) ids.push_back(add(*sim, p));
  sim->start();
  // The poses as the world holds them (the orientation is stored normalised).
  for (std::size_t i = 0; i < parts.size(); ++i)
    parts[i].at = sim.position(ids[i]), parts[i].q = sim.orientation(ids[i]);
  const auto& c = dynamic_cast<const CollisionSet&>(*sim->stage("collisions"));
  max_contacts = 4;  // the rigid body's default max_contacts
  return reported(c);
}

void expect_same(const std::vector<Found>& got, const std::vector<Found>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    ASSERT_EQ(got[k].a, want[k].a) << "pair " << k;
    ASSERT_EQ(got[k].b, want[k].b) << "pair " << k;
    ASSERT_EQ(got[k].points.size(), want[k].points.size()) << "pair " << k;
    for (std::size_t i = 0; i < want[k].points.size(); ++i) {
      EXPECT_EQ(got[k].points[i].position, want[k].points[i].position);
      EXPECT_EQ(got[k].points[i].normal, want[k].points[i].normal);
      EXPECT_EQ(got[k].points[i].depth, want[k].points[i].depth);
    }
  }
}

Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  const Vec3 axis{n(rng), n(rng), n(rng)};
  return Quat::from_axis_angle(axis / length(axis),
                               std::uniform_real_distribution<double>(0, 6.28)(rng));
}

/// A cluster of 3,000 parts of every shape and of sizes over two orders of
/// magnitude (0.02 to 2 m, so some are "big" for the grid), packed so that
/// most touch several others, on a static floor, with a static wall and a
/// long thin capsule crossing the pile; plus coincident twins and parts deep
/// inside others.
std::vector<Part> random_cluster() {
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Part> parts;
  parts.push_back({Kind::Box, {0, -0.5, 0}, {}, {40, 1, 40}, true});             // floor
  parts.push_back({Kind::Box, {3, 1, 0}, {}, {0.2, 4, 8}, true});                // wall
  parts.push_back({Kind::Capsule, {0, 0.5, 0}, {}, {0.05, 9, 0}});               // a long pole
  parts.push_back({Kind::Box, {-2, 1, -2}, random_rotation(rng), {2, 1.5, 2}});  // big, movable
  const double side = 6;
  while (parts.size() < 3000) {
    const Kind kind = Kind(int(u(rng) * 4) % 4);
    // Sizes log-uniform over 0.02 to 0.4 m, one in 100 up to 2 m.
    const double s = (u(rng) < 0.01 ? 2.0 : 0.4) * std::pow(0.05, u(rng));
    Part p{kind, {side * (u(rng) - 0.5), 2 * u(rng), side * (u(rng) - 0.5)}, random_rotation(rng)};
    p.size = kind == Kind::Box ? Vec3{s, s * (0.3 + u(rng)), s * (0.3 + u(rng))}
                               : Vec3{0.5 * s, s * (0.2 + u(rng)), 0};
    parts.push_back(p);
    if (u(rng) < 0.02) parts.push_back(p);  // a coincident twin
    if (u(rng) < 0.02) {                    // a small sphere deep inside it
      parts.push_back({Kind::Sphere, p.at, {}, {0.1 * s, 0, 0}});
    }
  }
  return parts;
}

/// Boxes on a grid, each face exactly on its neighbours' (touching, depth 0,
/// bounds that meet without overlapping), cells of the grid's spacing
/// straddled at every offset; and spheres resting exactly on them.
std::vector<Part> touching_grid() {
  std::vector<Part> parts;
  const double e = 0.25;  // exactly representable: faces meet exactly
  for (int i = 0; i < 14; ++i)
    for (int j = 0; j < 14; ++j)
      for (int k = 0; k < 10; ++k)
        parts.push_back({Kind::Box, {e * i, e * k + 0.125, e * j}, {}, {e, e, e}});
  for (int i = 0; i < 14; ++i)
    parts.push_back({Kind::Sphere, {e * i, e * 10 + 0.125 + 0.125 - 1e-3, 0}, {}, {0.125, 0, 0}});
  parts.push_back({Kind::Box, {0, -0.5, 0}, {}, {20, 1, 20}, true});
  return parts;
}

TEST(BroadPhase, FindsEveryPairBruteForceFindsOnARandomCluster) {
  std::vector<Part> parts = random_cluster();
  std::vector<ObjectId> ids;
  int max_contacts = 0;
  const std::vector<Found> got = collide_in_world(parts, ids, max_contacts);
  const std::vector<Found> want = brute_force(parts, ids, max_contacts);
  EXPECT_GT(want.size(), 2000u);  // a dense pile: the test means something
  expect_same(got, want);
}

TEST(BroadPhase, FindsTouchingPairsOnAGridOfExactlyMeetingBoxes) {
  std::vector<Part> parts = touching_grid();
  std::vector<ObjectId> ids;
  int max_contacts = 0;
  const std::vector<Found> got = collide_in_world(parts, ids, max_contacts);
  const std::vector<Found> want = brute_force(parts, ids, max_contacts);
  EXPECT_GT(want.size(), 5000u);
  expect_same(got, want);
}

TEST(BroadPhase, OrderIsByPairAndTheSameEveryRun) {
  std::vector<Part> parts = random_cluster();
  std::vector<ObjectId> ids1, ids2;
  int m = 0;
  std::vector<Part> again = parts;  // the same input twice (the first call rewrites the poses)
  const std::vector<Found> first = collide_in_world(parts, ids1, m);
  const std::vector<Found> second = collide_in_world(again, ids2, m);
  for (std::size_t k = 1; k < first.size(); ++k)
    ASSERT_TRUE(rigid::pair_less(first[k - 1].a, first[k - 1].b, first[k].a, first[k].b)) << k;
  expect_same(second, first);
}

TEST(BroadPhase, AWorldEmptiedOfPartsFindsNothing) {
  // The grid of the last update must not outlive its parts.
  WorldDef def;
  def.plugins = {"rigid_body", "collisions", "rigid_body_from_collisions"};
  Sim sim(def);
  const ObjectId a = add(*sim, {Kind::Box, {0, 0, 0}, {}, {1, 1, 1}});
  const ObjectId b = add(*sim, {Kind::Box, {0.5, 0, 0}, {}, {1, 1, 1}});
  std::vector<Event> errors;
  sim->add_observer([&](const Event& e) {
    if (e.type == "engine_error") errors.push_back(e);
  });
  sim->step();
  const auto& c = dynamic_cast<const CollisionSet&>(*sim->stage("collisions"));
  ASSERT_EQ(c.touching().size(), 1u);
  sim->destroy(a);
  sim->destroy(b);
  sim->step();
  sim->step();
  EXPECT_TRUE(c.touching().empty());
  EXPECT_TRUE(errors.empty()) << errors[0].text;
}

}  // namespace
}  // namespace alloy::scenes
