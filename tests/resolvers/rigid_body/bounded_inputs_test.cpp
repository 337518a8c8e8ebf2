// Physically bounded inputs of the rigid body (resolvers/rigid_body: limits::
// in properties.hpp, rigid_body_bounds.cpp, ode_support's
// error routing). Finite but absurd loads, masses and poses used to abort the
// process inside ODE; each is now refused at the boundary: an edit by the
// property registry (InputError naming the object and the value), a load or
// a motion by the rigid body, which freezes the body with an "out_of_bounds"
// event naming the stage that gave the value. In every case another body
// goes on falling exactly as it would alone.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/ode_support.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy {
namespace {

using rigid::RigidBodyResolver;
namespace limits = rigid::limits;

/// An interaction that queues whatever the test says on the rigid body, every step.
class Pusher final : public Interaction {
 public:
  using Act = std::function<void(RigidBodyResolver&, const WorldView&)>;
  Pusher(RigidBodyResolver& rigid, std::shared_ptr<Act> act)
      : rigid_(rigid), act_(std::move(act)) {}
  void apply(const WorldView& w) override {
    if (*act_) (*act_)(rigid_, w);
  }

 private:
  RigidBodyResolver& rigid_;
  std::shared_ptr<Act> act_;
};

constexpr double g = 9.81;

/// A world with the rigid body, uniform gravity, collisions and the pusher;
/// a ball ("victim") for the hostile input and a ball ("witness") that falls
/// freely beside it, far enough not to touch.
struct Bench {
  PluginRegistry registry;
  std::shared_ptr<Pusher::Act> act = std::make_shared<Pusher::Act>();
  std::unique_ptr<World> world;
  ObjectId victim, witness;
  std::vector<Event> refused;  // out_of_bounds events
  std::vector<Event> errors;   // engine_error events

