// The Box2D engine's energy books: the accounts of ODE's engine, under the
// same names (resolvers/rigid_body/energy_books.hpp; docs/energy.md, "The
// rigid body", and docs/box2d.md, "Energy books").
//
// Per Box2D step (a substep of the window): the kinetic energy before and
// after the engine's drag factor (drag) and after the step. Each queued load
// (the queue, the rated loads at the substep's time, the uniform weights)
// is booked along the step's displacement: the move of its body's centre of
// mass, and the body's turn times the load's torque about that centre (its
// own and its force's): the transfer its stage sees. Box2D moves a body by
// h v' and then its position solver pushes it (contacts, joints) with no
// velocity; measured on the body, the work holds both, so for a uniform
// field (whose weights' moments about the centre of mass cancel) it is
// exactly minus the change of the potential that gravity.uniform reports
// from the written positions. The turn is taken to first order, as ODE's
// h tau . w': the loads between parts of one body (the motor's rotor's
// magnets on one another) then do no work, as on a rigid body they must;
// along the chords the parts' centres move, they did a first-order share
// (0.17 J in 10 s of the motor at 1/240 s, booked as magnetism). Along the mean
// velocity, h F . (v + v') / 2, it is what the load gave the kinetic energy;
// the difference is the integrator's share and the position corrections.
//
// Restitution: Box2D bounces a contact inside its velocity solve, by a
// velocity bias of -e times the approach speed at points that approach
// faster than the threshold (after the step's loads kicked the bodies). The
// solve's impulses change the kinetic energy by exactly the sum over them
// of impulse times the mean of the relative velocity at its point before
// and after; the books take that sum over the points that bounced (their
// normal and friction impulses) as the collision impulses' loss, the same
// account ODE books its restitution pass in. What the kinetic energy did not
// receive of the loads' mean work, less that, is the contacts' and joints'
// residue.
#include <box2d/box2d.h>

#include <algorithm>

#include "resolvers/rigid_body_box2d/box2d_engine.hpp"

namespace alloy::box2d {

/// A Box2D body's velocity at the step's start with the step's loads added
/// (what the solver starts from), in Box2D's units.
struct Kicked {
  const b2Body* body;
  b2Vec2 v;
  double w;
};

struct Box2DEngine::Books final : b2ContactListener {
  Box2DEngine* engine = nullptr;
  b2ContactListener* inner = nullptr;  // the engine's own listener, relayed to
  b2World* world = nullptr;
  /// The window's loads: what each applies at the window's start, and its
  /// rate (rated loads: value + rate * tau).
  struct Load {
    rigid::EnergyBooks::Applied a;
    Vec3 force_rate, torque_rate;
  };
  std::vector<Load> loads;
  std::vector<b2Body*> carriers;  // by EnergyBooks::Applied::body
  std::vector<double> angle0;     // per carrier, at the substep's start
  std::vector<Vec3> centre0;      // per carrier: its centre of mass then (after the step: now)
  std::vector<Kicked> kicked;     // every moving body, sorted by body
  double ke0 = 0, ke1 = 0;        // before and after the drag
  double collisions = 0;          // this step's bounced impulses' loss, J

  std::uint32_t carrier(b2Body* b) {
    for (std::size_t i = 0; i < carriers.size(); ++i)
      if (carriers[i] == b) return std::uint32_t(i);
    carriers.push_back(b);
    return std::uint32_t(carriers.size() - 1);
  }
  Kicked* find(const b2Body* b) {
    auto it = std::lower_bound(kicked.begin(), kicked.end(), b,
                               [](const Kicked& k, const b2Body* x) { return k.body < x; });
    return it != kicked.end() && it->body == b ? &*it : nullptr;
  }

