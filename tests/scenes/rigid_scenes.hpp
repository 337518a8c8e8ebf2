// Rigid-body scenes, built through the world's editing API exactly as a Lua
// scene would be. The tests assert on them, the benchmarks time them; the pile
// is also plain data so that a hand-written ODE loop can build the same scene.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/world.hpp"

namespace alloy::scenes {

/// A registry with every native plugin and a world over it (the registry must
/// outlive the world, so they travel together).
struct Sim {
  PluginRegistry registry;
  std::unique_ptr<World> world;

  explicit Sim(WorldDef def = {});
  World& operator*() { return *world; }
  World* operator->() { return world.get(); }
  Vec3 position(ObjectId o) const { return std::get<Vec3>(world->get(o, "position")); }
  Vec3 velocity(ObjectId o) const { return std::get<Vec3>(world->get(o, "velocity")); }
  Quat orientation(ObjectId o) const { return std::get<Quat>(world->get(o, "orientation")); }
  /// Steps for `seconds` of simulated time (rounded to whole steps).
  void run_for(double seconds) { world->run(std::uint64_t(std::llround(seconds / world->dt()))); }
};

// --- parts ---------------------------------------------------------------------------

/// A static box whose top face is at y = top (the play area's floor).
ObjectId add_floor(World& w, double top = 0, Vec3 extent = {20, 1, 20}, const std::string& name = "floor");
ObjectId add_box(World& w, Vec3 position, Vec3 size, double mass, Quat orientation = {},
                 const std::string& name = "");
ObjectId add_sphere(World& w, Vec3 position, double radius, double mass, const std::string& name = "");
/// A hinge object between a and b (b null: the play area).
ObjectId add_hinge(World& w, ObjectId a, ObjectId b, Vec3 anchor, Vec3 axis = {0, 0, 1},
                   const std::string& name = "");
/// A fixed joint object gluing a to b (b null: the play area).
ObjectId add_glue(World& w, ObjectId a, ObjectId b, const std::string& name = "");

// --- scenes --------------------------------------------------------------------------

/// A ball at rest at height y0, nothing under it.
struct FreeFall {
  ObjectId ball;
  Vec3 start;
};
FreeFall build_free_fall(World& w, double y0 = 10);

/// A bar of the 2D kit (planar) hinged at one end to the play area at the
/// origin, released at angle theta0 from hanging straight down (-y).
struct BarPendulum {
  ObjectId bar, hinge;
  double length = 1, width = 0.04, theta0 = 0.05, mass = 1;
  /// Period of the compound pendulum 2 pi sqrt(I / (m g d)), with the
  /// finite-amplitude series 1 + theta0^2/16 + 11 theta0^4/3072.
  double analytic_period(double g) const;
};
BarPendulum build_bar_pendulum(World& w, double length = 1, double theta0 = 0.05);

/// A ball dropped onto a static floor (restitution on the ball, 0 on the floor).
struct Bounce {
  ObjectId ball, floor;
  double radius = 0.1, drop = 1, restitution = 0.7;
};
Bounce build_bounce(World& w, double drop = 1, double restitution = 0.7);

/// n cubes of edge `edge` stacked on a floor, each resting exactly on the one below.
struct Stack {
  std::vector<ObjectId> boxes;
  double edge = 0.2;
};
Stack build_stack(World& w, int n = 10, double edge = 0.2);

/// A box in plain data (pile layouts).
struct BoxSpec {
  Vec3 position;
  Quat orientation;
  Vec3 size;
  double mass = 0;  ///< 0: static
};
/// A pile: boxes dropped in a jittered grid into a bin (floor and four walls).
struct PileLayout {
  std::vector<BoxSpec> boxes;
  std::vector<BoxSpec> statics;  ///< floor and walls
  double friction = 0.5;
};
/// `count` boxes of 0.2 m, 1 kg, 8 x 8 per layer; the jitter comes from `seed`.
PileLayout pile_layout(int count = 500, std::uint32_t seed = 1);
void build_pile(World& w, const PileLayout& layout);

/// A mixed scene for determinism: spheres, boxes, capsules, a hinged bar and a
/// glued assembly tumbling onto a floor.
void build_tumble(World& w);

}  // namespace alloy::scenes