  Bench() {
    register_native_plugins(registry);
    registry.add({.info = {.name = "pusher",
                           .kind = StageKind::Interaction,
                           .needs = {"mass"},
                           .target = "rigid_body"},
                  .create = [act = act](PluginContext& ctx) {
                    return std::make_unique<Pusher>(ctx.target<RigidBodyResolver>(), act);
                  }});
    world = std::make_unique<World>(
        registry, WorldDef{.plugins = {"rigid_body", "gravity.uniform", "rigid_body_from_gravity",
                                       "collisions", "rigid_body_from_collisions", "pusher"}});
    victim = scenes::add_sphere(*world, {0, 10, 0}, 0.1, 4.0, "victim");
    witness = scenes::add_sphere(*world, {5, 10, 0}, 0.1, 4.0, "witness");
    world->add_observer([this](const Event& e) {
      if (e.type == "out_of_bounds") refused.push_back(e);
      if (e.type == "engine_error") errors.push_back(e);
    });
  }
  World& w() { return *world; }
  Vec3 position(ObjectId o) const { return std::get<Vec3>(world->get(o, "position")); }
  /// The witness fell freely all along: y = 10 - g t^2 / 2, plus the g dt t / 2
  /// of semi-implicit Euler.
  void expect_witness_fell() const {
    const double t = world->time(), dt = world->dt();
    EXPECT_NEAR(position(witness).y, 10 - g * t * t / 2 - g * dt * t / 2, 1e-9);
    EXPECT_FALSE(world->frozen(witness));
  }
  /// Exactly one refusal, of the victim, from `source`, whose text holds `part`.
  void expect_refused(const std::string& source, const std::string& part) const {
    ASSERT_EQ(refused.size(), 1u);
    const Event& e = refused[0];
    EXPECT_EQ(e.a, victim);
    EXPECT_EQ(e.source, source);
    EXPECT_NE(e.text.find(part), std::string::npos) << e.text;
    EXPECT_NE(frozen_message(*world, e).find("frozen: victim: " + source), std::string::npos)
        << frozen_message(*world, e);
    EXPECT_TRUE(world->frozen(victim));
    EXPECT_TRUE(errors.empty()) << errors[0].text;
    // The victim keeps finite values within the bounds (a part refused at its
    // first build never had a velocity written).
    for (const char* p : {"position", "velocity", "angular_velocity"}) {
      const auto value = world->value<Vec3>(victim, p);
      if (!value) continue;
      const Vec3 v = *value;
      EXPECT_TRUE(std::abs(v.x) <= limits::extent && std::abs(v.y) <= limits::extent &&
                  std::abs(v.z) <= limits::extent)
          << p;
    }
  }
};

TEST(BoundedInputs, OdeAssertionsThrowInsteadOfAborting) {
  // dBodySetMass asserts that the mass is valid (dIASSERT / dUASSERT, kept in
  // Debian's build); with alloy's handler that is an exception, not abort().
  rigid::ensure_ode();
  dWorldID world = dWorldCreate();
  dBodyID body = dBodyCreate(world);
  dMass zero;
  dMassSetZero(&zero);
  try {
    dBodySetMass(body, &zero);
    ADD_FAILURE() << "ODE accepted a zero mass";
  } catch (const rigid::OdeError& e) {
    EXPECT_NE(std::string(e.what()).find("ODE error"), std::string::npos) << e.what();
  }
  // ODE is still usable after the throw.
  dMass unit;
  dMassSetSphereTotal(&unit, 1, 0.1);
  dBodySetMass(body, &unit);
  dWorldStep(world, 0.01);
  dWorldDestroy(world);
}

TEST(BoundedInputs, AHugeFiniteForceIsRefusedAndItsBodyFrozen) {
  // 1e12 N on a 4 kg ball for one step of 1/240 s: 1e9 m/s. It used to end in
  // ODE's aabbBound assertion in collide() the step after.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 10) r.add_force(b.victim, Vec3{1e12, 0, 0});
  };
  b.w().run(60);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("pusher", "add_force {1e+12, 0, 0} N"));
  EXPECT_NE(b.refused[0].text.find("its speed by 1.04167e+09 m/s"), std::string::npos)
      << b.refused[0].text;
  EXPECT_EQ(b.refused[0].value("x"), 1e12);
  b.expect_witness_fell();
}

TEST(BoundedInputs, AHugeTorqueIsRefused) {
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3) r.add_torque(b.victim, Vec3{0, 0, 1e308});
  };
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("pusher", "add_torque {0, 0, 1e+308} N m"));
  EXPECT_NE(b.refused[0].text.find("angular speed"), std::string::npos);
  b.expect_witness_fell();
}

TEST(BoundedInputs, AForceAtAFarPointIsRefusedForItsTorque) {
  // 1 N, but 1e300 m from the centre: a torque of 1e300 N m.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3) r.add_force(b.victim, Vec3{0, 1, 0}, Vec3{1e300, 0, 0});
  };
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(
      b.expect_refused("pusher", "add_force_at {0, 1, 0} N at {1e+300, 0, 0} m"));
  b.expect_witness_fell();
}

TEST(BoundedInputs, ManyLoadsWithinTheBoundAreSummed) {
  // One 5e7 N load is within the bound for a 4 kg ball (5e7 N * dt / 4 kg =
  // 5.2e4 m/s), two are not; and +-huge loads that cancel are refused too,
  // since magnitudes are summed.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3)
      for (int i = 0; i < 2; ++i) r.add_force(b.victim, Vec3{5e7, 0, 0});
  };
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("pusher", "its speed by 104167 m/s"));
  b.expect_witness_fell();

  Bench c;
  *c.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3)
      for (double s : {1.0, -1.0}) r.add_force(c.victim, Vec3{s * 1e300, 0, 0});
  };
  c.w().run(30);
  ASSERT_NO_FATAL_FAILURE(c.expect_refused("pusher", "add_force"));
  c.expect_witness_fell();
}