  void BeginContact(b2Contact* c) override { inner->BeginContact(c); }
  void EndContact(b2Contact* c) override { inner->EndContact(c); }
  void PreSolve(b2Contact* c, const b2Manifold* old) override { inner->PreSolve(c, old); }
  void PostSolve(b2Contact* c, const b2ContactImpulse* imp) override {
    inner->PostSolve(c, imp);
    engine->book_collision(c, imp);
  }
};

namespace {

/// A body's kinetic energy in J: Box2D's velocities are of the centre of
/// mass, its inertia about the body's origin, all at the engine's scale.
double kinetic(const b2Body* b, double s) {
  const b2Vec2 v = b->GetLinearVelocity(), lc = b->GetLocalCenter();
  const double m = b->GetMass(), w = b->GetAngularVelocity();
  const double ic = double(b->GetInertia()) - m * double(b2Dot(lc, lc));
  return 0.5 * (m * double(b2Dot(v, v)) + ic * w * w) / (s * s);
}

Vec3 si(b2Vec2 v, double s) {
  return {v.x / s, v.y / s, 0};
}

}  // namespace

double Box2DEngine::kinetic_energy() const {
  const b2World* world = box2d_world();
  double e = 0;
  if (world)
    for (const b2Body* b = world->GetBodyList(); b; b = b->GetNext())
      if (b->GetType() == b2_dynamicBody) e += kinetic(b, config_.scale);
  return e;
}

void Box2DEngine::report_energy(const WorldView&, EnergyReport& out) {
  books_on_ = true;
  books_.report(kinetic_energy(), out);
}

void Box2DEngine::books_open(bool weigh, const ColumnView<double>& mass, const Carrier& carrier) {
  if (!b2books_) b2books_ = std::make_shared<Books>();
  Books& k = *b2books_;
  const double s = config_.scale;
  k.engine = this;
  k.world = box2d_world();
  k.loads.clear(), k.carriers.clear();
  // The account of each load, the body it acts on, and where in its frame.
  std::uint32_t account = 0;
  std::string last = "\x01";
  auto add = [&](const std::string& stage, std::uint32_t slot, std::uint32_t generation, Vec3 force,
                 Vec3 torque, const Vec3* point, Vec3 force_rate, Vec3 torque_rate) {
    b2Vec2 local;
    b2Body* b = carrier(slot, generation, local);
    if (!b) return;
    if (point) local = b->GetLocalPoint(b2Vec2(float(point->x * s), float(point->y * s)));
    if (stage != last) account = books_.account(stage), last = stage;
    // Box2D applies forces in the plane and torques about z (screen_loads
    // reports what it drops).
    k.loads.push_back({.a = {.body = k.carrier(b),
                             .force = {force.x, force.y, 0},
                             .torque = {0, 0, torque.z},
                             .source = account,
                             .local = {local.x, local.y, 0}},
                       .force_rate = {force_rate.x, force_rate.y, 0},
                       .torque_rate = {0, 0, torque_rate.z}});
  };
  auto weights = [&] {
    const std::string stage = uniform_source_ ? *uniform_source_ : std::string();
    for (const std::uint32_t slot : uniform_parts_)
      if (mass.has(slot)) add(stage, slot, 0, mass[slot] * uniform_g_, {}, nullptr, {}, {});
  };
  for (std::size_t i = 0; i < loads_.size(); ++i) {
    if (weigh && i == uniform_at_) weights();
    const LoadCommand& c = loads_[i];
    const std::string& stage = load_sources_.name_of(i);
    switch (c.kind) {
      case Load::Force:
        add(stage, c.slot, c.generation, c.value, {}, nullptr, {}, {});
        break;
      case Load::ForceAtPoint:
        add(stage, c.slot, c.generation, c.value, {}, &c.point, {}, {});
        break;
      case Load::Torque:
        add(stage, c.slot, c.generation, {}, c.value, nullptr, {}, {});
        break;
    }
  }
  if (weigh && uniform_at_ == loads_.size()) weights();
  for (std::size_t j = 0; j < rated_.size(); ++j) {
    const RatedLoad& r = rated_[j];
    add(rated_sources_.name_of(j), r.slot, r.generation, r.force, r.torque, nullptr, r.force_rate,
        r.torque_rate);
  }
  books_.applied.resize(k.loads.size());
  books_.v0.resize(k.carriers.size()), books_.w0.resize(k.carriers.size());
  k.angle0.resize(k.carriers.size()), k.centre0.resize(k.carriers.size());
  // Box2D's contact callbacks pass through the books while the window steps.
  k.inner = k.world->GetContactManager().m_contactListener;
  k.world->SetContactListener(&k);
}

void Box2DEngine::books_before_drag(double tau) {
  Books& k = *b2books_;
  k.ke0 = kinetic_energy();
  for (std::size_t i = 0; i < k.loads.size(); ++i) {
    const Books::Load& l = k.loads[i];
    rigid::EnergyBooks::Applied& a = books_.applied[i];
    a = l.a;
    a.force = l.a.force + tau * l.force_rate;
    a.torque = l.a.torque + tau * l.torque_rate;
  }
}

void Box2DEngine::books_before_step(double h) {
  Books& k = *b2books_;
  const double s = config_.scale;
  k.ke1 = kinetic_energy();
  books_.drag += k.ke0 - k.ke1;
  for (std::size_t c = 0; c < k.carriers.size(); ++c) {
    const b2Body* b = k.carriers[c];
    books_.v0[c] = si(b->GetLinearVelocity(), s);
    books_.w0[c] = {0, 0, b->GetAngularVelocity()};
    k.angle0[c] = b->GetAngle();
    k.centre0[c] = si(b->GetWorldCenter(), s);
  }
  // The velocities the solver starts from: each moving body's, kicked by
  // the step's loads (Box2D integrates forces first).
  k.kicked.clear();
  for (const b2Body* b = k.world->GetBodyList(); b; b = b->GetNext())
    if (b->GetType() == b2_dynamicBody)
      k.kicked.push_back({b, b->GetLinearVelocity(), b->GetAngularVelocity()});
  std::sort(k.kicked.begin(), k.kicked.end(),
            [](const Kicked& x, const Kicked& y) { return x.body < y.body; });
  for (rigid::EnergyBooks::Applied& a : books_.applied) {
    const b2Body* b = k.carriers[a.body];
    a.at = si(b->GetWorldPoint(b2Vec2(float(a.local.x), float(a.local.y))), s);
    a.arm = a.at - k.centre0[a.body];
    const double m = b->GetMass(), lc = double(b2Dot(b->GetLocalCenter(), b->GetLocalCenter()));
    const double ic = (double(b->GetInertia()) - m * lc) / (s * s);
    Kicked* kick = k.find(b);
    if (!kick || !b->IsAwake()) continue;  // a sleeper's loads are dropped
    const Vec3 dv = a.force * (h * s / m);
    kick->v += b2Vec2(float(dv.x), float(dv.y));
    if (ic > 0) kick->w += h * (a.torque + cross(a.arm, a.force)).z / ic;
  }
  k.collisions = 0;
}

void Box2DEngine::books_after_step(double h) {
  Books& k = *b2books_;
  const double s = config_.scale;
  double along_mean = 0;
  for (const rigid::EnergyBooks::Applied& a : books_.applied) {
    const b2Body* b = k.carriers[a.body];
    const Vec3 moved = si(b->GetWorldCenter(), s) - k.centre0[a.body];
    const double turn = double(b->GetAngle()) - k.angle0[a.body];
    const double work = dot(a.force, moved) + (a.torque + cross(a.arm, a.force)).z * turn;
    along_mean += books_.book_load(a, work, h, si(b->GetLinearVelocity(), s),
                                   {0, 0, b->GetAngularVelocity()});
  }
  for (std::size_t c = 0; c < k.carriers.size(); ++c)
    k.centre0[c] = si(k.carriers[c]->GetWorldCenter(), s);  // where the sweep starts from
  books_.restitution += k.collisions;
  books_.close_substep(along_mean - k.collisions, kinetic_energy() - k.ke1);
}

void Box2DEngine::books_close() {
  Books& k = *b2books_;
  const double s = config_.scale;
  // A body the sweep moved back moved with no velocity: the loads' work
  // along that move is booked with the integrator's share, as ODE books its
  // restitution pass's move to the time of impact.
  for (const rigid::EnergyBooks::Applied& a : books_.applied) {
    const double moved =
        dot(a.force, si(k.carriers[a.body]->GetWorldCenter(), s) - k.centre0[a.body]);
    books_.book_move(a, moved);
  }
  k.world->SetContactListener(k.inner);
}

void Box2DEngine::book_collision(b2Contact* c, const b2ContactImpulse* imp) {
  Books& k = *b2books_;
  const float e = c->GetRestitution();
  if (!(e > 0)) return;
  const double s = config_.scale;
  const b2Body* A = c->GetFixtureA()->GetBody();
  const b2Body* B = c->GetFixtureB()->GetBody();
  const Kicked* ka = k.find(A);
  const Kicked* kb = k.find(B);
  b2WorldManifold wm;
  c->GetWorldManifold(&wm);
  const b2Vec2 n = wm.normal, t = b2Cross(n, 1.0f);
  // Relative velocity of B against A at p, from velocities (v, w) of each.
  auto relative = [&](b2Vec2 p, b2Vec2 va, double wa, b2Vec2 vb, double wb) {
    const b2Vec2 ra = p - A->GetWorldCenter(), rb = p - B->GetWorldCenter();
    const b2Vec2 ua = va + b2Cross(float(wa), ra), ub = vb + b2Cross(float(wb), rb);
    return ub - ua;
  };
  const b2Vec2 zero(0, 0);
  for (int i = 0; i < imp->count; ++i) {
    const b2Vec2 before = relative(wm.points[i], ka ? ka->v : zero, ka ? ka->w : 0.0,
                                   kb ? kb->v : zero, kb ? kb->w : 0.0);
    // Box2D's rule: a point bounces when it approaches faster than the threshold.
    if (!(double(b2Dot(before, n)) < -double(c->GetRestitutionThreshold()))) continue;
    const b2Vec2 after = relative(wm.points[i], A->GetLinearVelocity(), A->GetAngularVelocity(),
                                  B->GetLinearVelocity(), B->GetAngularVelocity());
    const b2Vec2 mean = 0.5f * (before + after);
    const double work = double(imp->normalImpulses[i]) * double(b2Dot(mean, n)) +
                        double(imp->tangentImpulses[i]) * double(b2Dot(mean, t));
    k.collisions -= work / (s * s);
  }
}

}  // namespace alloy::box2d
