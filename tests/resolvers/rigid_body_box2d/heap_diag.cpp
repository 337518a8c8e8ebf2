// heap_diag: what a heap of n parts placed through each other (a hostile
// mod's spawn at one spot) costs a step on either engine (docs/security.md,
// F14). Not a test: a measuring tool; guards_test checks the bound by counts.
//
//   heap_diag ENGINE N [STEPS]
//
// ENGINE is ode or box2d. Prints the wall time of the start (the first build
// and contact update) and of each step, the touching pairs, and on Box2D the
// guard's counters (bodies waiting, pairs put to the contact filter, shape
// tests, Box2D's contacts); on ODE the parts waiting outside collisions and
// the guard's shape tests.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"
#include "runtime/contact_set.hpp"
#include "tests/scenes/rigid_scenes.hpp"

using namespace alloy;
using namespace alloy::scenes;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s ode|box2d N [STEPS]\n", argv[0]);
    return 2;
  }
  const bool box2d = std::string(argv[1]) == "box2d";
  const int n = std::atoi(argv[2]), steps = argc > 3 ? std::atoi(argv[3]) : 3;
  WorldDef def;
  def.dt = 1.0 / 240;
  if (box2d) def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
  Sim s(def);
  add_floor(*s);
  // The guards test's heap: n spheres of 5 cm within 1 mm of one spot.
  for (int i = 0; i < n; ++i) {
    const double a = 2.399963 * i, r = 1e-3 * std::sqrt((i + 0.5) / n);
    add_sphere(*s, {r * std::cos(a), 0.3 + r * std::sin(a), 0}, 0.05, 0.1, "g" + std::to_string(i));
  }
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) {
    return std::chrono::duration<double>(clock::now() - t).count();
  };
  auto t = clock::now();
  s->start();
  std::printf("%s heap of %d: start %.3f s\n", argv[1], n, since(t));
  const auto& set =
      dynamic_cast<const ContactSet&>(*s->stage(box2d ? "collisions.box2d" : "collisions"));
  for (int k = 0; k < steps; ++k) {
    t = clock::now();
    s->step();
    const double dt = since(t);
    std::printf("  step %d: %.3f s, %zu touching pairs", k + 1, dt, set.touching().size());
    if (auto* b = dynamic_cast<const box2d::Box2DEngine*>(s->stage("rigid_body.box2d")))
      std::printf(", waiting %zu, filter calls %llu, shape tests %llu, Box2D contacts %zu",
                  b->waiting_count(), (unsigned long long)b->pair_filter_calls(),
                  (unsigned long long)b->crowd_tests(), b->box2d_contact_count());
    if (auto* c = dynamic_cast<const rigid::CollisionSet*>(&set))
      std::printf(", waiting %zu, shape tests %llu", c->waiting().size(),
                  (unsigned long long)c->crowd_tests());
    std::printf("\n");
  }
  return 0;
}