TEST(BoundedInputs, ALoadWithinTheBoundIsPerformed) {
  // 1e6 N on 4 kg for one step: 1042 m/s, well within the limits: no refusal.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3) r.add_force(b.victim, Vec3{0, 0, 1e6});
  };
  b.w().run(30);
  EXPECT_TRUE(b.refused.empty()) << frozen_message(b.w(), b.refused[0]);
  EXPECT_NEAR(std::get<Vec3>(b.w().get(b.victim, "velocity")).z, 1e6 / 4 / 240, 1e-6);
  b.expect_witness_fell();
}

TEST(BoundedInputs, ASteadyLoadThatRunsAwayIsStoppedAtTheSpeedLimit) {
  // Each step's push is within bounds (2.5e4 m/s a step), but it never stops:
  // after four steps the ball passes the speed limit, and the check after
  // ODE's step refuses it before its pose reaches a property, naming the
  // stage that pushed it.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView&) {
    r.add_force(b.victim, Vec3{0, 0, 2.4e7});
  };
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused(
      "pusher", "pushed it until the rigid body's step gave it a velocity of {0,"));
  EXPECT_NE(b.refused[0].text.find("beyond the limit of +-100000 m/s"), std::string::npos)
      << b.refused[0].text;
  b.expect_witness_fell();
}

TEST(BoundedInputs, ABodyLeavingTheWorldsExtentIsStopped) {
  Bench b;
  b.w().set(b.victim, "position", Vec3{0, 10, limits::extent - 100});
  b.w().set(b.victim, "velocity", Vec3{0, 0, 9e4});
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("rigid_body", "beyond the world's extent of +-1e+06 m"));
  b.expect_witness_fell();
}

TEST(BoundedInputs, AbsurdEditsAreRefusedByTheRegistry) {
  // A scene, the viewer and the timeline all edit through World::set.
  Bench b;
  auto message = [&](const char* p, PropertyValue v) -> std::string {
    try {
      b.w().set(b.victim, p, v);
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(message("position", Vec3{1e300, 0, 0}),
            "object 'victim': 'position' must lie between -1e+06 and 1e+06 in every direction, got "
            "{1e+300, 0, 0}");
  EXPECT_EQ(message("velocity", Vec3{0, -1e300, 0}),
            "object 'victim': 'velocity' must lie between -100000 and 100000 in every direction, "
            "got {0, -1e+300, 0}");
  EXPECT_NE(
      message("angular_velocity", Vec3{0, 0, 1e10}).find("'angular_velocity' must lie between"),
      std::string::npos);
  EXPECT_EQ(message("mass", 1e300),
            "object 'victim': 'mass' must be greater than 0 and at most 1e+12, got 1e+300");
  EXPECT_EQ(message("mass", -2.0),
            "object 'victim': 'mass' must be greater than 0, got -2");  // as before
  EXPECT_NE(message("radius", 1e300).find("'radius' must be greater than 0 and at most 1e+06"),
            std::string::npos);
  // The timeline checks when it is given.
  EXPECT_THROW(b.w().schedule(0.1, b.victim, b.w().properties().id("velocity"), Vec3{1e200, 0, 0}),
               InputError);
  b.w().run(30);
  EXPECT_TRUE(b.refused.empty());
  b.expect_witness_fell();
}

TEST(BoundedInputs, ATinyMassIsLeftOutOfTheRigidBody) {
  // 1e-300 kg: its inverse mass and inertia overflow the solver.
  Bench b;
  b.w().set(b.victim, "mass", 1e-300);
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(
      b.expect_refused("rigid_body", "has a mass of 1e-300 kg, outside the 1e-09 .. 1e+12 kg"));
  EXPECT_EQ(b.position(b.victim).y, 10.0);  // left where it was
  b.expect_witness_fell();
}

TEST(BoundedInputs, APartTooThinForItsInertiaIsLeftOut) {
  // A box 1e-200 m thin: its moments of inertia underflow to 0, and ODE's
  // dBodySetMass asserts on an inertia that is not positive definite.
  Bench b;
  const ObjectId sliver =
      scenes::add_box(b.w(), {-5, 10, 0}, {1e-200, 1e-200, 1e-200}, 1.0, {}, "sliver");
  b.w().run(30);
  ASSERT_EQ(b.refused.size(), 1u);
  EXPECT_EQ(b.refused[0].a, sliver);
  EXPECT_NE(b.refused[0].text.find("smallest moment of inertia"), std::string::npos)
      << b.refused[0].text;
  EXPECT_TRUE(b.w().frozen(sliver));
  EXPECT_FALSE(b.w().frozen(b.victim));
  b.expect_witness_fell();
}

TEST(BoundedInputs, AHingeToARefusedPartHoldsNothing) {
  Bench b;
  b.w().set(b.victim, "mass", 1e-300);
  scenes::add_hinge(b.w(), b.victim, ObjectId{}, {0, 10, 0});
  b.w().run(30);  // no "neither a rigid body nor static" error
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("rigid_body", "has a mass of 1e-300 kg"));
  b.expect_witness_fell();
}

TEST(BoundedInputs, HugeOrTinyRotationsAndAxesNormalise) {
  // Finite, non-zero, but their squares overflow or underflow: the rotation
  // and the hinge axis are scaled before they are normalised (a zero
  // quaternion would trip ODE's dNormalize4).
  Bench b;
  b.w().set(b.victim, "orientation", Quat{1e300, 0, 0, 1e300});
  const ObjectId arm = scenes::add_box(b.w(), {-5, 10, 0}, {0.5, 0.1, 0.1}, 1.0, {}, "arm");
  const ObjectId pivot = scenes::add_hinge(b.w(), arm, ObjectId{}, {-5.25, 10, 0}, {0, 0, 1e300});
  b.w().run(10);
  b.w().set(arm, "orientation", Quat{1e-300, 0, 0, 0});
  b.w().run(10);
  EXPECT_TRUE(b.refused.empty());
  EXPECT_TRUE(b.errors.empty());
  const Quat q = std::get<Quat>(b.w().get(b.victim, "orientation"));
  EXPECT_NEAR(q.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(q.z, std::sqrt(0.5), 1e-12);
  const Vec3 axis = std::get<Vec3>(b.w().get(pivot, "axis"));
  EXPECT_NEAR(axis.z, 1.0, 1e-9);
  b.expect_witness_fell();
}

TEST(BoundedInputs, RatedLoadsAreBoundedOverTheWindow) {
  // add_load's value plus its rate over the window.
  Bench b;
  *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
    if (w.step() == 3) r.add_load(b.victim, Vec3{}, Vec3{}, Vec3{1e15, 0, 0}, Vec3{});
  };
  b.w().run(30);
  ASSERT_NO_FATAL_FAILURE(b.expect_refused("pusher", "add_load"));
  b.expect_witness_fell();
}

TEST(BoundedInputs, ALoadOnlyRefusesItsOwnBodyAndTheRestIsDeterministic) {
  // Two runs of the same hostile input end bit-identical.
  auto run = [] {
    Bench b;
    *b.act = [&](RigidBodyResolver& r, const WorldView& w) {
      if (w.step() % 7 == 0) r.add_force(b.victim, Vec3{w.step() % 2 ? 1e20 : -1e20, 0, 0});
      r.add_force(b.witness, Vec3{0, 0, 0});
    };
    b.w().run(40);
    EXPECT_NO_FATAL_FAILURE(b.expect_refused("pusher", "add_force"));
    b.expect_witness_fell();
    return b.position(b.witness);
  };
  EXPECT_EQ(run(), run());
}

}  // namespace
}  // namespace alloy
