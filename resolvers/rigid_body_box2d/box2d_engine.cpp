#include "resolvers/rigid_body_box2d/box2d_engine.hpp"

#include <box2d/b2_distance.h>
#include <box2d/box2d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_set>
#include <utility>

#include "resolvers/rigid_body/hinge_anchors.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "runtime/stage_state.hpp"

namespace alloy::box2d {

using rigid::JointType;
using rigid::Shape;

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// The same drag as ODE's engine (rigid_body.cpp, damping_factor): the
/// velocity is multiplied by this before the step's kick, so a drag-limited
/// speed under a steady force is exact. Box2D's own damping, 1 / (1 + c h)
/// after the kick, would run such a speed slow by c h / 2; it is left at 0.
double damping_factor(double c, double h) {
  const double x = c * h;
  return x <= 0.5 ? 1 - x : 0.25 / x;
}

/// Moment of inertia about the part's z axis through its centre, kg m^2.
double inertia_z(Shape shape, double m, Vec3 size, double r, double len) {
  switch (shape) {
    case Shape::Box:
      return m * (size.x * size.x + size.y * size.y) / 12;
    case Shape::Sphere:
      return 0.4 * m * r * r;
    case Shape::Cylinder:
      return 0.5 * m * r * r;
    case Shape::Capsule: {
      // Cylinder of length len along x and two hemispheres at its ends.
      const double vc = std::numbers::pi * r * r * len,
                   vs = 4.0 / 3.0 * std::numbers::pi * r * r * r;
      const double mc = m * vc / (vc + vs), ms = m - mc;
      return mc * (3 * r * r + len * len) / 12 +
             ms * (0.4 * r * r + len * len / 4 + 3 * len * r / 8);
    }
  }
  return 0;
}

/// What another engine leaves out of the plane on a part that never left it:
/// ODE's contact solver and planar joint leave velocity.z of 1e-6 to 1e-4 m/s
/// and a tilt of the same order on a stack in the plane. Up to these bounds
/// the residue is dropped (Box2D keeps the part in z = 0); beyond them the
/// part is out of the plane and refused.
constexpr double kResidueZ = 1e-4;         // m, of position.z
constexpr double kResidueTilt = 1e-4;      // of the quaternion's x and y, by its norm
constexpr double kResidueSpeedZ = 1e-3;    // m/s, of velocity.z
constexpr double kResidueInPlaneW = 1e-2;  // rad/s, of angular_velocity.x and .y

/// Why a part with this pose and motion cannot be simulated in the plane, or
/// empty. `moving`: a part that is neither fixed nor `planar` (a `planar`
/// part's out-of-plane motion is residue by definition).
std::string off_plane(Vec3 p, Quat q, Vec3 v, Vec3 w, bool moving) {
  const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(std::abs(p.z) <= kResidueZ)) return "lies off the plane (z = " + num(p.z) + " m)";
  if (!(std::abs(q.x) <= kResidueTilt * qn && std::abs(q.y) <= kResidueTilt * qn))
    return "is turned about an axis other than z";
  if (!moving) return {};
  if (!(std::abs(v.z) <= kResidueSpeedZ))
    return "moves out of the plane (velocity.z = " + num(v.z) + " m/s)";
  if (!(std::abs(w.x) <= kResidueInPlaneW && std::abs(w.y) <= kResidueInPlaneW))
    return "spins about an axis in the plane (angular_velocity {" + num(w.x) + ", " + num(w.y) +
           ", " + num(w.z) + "})";
  return {};
}

/// Box2D mixes friction as sqrt(a b) and restitution as max(a, b) in single
/// precision: a coefficient of 1e80 overflows to inf and the solver makes NaN
/// of it. Past 1e6 a friction coefficient already means "never slides" for
/// every load the bounds allow, so larger ones are held there.
constexpr double kMaxCoefficient = 1e6;
double coefficient(double c) {
  return std::min(c, kMaxCoefficient);
}

/// The most one Box2D step may move a body (b2_maxTranslation, in its units)
/// and turn it (b2_maxRotation, rad): Box2D clamps faster motion silently.
/// The engine takes as many substeps as keep every body within 90 % of them,
/// up to kMaxAutoSubsteps; a body that would need more is refused.
constexpr int kMaxAutoSubsteps = 64;

}  // namespace

// --- settings -----------------------------------------------------------------------

Box2DConfig Box2DConfig::from(const PluginSettings& s) {
  s.check_known("rigid_body.box2d", {"scale", "velocity_iterations", "position_iterations",
                                     "substeps", "max_substep", "sleep", "bounce_velocity"});
  Box2DConfig c;
  auto bad = [&](const std::string& what) {
    throw InputError(s.where, "rigid_body.box2d: " + what);
  };
  c.scale = s.number("scale", c.scale);
  if (!(c.scale >= 1e-3 && c.scale <= 1e3))
    bad("scale must be between 0.001 and 1000 units per metre");
  c.velocity_iterations = int(s.integer("velocity_iterations", c.velocity_iterations));
  if (c.velocity_iterations < 1 || c.velocity_iterations > 1000)
    bad("velocity_iterations must be 1..1000");
  c.position_iterations = int(s.integer("position_iterations", c.position_iterations));
  if (c.position_iterations < 0 || c.position_iterations > 1000)
    bad("position_iterations must be 0..1000");
  c.substeps = int(s.integer("substeps", c.substeps));
  if (c.substeps < 1 || c.substeps > 1000) bad("substeps must be 1..1000");
  c.max_substep = s.number("max_substep", c.max_substep);
  if (!(c.max_substep == 0 || (c.max_substep >= 1e-6 && c.max_substep <= 1)))
    bad("max_substep must be 0 (no bound) or between 1e-6 and 1 s");
  c.sleep = s.boolean("sleep", c.sleep);
  c.bounce_velocity = s.number("bounce_velocity", c.bounce_velocity);
  if (!(c.bounce_velocity >= 0 && c.bounce_velocity < 1e6)) bad("bounce_velocity must be >= 0 m/s");
  return c;
}

int substeps_for(const Box2DConfig& c, double dt) {
  // A step equal to max_substep up to rounding is one Box2D step.
  if (!(c.max_substep > 0)) return c.substeps;
  const double k = std::ceil(dt / c.max_substep * (1 - 1e-9));
  return std::max(c.substeps, int(std::min(k, 1000.0)));
}

// --- Box2D's world and the tables ----------------------------------------------------

struct Box2DEngine::Impl : b2ContactListener, b2ContactFilter {
  /// A part: which body carries it and where in the body's frame.
  struct Part {
    ObjectId id;
    std::uint32_t body;
    b2Vec2 local;      // centre in the body's frame, scaled units
    double angle = 0;  // relative to the body
    double friction = 0.5, restitution = 0;
    double inscribed = 0;  // radius of the largest disk inside the part, m (sweeps)
    // What we last wrote (to tell an edit from outside).
    Vec3 pos, vel, ang;
    Quat rot;
    /// The angle `rot` was made from at the last write-back (NaN: none): a
    /// part that has not turned since is not given a sine and cosine again.
    double rot_angle = std::numeric_limits<double>::quiet_NaN();
  };
  struct Body {
    b2Body* b = nullptr;
    bool dynamic = false;
    double linear_damping = 0, angular_damping = 0;
    b2Vec2 force{0, 0};  // the window's summed load, for waking sleepers
    float torque = 0;
    b2Vec2 last_force{0, 0};
    float last_torque = 0;
    bool written_asleep = false;  // asleep at the last write-back
    bool still = false;           // and at this one: nothing to write
  };
  struct Hinge {
    ObjectId id;
    b2RevoluteJoint* j;
  };
  struct PreSpeed {
    ObjectId a, b;
    double speed;
  };

  double s = 10;
  double bounce = 0.1;
  bool want_impulses = false;
  std::unique_ptr<b2World> world;
  b2Body* ground = nullptr;
  std::vector<Part> parts;
  std::vector<std::int32_t> part_of_slot;  // slot -> index into parts, -1: not ours
  std::vector<Body> bodies;
  std::vector<Hinge> hinges;
  std::vector<PreSpeed> pre_speeds;
  std::vector<PairImpulse> step_impulses;
  /// A touching contact, its parts' ids in order, and its place in Box2D's list.
  struct ContactKey {
    ObjectId a, b;
    b2Contact* c;
    std::uint32_t seq;
    /// Published touching though Box2D's contact is not: kept across a drop
    /// of its touching test (kept_contacts); its point comes from the
    /// shapes' distance.
    bool kept = false;
  };
  std::vector<ContactKey> contact_keys, last_keys;  // this step's, and the last sorted ones
  std::vector<std::uint32_t> contact_order;         // into contact_keys, by (a, b, seq)
  /// A contact began or ended touching since the keys were taken (Box2D's
  /// BeginContact and EndContact; set by a build): while it is false, the
  /// touching contacts are those of the keys, in the same list order (Box2D
  /// prepends the contacts it makes, and a contact it destroys that touched
  /// ends first), so the keys stand and the list is not walked again.
  bool touch_changed = true;
  void BeginContact(b2Contact*) override { touch_changed = true; }
  void EndContact(b2Contact* c) override {
    touch_changed = true;
    ended.push_back({c->GetFixtureA(), c->GetFixtureB()});
  }

  // --- contacts Box2D's touching test leaves out ------------------------------------
  // Box2D 2.4 calls two shapes touching when their manifold has a point, and
  // b2CollidePolygons keeps a point when its separation is at most the two
  // skins (`separation <= totalRadius`), with no margin. Its solvers leave a
  // contact made at zero overlap (parts placed touching, as the kit's are)
  // there: the velocity solver stops the approach and the position solver
  // corrects only overlaps past the linear slop. The test then sits on its
  // rounding, which changes with the bodies' transforms: a block sliding on a
  // floor lost the contact for one step (adv F5) when the rounding went the
  // other way, fell for that step without friction and landed 0.17 mm deeper.
  // The engine keeps such a pair touching in what it publishes while the
  // skins are within kKeepGap of each other. (With several Box2D steps to a
  // world step, publishing also the contacts made and broken between them
  // was tried and left out: brief touches of the motor's slider on the next
  // spoke closed a coil's circuit for a whole step and stalled the rotor at
  // 1/120 s; docs/box2d.md, "Box2D's step and the world's".)
  struct FixturePair {
    b2Fixture* a;
    b2Fixture* b;
  };
  struct PairHash {
    std::size_t operator()(const std::pair<const b2Fixture*, const b2Fixture*>& p) const {
      const std::hash<const void*> h;
      return h(p.first) * 31 + h(p.second);
    }
  };
  std::vector<FixturePair> ended;  // EndContact in this advance
  std::vector<FixturePair> kept;   // pairs kept at the last advance
  /// The largest gap between the skins of a kept pair, Box2D units: a tenth
  /// of the linear slop (Box2D's own tolerance for the choice of reference
  /// face), 0.05 mm at scale 10; the rounding is below 1e-4 up to 1,000 units.
  static constexpr float kKeepGap = 0.1f * b2_linearSlop;
  /// Box2D's contact between two fixtures, or null (destroyed, or never made).
  static b2Contact* contact_of(b2Fixture* fa, b2Fixture* fb) {
    b2Body* body = fa->GetBody()->GetType() == b2_staticBody ? fb->GetBody() : fa->GetBody();
    for (b2ContactEdge* e = body->GetContactList(); e; e = e->next) {
      b2Contact* c = e->contact;
      if ((c->GetFixtureA() == fa && c->GetFixtureB() == fb) ||
          (c->GetFixtureA() == fb && c->GetFixtureB() == fa))
        return c;
    }
    return nullptr;
  }
  /// The closest points of a contact's two shapes (cores, without skins).
  static b2DistanceOutput distance(const b2Contact* c) {
    b2DistanceInput in;
    in.proxyA.Set(c->GetFixtureA()->GetShape(), c->GetChildIndexA());
    in.proxyB.Set(c->GetFixtureB()->GetShape(), c->GetChildIndexB());
    in.transformA = c->GetFixtureA()->GetBody()->GetTransform();
    in.transformB = c->GetFixtureB()->GetBody()->GetTransform();
    in.useRadii = false;
    b2SimplexCache cache;
    cache.count = 0;
    b2DistanceOutput out;
    b2Distance(&out, &cache, &in);
    return out;
  }
  /// The contacts to publish touching though Box2D's are not (see above),
  /// appended to `keys`; remembers the kept ones for the next advance.
  void kept_contacts(std::vector<ContactKey>& keys) {
    std::vector<FixturePair> now;
    // Each pair once, whichever fixture comes first: a set, not a scan of
    // `now` per pair (a heap that flies apart ends thousands of contacts in
    // one advance).
    std::unordered_set<std::pair<const b2Fixture*, const b2Fixture*>, PairHash> looked_at;
    auto consider = [&](const FixturePair& p) {
      const b2Fixture* lo = std::min<const b2Fixture*>(p.a, p.b);
      const b2Fixture* hi = std::max<const b2Fixture*>(p.a, p.b);
      if (!looked_at.insert({lo, hi}).second) return;
      b2Contact* c = contact_of(p.a, p.b);
      if (!c || !c->IsEnabled() || c->IsTouching()) return;
      const float r =
          c->GetFixtureA()->GetShape()->m_radius + c->GetFixtureB()->GetShape()->m_radius;
      if (!(distance(c).distance - r <= kKeepGap)) return;
      now.push_back({c->GetFixtureA(), c->GetFixtureB()});
      const ObjectId a = part_of(c->GetFixtureA()).id, b = part_of(c->GetFixtureB()).id;
      keys.push_back({std::min(a, b), std::max(a, b), c, std::uint32_t(keys.size()), true});
    };
    for (const FixturePair& p : ended) consider(p);
    for (const FixturePair& p : kept) consider(p);
    ended.clear();
    kept = std::move(now);
  }
  /// Versions of position, orientation, velocity and angular_velocity after
  /// the last write-back (none after a build: the parts are compared then).
  std::array<std::uint64_t, 4> written_versions{~0ull, ~0ull, ~0ull, ~0ull};

  Part& part_of(b2Fixture* f) { return parts[f->GetUserData().pointer]; }

  // The bound on contact pairs (limits::contact_pairs_per_part): Box2D asks
  // before it makes a contact for a new pair of overlapping fixtures; when
  // both bodies already have that many contacts with moving bodies, the pair
  // is left out (its parts pass through each other) and counted.
  std::size_t left_out = 0;
  std::vector<std::uint32_t> left_out_of;  // by index into parts
  static bool crowded(const b2Body* b) {
    std::uint32_t n = 0;
    for (const b2ContactEdge* e = b->GetContactList(); e; e = e->next)
      if (e->other->GetType() == b2_dynamicBody && ++n >= rigid::limits::contact_pairs_per_part)
        return true;
    return false;
  }
  std::uint64_t filter_calls = 0;  // pairs Box2D's broad phase put to the filter, in all
  bool ShouldCollide(b2Fixture* a, b2Fixture* b) override {
    ++filter_calls;
    if (!b2ContactFilter::ShouldCollide(a, b)) return false;
    if (!crowded(a->GetBody()) || !crowded(b->GetBody())) return true;
    left_out_of.resize(parts.size(), 0);
    ++left_out_of[a->GetUserData().pointer], ++left_out_of[b->GetUserData().pointer];
    ++left_out;
    return false;
  }

  // --- parts buried in a heap (docs/security.md, F14) -------------------------------
  // The bound on contact pairs above is asked after Box2D's broad phase has
  // found a pair and AddPair has walked a body's contact list for it: a heap
  // of n parts placed through each other still costs n^2 / 2 of those a step
  // (3,000 parts: over 12 s). A part that deeply overlaps more than kCrowd
  // moving parts' shapes (their cores closer than half the sum of their
  // radii: a rounded box sunk past its skin, a disk past half its radius;
  // resting parts overlap by Box2D's linear slop, 0.5 mm, not that) waits:
  // its body is taken out of Box2D's world (b2Body::SetEnabled: no proxy in
  // the broad phase, no contacts), held still, until the parts around it
  // have moved apart and it is sunk into at most kWake of them. A heap keeps
  // kCrowd + 1 parts in the world at its spot, each with every pair it
  // touches (the contact limit leaves none out), and lets the others back a
  // few at a time as they push apart.
  static constexpr std::uint32_t kCrowd = rigid::limits::contact_pairs_per_part;
  /// A waiting body comes back when it is sunk into at most this many: into
  /// room the heap's parts have made by moving apart, not into the heap again
  /// (at kCrowd, 1,000 parts came back into a mass where the contact limit
  /// left pairs out, and steps took 1 s).
  static constexpr std::uint32_t kWake = 4;
  std::vector<std::uint32_t> dormant;  // bodies taken out, by index, in the order they went
  std::size_t went_dormant = 0;        // since the last report (for the event)
  bool waiting_reported = false;       // the event was sent and some still wait
  std::uint32_t dormant_example = 0;   // a body that went, for the event
  std::uint64_t crowd_tests = 0;       // shape tests made by crowded_body, in all
  struct CrowdQuery final : b2QueryCallback {
    const b2Body* self = nullptr;
    const b2Fixture* mine = nullptr;
    std::vector<const b2Body*>* seen = nullptr;
    std::uint64_t* tests = nullptr;
    std::uint32_t limit = kCrowd;
    bool ReportFixture(b2Fixture* f) override {
      const b2Body* b = f->GetBody();
      if (b == self || b->GetType() != b2_dynamicBody || !b->IsEnabled()) return true;
      if (std::find(seen->begin(), seen->end(), b) != seen->end()) return true;
      b2DistanceInput in;
      in.proxyA.Set(mine->GetShape(), 0);
      in.proxyB.Set(f->GetShape(), 0);
      in.transformA = self->GetTransform();
      in.transformB = b->GetTransform();
      in.useRadii = false;
      b2SimplexCache cache;
      cache.count = 0;
      b2DistanceOutput out;
      b2Distance(&out, &cache, &in);
      ++*tests;
      if (out.distance < 0.5f * (mine->GetShape()->m_radius + f->GetShape()->m_radius))
        seen->push_back(b);
      return seen->size() <= limit;  // enough: stop the query
    }
  };
  std::vector<const b2Body*> crowd_seen;
  /// Whether body `bi` deeply overlaps more than `limit` moving bodies in
  /// the world (it may be out of it: its shapes are placed where it is).
  bool crowded_body(std::uint32_t bi, std::uint32_t limit = kCrowd) {
    const b2Body* b = bodies[bi].b;
    crowd_seen.clear();
    CrowdQuery q;
    q.self = b, q.seen = &crowd_seen, q.tests = &crowd_tests, q.limit = limit;
    for (const b2Fixture* f = b->GetFixtureList(); f && crowd_seen.size() <= limit;
         f = f->GetNext()) {
      b2AABB box;
      f->GetShape()->ComputeAABB(&box, b->GetTransform(), 0);
      q.mine = f;
      world->QueryAABB(&q, box);
    }
    return crowd_seen.size() > limit;
  }
  void make_dormant(std::uint32_t bi) {
    b2Body* b = bodies[bi].b;
    b->SetLinearVelocity(b2Vec2(0, 0));
    b->SetAngularVelocity(0);
    b->SetEnabled(false);
    dormant.push_back(bi);
    if (went_dormant++ == 0) dormant_example = bi;
  }
  /// Takes out every moving body, in order, that is crowded by the bodies
  /// still in (a heap of n keeps its last kCrowd + 1).
  void settle_crowds() {
    for (std::uint32_t bi = 0; bi < bodies.size(); ++bi)
      if (bodies[bi].dynamic && bodies[bi].b->IsEnabled() && crowded_body(bi)) make_dormant(bi);
  }
  /// Puts back, in the order they went, the waiting bodies that are no
  /// longer crowded (each one put back counts for the next).
  void wake_uncrowded() {
    std::size_t kept = 0;
    for (const std::uint32_t bi : dormant) {
      if (bodies[bi].dynamic && crowded_body(bi, kWake)) {
        dormant[kept++] = bi;
        continue;
      }
      bodies[bi].b->SetEnabled(true);
    }
    dormant.resize(kept);
  }

  // --- continuous detection, by ODE's rule (resolvers/rigid_body/collisions.hpp) ---
  // A part that moved more than half its inscribed radius in the step, along
  // its velocity, is swept: a ray from its centre's previous position to its
  // current one. If the centre crossed the surface of a static part (one it
  // did not touch at the step before, not one hinged to it), the part
  // tunnelled: its body goes back along the path to where the part, a disk of
  // its inscribed radius, first touches that surface with Box2D's resting
  // overlap, its velocity kept, and the next step's contact stops it. Unlike
  // Box2D's time-of-impact sub-step this does nothing to a body that only
  // sinks into a surface (the doorbell's hammer into its bell); like it, it
  // moves a body that did tunnel without its joints' partners (the joints
  // pull them together at the next step), and it looks at static parts only
  // (ODE's looks at every part).
  std::uint64_t sweeps = 0;  // parts moved back, in every advance so far
  struct RayHit final : b2RayCastCallback {
    Impl* m = nullptr;
    const b2Body* self = nullptr;
    ObjectId id;
    // The pairs touching after the advance before (its contact keys, and
    // their order by (a, b)).
    const std::vector<ContactKey>* keys = nullptr;
    const std::vector<std::uint32_t>* order = nullptr;
    float fraction = 2;
    b2Vec2 normal{0, 0};
    const b2Fixture* fixture = nullptr;
    float ReportFixture(b2Fixture* f, const b2Vec2&, const b2Vec2& n, float frac) override {
      const b2Body* b = f->GetBody();
      // Static surfaces only, as Box2D's time-of-impact sub-step did: a
      // link of a swinging 50-link chain swept against its neighbours' neighbours
      // was moved back without the links hinged to it and opened a joint by 4 cm.
      if (b == self || f->IsSensor() || b->GetType() != b2_staticBody) return -1;
      for (const b2JointEdge* e = self->GetJointList(); e; e = e->next)
        if (e->other == b) return -1;
      const ObjectId other = m->part_of(f).id;
      const ObjectId a = std::min(id, other), c = std::max(id, other);
      const auto at =
          std::lower_bound(order->begin(), order->end(), a, [&](std::uint32_t k, ObjectId) {
            const ContactKey& x = (*keys)[k];
            return pair_less(x.a, x.b, a, c);
          });
      if (at != order->end() && (*keys)[*at].a == a && (*keys)[*at].b == c) return -1;
      fraction = frac, normal = n, fixture = f;
      return frac;  // the nearest surface
    }
  };
  void sweep(double dt) {
    const double layer = double(b2_linearSlop) / s;
    for (Part& part : parts) {
      const Body& body = bodies[part.body];
      if (!body.dynamic) continue;
      b2Body* b = body.b;
      const b2Vec2 c = b->GetWorldPoint(part.local);
      const Vec3 to{c.x / s, c.y / s, 0}, d = to - part.pos;
      const double len2 = dot(d, d);
      if (!(len2 > 0.25 * part.inscribed * part.inscribed)) continue;  // the usual case
      const double len = std::sqrt(len2);
      // Only motion along the velocity: an edit that carries a part through
      // a wall is not undone.
      const b2Vec2 v = b->GetLinearVelocityFromWorldPoint(c);
      const Vec3 step{v.x / s * dt, v.y / s * dt, 0};
      if (length(d - step) > 0.5 * len) continue;
      RayHit hit;
      hit.m = this, hit.self = b, hit.id = part.id, hit.keys = &contact_keys,
      hit.order = &contact_order;
      world->RayCast(&hit, b2Vec2(float(part.pos.x * s), float(part.pos.y * s)), c);
      if (!hit.fixture) continue;  // the centre crossed no surface: the discrete contact sees it
      const Vec3 dir = d / len;
      Vec3 n{hit.normal.x, hit.normal.y, 0};
      if (dot(n, dir) > 0) n = Vec3{} - n;  // out of the surface, towards where the part came from
      const double incidence = std::max(-dot(n, dir), 0.05);
      // A polygon's ray stops at its core; its skin is outside that.
      const double skin = hit.fixture->GetType() == b2Shape::e_polygon
                              ? double(hit.fixture->GetShape()->m_radius) / s
                              : 0.0;
      const double along =
          std::max(0.0, double(hit.fraction) * len - (part.inscribed + skin - layer) / incidence);
      const Vec3 back = part.pos + dir * along - to;
      b->SetTransform(b->GetPosition() + b2Vec2(float(back.x * s), float(back.y * s)),
                      b->GetAngle());
      ++sweeps;
    }
  }

  double approach(b2Contact* c, const b2WorldManifold& wm, int n, bool a_is_A) const {
    // Normal speed of a towards b at the points, SI.
    const b2Body* A = c->GetFixtureA()->GetBody();
    const b2Body* B = c->GetFixtureB()->GetBody();
    double best = 0;
    for (int i = 0; i < n; ++i) {
      const b2Vec2 rel = B->GetLinearVelocityFromWorldPoint(wm.points[i]) -
                         A->GetLinearVelocityFromWorldPoint(wm.points[i]);
      // Box2D's normal points from A to B: A and B close in when rel . n < 0.
      best = std::max(best, -double(b2Dot(rel, wm.normal)) / s);
    }
    (void)a_is_A;
    return best;
  }

  /// A kept contact's point (kept_contacts): one, on A's surface where the
  /// shapes are closest, the normal from A to B, its separation the skins'
  /// gap. Returns the number of points (1; 0 if the cores overlap, when the
  /// closest points give no normal: not seen at a gap within kKeepGap).
  static int kept_manifold(const b2Contact* c, b2WorldManifold& wm) {
    const b2DistanceOutput d = distance(c);
    const float ra = c->GetFixtureA()->GetShape()->m_radius,
                rb = c->GetFixtureB()->GetShape()->m_radius;
    if (!(d.distance > b2_epsilon)) return 0;
    wm.normal = (1.0f / d.distance) * (d.pointB - d.pointA);
    wm.points[0] = d.pointA + ra * wm.normal;
    wm.separations[0] = d.distance - ra - rb;
    return 1;
  }

  void PreSolve(b2Contact* c, const b2Manifold* old) override {
    if (old->pointCount == 0) {  // Box2D calls this for every touching contact a step
      const Part& pa = part_of(c->GetFixtureA());
      const Part& pb = part_of(c->GetFixtureB());
      // The same mixing as rigid_body_from_collisions for ODE, set when the
      // contact begins to touch: Box2D keeps a contact's values until it is
      // destroyed, and a change of the materials rebuilds the world.
      c->SetFriction(float(std::sqrt(pa.friction * pb.friction)));
      c->SetRestitution(float(std::clamp(std::max(pa.restitution, pb.restitution), 0.0, 1.0)));
      c->SetRestitutionThreshold(float(bounce * s));
      // Just began: the impact speed, before the solver removes it.
      b2WorldManifold wm;
      c->GetWorldManifold(&wm);
      const double v = approach(c, wm, c->GetManifold()->pointCount, true);
      pre_speeds.push_back({std::min(pa.id, pb.id), std::max(pa.id, pb.id), v});
    }
  }

  void PostSolve(b2Contact* c, const b2ContactImpulse* imp) override {
    if (!want_impulses) return;
    const Part& pa = part_of(c->GetFixtureA());
    const Part& pb = part_of(c->GetFixtureB());
    b2WorldManifold wm;
    c->GetWorldManifold(&wm);
    const b2Vec2 n = wm.normal, t = b2Cross(n, 1.0f);
    double jn = 0, jt = 0;
    for (int i = 0; i < imp->count; ++i)
      jn += imp->normalImpulses[i], jt += imp->tangentImpulses[i];
    // Box2D applies +P to B and -P to A, P = jn n + jt t.
    b2Vec2 on_A = -(float(jn) * n + float(jt) * t);
    const bool a_is_A = pa.id < pb.id;
    const b2Vec2 on_a = a_is_A ? on_A : -on_A;
    step_impulses.push_back({.a = std::min(pa.id, pb.id),
                             .b = std::max(pa.id, pb.id),
                             .impulse = {on_a.x / s, on_a.y / s, 0},
                             .normal_impulse = jn / s});
  }
};

// --- the engine ---------------------------------------------------------------------

Box2DEngine::Box2DEngine(const World& world, Box2DConfig config)
    : world_(world), store_(world.store()), config_(config), impl_(std::make_unique<Impl>()) {
  impl_->s = config_.scale;
  impl_->bounce = config_.bounce_velocity;
}

Box2DEngine::~Box2DEngine() {
  if (contacts_) contacts_->engine_gone();
}

namespace {
const char* const kDefining[] = {"shape",      "size",           "radius",          "length",
                                 "mass",       "density",        "static",          "pinned",
                                 "planar",     "linear_damping", "angular_damping", "joint",
                                 "body_a",     "body_b",         "joint_friction",  "limit_low",
                                 "limit_high", "friction",       "restitution",     "axis"};
}

void Box2DEngine::note_versions(const WorldView& v) {
  // The ids are looked up once (by name, a hash a property): a world's
  // properties keep their ids.
  if (defining_.empty())
    for (const char* n : kDefining) defining_.push_back(v.property(n));
  versions_.clear();
  for (const PropertyId p : defining_) versions_.push_back(v.store().column(p).version());
}

bool Box2DEngine::edited_since_write(const WorldView& v) const {
  if (versions_.size() != defining_.size()) return true;
  for (std::size_t i = 0; i < defining_.size(); ++i)
    if (v.store().column(defining_[i]).version() != versions_[i]) return true;
  return false;
}

void Box2DEngine::build(ResolverAccess& access) {
  Impl& m = *impl_;
  const double s = m.s;
  ++rebuilds_;
  m.world = std::make_unique<b2World>(b2Vec2(0, 0));  // gravity comes as loads
  m.world->SetAllowSleeping(config_.sleep);
  // Box2D's own continuous collision is off: its time-of-impact sub-step
  // moves a body that would sink more than 1.5 mm (3 linear slops) into a
  // static part in one step back to the impact, solving that body's contacts
  // but none of its joints. The doorbell's lever, struck into the bell, was
  // moved so without the contact finger hinged to it: the finger's hinge
  // passed its stop by 0.04 rad, the next step's joint solve threw the lever
  // back at 10 rad/s, and the strikes came at 14 to 23 steps, not 16
  // (docs/box2d.md, "The doorbell on both engines"). The engine sweeps fast
  // parts itself instead, by ODE's rule (sweep() below).
  m.world->SetContinuousPhysics(false);
  m.world->SetContactListener(&m);
  m.world->SetContactFilter(&m);
  m.touch_changed = true;  // the keys point into the world just destroyed
  m.ended.clear(), m.kept.clear();
  m.contact_keys.clear(), m.last_keys.clear(), m.contact_order.clear();
  m.parts.clear();
  m.dormant.clear();
  m.written_versions.fill(~0ull);
  m.bodies.clear();
  m.hinges.clear();
  b2BodyDef gd;
  m.ground = m.world->CreateBody(&gd);

  const auto shape = access.column<EnumValue>("shape");
  const auto size = access.column<Vec3>("size");
  const auto radius = access.column<double>("radius");
  const auto length = access.column<double>("length");
  const auto mass = access.column<double>("mass");
  const auto density = access.column<double>("density");
  const auto static_ = access.column<std::uint8_t>("static");
  const auto pinned = access.column<std::uint8_t>("pinned");
  const auto planar = access.column<std::uint8_t>("planar");
  const auto position = access.column<Vec3>("position");
  const auto orientation = access.column<Quat>("orientation");
  const auto velocity = access.column<Vec3>("velocity");
  const auto angular = access.column<Vec3>("angular_velocity");
  const auto ldamp = access.column<double>("linear_damping");
  const auto adamp = access.column<double>("angular_damping");
  const auto friction = access.column<double>("friction");
  const auto restitution = access.column<double>("restitution");
  const auto joint = access.column<EnumValue>("joint");
  const auto body_a = access.column<ObjectId>("body_a");
  const auto body_b = access.column<ObjectId>("body_b");
  const auto anchor = access.column<Vec3>("anchor");
  const auto anchor_a = access.column<Vec3>("anchor_a");
  const auto anchor_b = access.column<Vec3>("anchor_b");
  const auto axis = access.column<Vec3>("axis");
  const auto jfric = access.column<double>("joint_friction");
  const auto lo = access.column<double>("limit_low");
  const auto hi = access.column<double>("limit_high");
  auto mass_out = access.writer<double>("mass");
  auto anchor_a_out = access.writer<Vec3>("anchor_a");
  auto anchor_b_out = access.writer<Vec3>("anchor_b");

  auto refuse = [&](ObjectId id, const std::string& why) {
    // Named by the object, so that the scene loader adds its file and line.
    throw InputError(ErrorLocation{"", 0, store_.describe(id)},
                     "rigid_body.box2d: '" + store_.describe(id) + "' " + why +
                         " (Box2D simulates the z = 0 plane only; use the ODE rigid_body for it)");
  };

  // Parts: every object with a shape, in the plane.
  m.part_of_slot.assign(store_.slot_count(), -1);
  const bool mid_run = rebuilds_ > 1 || world_.step_count() > 0;
  std::vector<char> skipped(store_.slot_count(), 0);  // parts refused in this build
  auto refused_part = [&](ObjectId id) {
    return !id.is_null() && id.index < skipped.size() && skipped[id.index];
  };
  for (std::uint32_t slot : shape.members()) {
    const ObjectId id = store_.id_at(slot);
    const bool fixed = static_.value_or(slot, 0) || pinned.value_or(slot, 0);
    const std::string why = off_plane(position.value_or(slot, {}), orientation.value_or(slot, {}),
                                      velocity.value_or(slot, {}), angular.value_or(slot, {}),
                                      !fixed && !planar.value_or(slot, 0));
    if (!why.empty()) {
      // At the scene's load the scene is wrong: an error naming the part. In
      // a run (a rebuild after an edit or a mod's write, a swap to this
      // engine, a part crossing into its area) the part is refused instead
      // (frozen, an out_of_bounds event naming it) and the world goes on.
      if (!mid_run) refuse(id, why);
      access.refuse(slot, "", why + " (Box2D simulates the z = 0 plane only)");
      skipped[slot] = 1;
      continue;
    }
    m.part_of_slot[slot] = std::int32_t(m.parts.size());
    Impl::Part part;
    part.id = id;
    part.friction = coefficient(friction.value_or(slot, 0.5));
    part.restitution = coefficient(restitution.value_or(slot, 0.0));
    m.parts.push_back(part);
  }

  // Glue: parts joined by fixed joints share a body (union-find).
  std::vector<std::uint32_t> root(m.parts.size());
  std::iota(root.begin(), root.end(), 0u);
  auto find = [&](std::uint32_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  std::vector<char> glued_to_world(m.parts.size(), 0);
  auto ours = [&](ObjectId id) -> std::int32_t {
    if (id.is_null() || !store_.alive(id) || id.index >= m.part_of_slot.size()) return -1;
    return m.part_of_slot[id.index];
  };
  // A joint whose body_b is ours and body_a another engine's (an area's):
  // neither engine can hold it.
  auto refuse_across = [&](std::uint32_t slot, const char* what) {
    throw InputError(ErrorLocation{"", 0, store_.describe(store_.id_at(slot))},
                     "rigid_body.box2d: joint '" + store_.describe(store_.id_at(slot)) + "' (" +
                         what + ") joins '" + store_.describe(body_a.value_or(slot, {})) +
                         "' to '" + store_.describe(body_b.value_or(slot, {})) + "', but '" +
                         store_.describe(body_a.value_or(slot, {})) +
                         "' is simulated by another engine (an area's): a joint's two bodies must "
                         "be on one engine");
  };
  for (std::uint32_t slot : joint.members()) {
    if (JointType(joint[slot].index) != JointType::Fixed) continue;
    const ObjectId bid = body_b.value_or(slot, {});
    if (refused_part(body_a.value_or(slot, {})) || refused_part(bid)) continue;  // holds nothing
    const std::int32_t a = ours(body_a.value_or(slot, {})), b = ours(bid);
    if (a < 0 && b >= 0) refuse_across(slot, "glues");
    if (a < 0) continue;  // the joint lives with body_a's engine
    if (bid.is_null())
      glued_to_world[std::size_t(a)] = 1;
    else if (b < 0)
      throw InputError(
          ErrorLocation{"", 0, store_.describe(store_.id_at(slot))},
          "rigid_body.box2d: joint '" + store_.describe(store_.id_at(slot)) + "' glues '" +
              store_.describe(store_.id_at(std::uint32_t(m.parts[std::size_t(a)].id.index))) +
              "' to '" + store_.describe(bid) +
              "', which another engine simulates (a joint lives in body_a's engine, and "
              "both its bodies must be there)");
    else
      root[find(std::uint32_t(a))] = find(std::uint32_t(b));
  }

  // Bodies: one per assembly. The body's origin is its first part's centre.
  std::vector<std::int32_t> body_of_root(m.parts.size(), -1);
  for (std::uint32_t i = 0; i < m.parts.size(); ++i) {
    const std::uint32_t r = find(i);
    if (body_of_root[r] < 0) {
      body_of_root[r] = std::int32_t(m.bodies.size());
      m.bodies.emplace_back();
    }
    m.parts[i].body = std::uint32_t(body_of_root[r]);
  }
  struct Acc {
    ObjectId first;
    bool fixed = false;
    double m = 0, I = 0;  // I about the origin, SI
    b2Vec2 mc{0, 0};      // sum of m * local centre, scaled
    Vec3 v, w;
    bool have_first = false;
    // The parts' own motions, about the first part's centre `x0` (SI): momentum,
    // sum of m r, angular momentum about x0, sum of I + m r^2; `rigid` while every
    // part moves as the first part's rigid motion says.
    Vec3 x0, p, mr;
    double L = 0, Ir = 0, pm = 0;
    bool rigid = true;
  };
  std::vector<Acc> acc(m.bodies.size());
  for (std::uint32_t i = 0; i < m.parts.size(); ++i) {
    const std::uint32_t slot = m.parts[i].id.index;
    Acc& a = acc[m.parts[i].body];
    a.fixed = a.fixed || static_.value_or(slot, 0) || pinned.value_or(slot, 0) || glued_to_world[i];
    if (!a.have_first) a.have_first = true, a.first = m.parts[i].id;
  }
  for (std::uint32_t bi = 0; bi < m.bodies.size(); ++bi) {
    const std::uint32_t slot = acc[bi].first.index;
    const Vec3 p = position.value_or(slot, {});
    b2BodyDef d;
    d.type = acc[bi].fixed ? b2_staticBody : b2_dynamicBody;
    d.position.Set(float(p.x * s), float(p.y * s));
    d.angle = float(angle_z(orientation.value_or(slot, {})));
    d.bullet = false;
    m.bodies[bi].b = m.world->CreateBody(&d);
    m.bodies[bi].dynamic = !acc[bi].fixed;
    acc[bi].v = velocity.value_or(slot, {});
    acc[bi].w = angular.value_or(slot, {});
    acc[bi].x0 = p;
  }

  // Fixtures and masses.
  for (std::uint32_t i = 0; i < m.parts.size(); ++i) {
    Impl::Part& part = m.parts[i];
    const std::uint32_t slot = part.id.index;
    Impl::Body& body = m.bodies[part.body];
    b2Body* b = body.b;
    const Vec3 p = position.value_or(slot, {});
    part.local = b->GetLocalPoint(b2Vec2(float(p.x * s), float(p.y * s)));
    part.angle = angle_z(orientation.value_or(slot, {})) - b->GetAngle();
    const Shape sh = Shape(shape[slot].index);
    const Vec3 sz = size.value_or(slot, {});
    const double r = radius.value_or(slot, 0), len = length.value_or(slot, 0);
    part.inscribed = sh == Shape::Box ? 0.5 * std::min(sz.x, sz.y) : r;
    b2FixtureDef fd;
    fd.density = 0;  // masses are set below, from the part's mass or density
    fd.friction = float(part.friction);
    fd.restitution = float(part.restitution);
    fd.restitutionThreshold = float(m.bounce * s);
    fd.userData.pointer = i;
    const b2Rot rot{float(part.angle)};
    // Box2D gives every polygon a skin of b2_polygonRadius (1 cm in its units,
    // 1 mm of the kit's at scale 10) around its core, and rests contacts on
    // the skin: a box set to the part's size would stand 1 mm proud on every
    // side, and the kit's millimetre gaps (the doorbell's switch, its
    // contact finger) would close early. The core is shrunk by the skin, so
    // that the skin's outside is the part's surface (corners rounded by it).
    auto rounded_box = [&](double hx, double hy) {
      b2PolygonShape box;
      const double skin = std::min<double>(b2_polygonRadius, 0.5 * std::min(hx, hy));
      box.SetAsBox(float(hx - skin), float(hy - skin), part.local, float(part.angle));
      box.m_radius = float(skin);
      return box;
    };
    auto circle = [&](double along_x) {
      b2CircleShape c;
      c.m_radius = float(r * s);
      c.m_p = part.local + b2Mul(rot, b2Vec2(float(along_x * s), 0));
      fd.shape = &c;
      b->CreateFixture(&fd);
    };
    switch (sh) {
      case Shape::Box: {
        b2PolygonShape box = rounded_box(sz.x / 2 * s, sz.y / 2 * s);
        fd.shape = &box;
        b->CreateFixture(&fd);
        break;
      }
      case Shape::Sphere:
      case Shape::Cylinder:
        circle(0);
        break;
      case Shape::Capsule: {
        if (len > 0) {
          b2PolygonShape box = rounded_box(len / 2 * s, r * s);
          fd.shape = &box;
          b->CreateFixture(&fd);
        }
        circle(-len / 2);
        circle(len / 2);
        break;
      }
    }
    if (!body.dynamic) continue;
    double pm = mass.value_or(slot, 0);
    if (density.has(slot)) {
      pm = density[slot] * rigid::shape_volume(sh, sz, r, len);
      mass_out.set(slot, pm);
    }
    Acc& a = acc[part.body];
    const double d2 = double(b2Dot(part.local, part.local)) / (s * s);
    a.m += pm;
    a.I += inertia_z(sh, pm, sz, r, len) + pm * d2;
    a.mc += float(pm) * part.local;
    {
      // Momentum about the first part's centre (the body's velocity below).
      const Vec3 d = position.value_or(slot, {}) - a.x0, v = velocity.value_or(slot, {});
      const double w = angular.value_or(slot, {}).z;
      a.pm += pm;
      a.p += pm * v;
      a.mr += pm * d;
      a.L += inertia_z(sh, pm, sz, r, len) * w + pm * (d.x * v.y - d.y * v.x);
      a.Ir += inertia_z(sh, pm, sz, r, len) + pm * (d.x * d.x + d.y * d.y);
      const Vec3 rigid_v = a.v + Vec3{-a.w.z * d.y, a.w.z * d.x, 0};
      // Within Box2D's single precision of the velocities it wrote: the
      // first part's motion is then the assembly's, as it always was.
      const double tol = 1e-6 * (1 + std::abs(a.v.x) + std::abs(a.v.y) +
                                 std::abs(a.w.z) * (1 + std::abs(d.x) + std::abs(d.y)));
      if (std::abs(w - a.w.z) > tol || std::abs(v.x - rigid_v.x) > tol ||
          std::abs(v.y - rigid_v.y) > tol)
        a.rigid = false;
    }
    body.linear_damping = std::max(body.linear_damping, ldamp.value_or(slot, 0));
    body.angular_damping = std::max(body.angular_damping, adamp.value_or(slot, 0));
  }
  for (std::uint32_t bi = 0; bi < m.bodies.size(); ++bi) {
    if (!m.bodies[bi].dynamic) continue;
    const Acc& a = acc[bi];
    if (!(a.m > 0))
      throw InputError(ErrorLocation{"", 0, store_.describe(a.first)},
                       "rigid_body.box2d: '" + store_.describe(a.first) + "' has no mass");
    // The same bounds as ODE's engine (rigid_body_bounds.cpp), for the same
    // reason, and sharper here: Box2D inverts mass and inertia in single
    // precision. A body outside them is refused (frozen, an out_of_bounds
    // event naming it) and held static until the next step drops it.
    std::string why;
    if (!(a.m >= rigid::limits::min_mass && a.m <= rigid::limits::max_mass))
      why = "has a mass of " + num(a.m) + " kg, outside the " + num(rigid::limits::min_mass) +
            " .. " + num(rigid::limits::max_mass) + " kg a moving body may have";
    else if (!(a.I >= rigid::limits::min_inertia))
      why = "has a moment of inertia about z of " + num(a.I) + " kg m^2, below the " +
            num(rigid::limits::min_inertia) +
            " kg m^2 a moving body needs (a part too light or too thin)";
    if (!why.empty()) {
      access.refuse(a.first.index, "", why + ": it was left out of the rigid body",
                    {{"mass", a.m}});
      m.bodies[bi].dynamic = false;
      m.bodies[bi].b->SetType(b2_staticBody);
      continue;
    }
    b2MassData md;
    md.mass = float(a.m);
    md.center = (1.0f / float(a.m)) * a.mc;
    md.I = float(a.I * s * s);
    b2Body* b = m.bodies[bi].b;
    b->SetMassData(&md);
    if (a.rigid) {
      // Velocity of the centre of mass from the first part's (at the origin):
      // every part already moves with it.
      const b2Vec2 rc = b->GetWorldCenter() - b->GetPosition();
      const double w = a.w.z;
      b->SetLinearVelocity(b2Vec2(float(a.v.x * s - w * rc.y), float(a.v.y * s + w * rc.x)));
      b->SetAngularVelocity(float(w));
    } else {
      // Parts glued while moving apart (adv15 F13): the assembly keeps their
      // momentum and their angular momentum about its centre of mass.
      const Vec3 c = a.mr / a.pm, v = a.p / a.pm;
      const double L = a.L - a.pm * (c.x * v.y - c.y * v.x);
      const double I = a.Ir - a.pm * (c.x * c.x + c.y * c.y);
      b->SetLinearVelocity(b2Vec2(float(v.x * s), float(v.y * s)));
      b->SetAngularVelocity(float(L / I));
    }
  }

  // Hinges: Box2D's revolute joints about z.
  for (std::uint32_t slot : joint.members()) {
    if (JointType(joint[slot].index) != JointType::Hinge) continue;
    const ObjectId jid = store_.id_at(slot);
    const ObjectId bid = body_b.value_or(slot, {});
    if (refused_part(body_a.value_or(slot, {})) || refused_part(bid)) continue;  // holds nothing
    const std::int32_t a = ours(body_a.value_or(slot, {})), b = ours(bid);
    if (a < 0 && b >= 0) refuse_across(slot, "hinge");
    if (a < 0) continue;  // lives with body_a's engine
    if (!bid.is_null() && b < 0)
      throw InputError(
          ErrorLocation{"", 0, store_.describe(jid)},
          "rigid_body.box2d: hinge '" + store_.describe(jid) + "' joins '" +
              store_.describe(m.parts[std::size_t(a)].id) + "' to '" + store_.describe(bid) +
              "', which another engine simulates (a joint lives in body_a's engine, and "
              "both its bodies must be there)");
    const Vec3 ax = axis.value_or(slot, {0, 0, 1});
    const double an = std::sqrt(dot(ax, ax));
    if (std::abs(ax.x) > kResidueTilt * an || std::abs(ax.y) > kResidueTilt * an)
      refuse(jid, "is a hinge whose axis {" + num(ax.x) + ", " + num(ax.y) + ", " + num(ax.z) +
                      "} is not along z");
    const double sign = ax.z > 0 ? 1 : -1;
    b2Body* A = m.bodies[m.parts[std::size_t(a)].body].b;
    b2Body* B = b < 0 ? m.ground : m.bodies[m.parts[std::size_t(b)].body].b;
    if (A == B) continue;  // glued together: nothing turns
    // The points each part is held at, as defined (hinge_anchors.hpp), not
    // the present anchor: a swap or rebuild does not bake a stretch in.
    const std::uint32_t sa = m.parts[std::size_t(a)].id.index;
    const std::uint32_t sb = b < 0 ? 0 : m.parts[std::size_t(b)].id.index;
    const Vec3 given = anchor.value_or(slot, {}), given_a = anchor_a.value_or(slot, {}),
               given_b = anchor_b.value_or(slot, {});
    const rigid::HingeAnchors held = rigid::hinge_anchors(
        anchor.has(slot) ? &given : nullptr, position.value_or(sa, {}),
        anchor_a.has(slot) ? &given_a : nullptr, anchor_b.has(slot) ? &given_b : nullptr, true,
        position.value_or(sa, {}), orientation.value_or(sa, {}), b >= 0,
        b < 0 ? Vec3{} : position.value_or(sb, {}), b < 0 ? Quat{} : orientation.value_or(sb, {}));
    const Vec3 an_at = held.on_a;
    if (std::abs(an_at.z) > kResidueZ || std::abs(held.on_b.z) > kResidueZ)
      refuse(jid, "has its anchor off the plane (z = " + num(an_at.z) + ")");
    b2RevoluteJointDef jd;
    // Box2D's angle is that of its body B relative to its body A, less the
    // reference: made alloy's angle of part a relative to part b about +z,
    // zero when their orientations are equal (as ODE's engine defines it), by
    // taking off where each part sits turned on its body. The angle then
    // depends on the properties alone, so limits mean the same angles after a
    // rebuild, a swap from ODE, or a restore (a reference taken from the pose
    // at the first build would shift them by wherever the swap found the hinge).
    jd.Initialize(B, A, b2Vec2(float(an_at.x * s), float(an_at.y * s)));
    jd.localAnchorA = B->GetLocalPoint(b2Vec2(float(held.on_b.x * s), float(held.on_b.y * s)));
    if (held.defined) {
      anchor_a_out.set(slot, held.local_a);
      anchor_b_out.set(slot, held.local_b);
    }
    const double part_b_angle = b < 0 ? 0.0 : m.parts[std::size_t(b)].angle;
    jd.referenceAngle = float(part_b_angle - m.parts[std::size_t(a)].angle);
    jd.collideConnected = false;
    if (jfric.has(slot) && jfric[slot] > 0) {
      // A motor at speed 0 whose torque is capped: Coulomb friction of the pivot.
      jd.enableMotor = true;
      jd.motorSpeed = 0;
      jd.maxMotorTorque = float(jfric[slot] * s * s);
    }
    if (lo.has(slot) || hi.has(slot)) {
      double l = lo.value_or(slot, -1e9), h = hi.value_or(slot, 1e9);
      if (sign < 0) std::swap(l, h), l = -l, h = -h;
      jd.enableLimit = true;
      jd.lowerAngle = float(l);
      jd.upperAngle = float(h);
    }
    m.hinges.push_back({jid, static_cast<b2RevoluteJoint*>(m.world->CreateJoint(&jd))});
  }

  // Parts buried in a heap wait outside the world (Impl::settle_crowds).
  m.settle_crowds();

  // What we wrote is what the properties hold now.
  for (Impl::Part& part : m.parts) {
    const std::uint32_t slot = part.id.index;
    part.pos = position.value_or(slot, {});
    part.rot = orientation.value_or(slot, {});
    part.vel = velocity.value_or(slot, {});
    part.ang = angular.value_or(slot, {});
  }
  impulses_.clear();
  dirty_ = false;
  note_versions(access);
  ++state_version_;
}

// --- loads ----------------------------------------------------------------------------

void Box2DEngine::queue(ObjectId part, Vec3 value, Vec3 point, Load kind) {
  store_.check_alive(part);
  load_sources_.note(loads_.size(), world_.running_stage());
  loads_.push_back({part.index, part.generation, value, point, kind});
}
void Box2DEngine::add_force(ObjectId part, Vec3 force) {
  queue(part, force, {}, Load::Force);
}
void Box2DEngine::add_force(ObjectId part, Vec3 force, Vec3 point) {
  queue(part, force, point, Load::ForceAtPoint);
}
void Box2DEngine::add_force(std::uint32_t slot, Vec3 force) {
  load_sources_.note(loads_.size(), world_.running_stage());
  loads_.push_back({slot, 0, force, {}, Load::Force});
}
void Box2DEngine::add_torque(ObjectId part, Vec3 torque) {
  queue(part, torque, {}, Load::Torque);
}
void Box2DEngine::add_load(ObjectId part, Vec3 force, Vec3 torque, Vec3 force_rate,
                           Vec3 torque_rate) {
  store_.check_alive(part);
  rated_sources_.note(rated_.size(), world_.running_stage());
  rated_.push_back({part.index, part.generation, force, torque, force_rate, torque_rate});
}
bool Box2DEngine::add_uniform_gravity(Vec3 g, std::span<const std::uint32_t> parts) {
  // Along z Box2D gives nothing: the per-part forces report it (load_dropped).
  const double in_plane = std::hypot(g.x, g.y);
  if (!std::isfinite(in_plane) || !(std::abs(g.z) <= 1e-12 || std::abs(g.z) <= 1e-6 * in_plane))
    return false;
  if (dirty_ || !impl_->world) return false;  // the parts are not known yet
  // One field taken a window: a second offer (another stage's gravity) comes
  // as forces, and does not replace the first's parts.
  if (uniform_) return false;
  uniform_parts_.assign(parts.begin(), parts.end());
  if (!uniform_covers_all()) return false;
  uniform_ = true;
  uniform_g_ = g;
  uniform_at_ = loads_.size();
  uniform_source_ = world_.running_stage();
  return true;
}

bool Box2DEngine::uniform_covers_all() const {
  const Impl& m = *impl_;
  std::vector<char> covered(m.parts.size(), 0);
  for (const std::uint32_t slot : uniform_parts_)
    if (slot < m.part_of_slot.size() && m.part_of_slot[slot] >= 0)
      covered[std::size_t(m.part_of_slot[slot])] = 1;
  for (std::size_t i = 0; i < m.parts.size(); ++i)
    if (!covered[i] && m.bodies[m.parts[i].body].dynamic) return false;
  return true;
}

std::span<rigid::RigidBodyEngine::LoadCommand> Box2DEngine::open_loads(std::size_t n) {
  if (open_ == ~std::size_t(0)) {
    open_ = loads_.size();
    load_sources_.note(open_, world_.running_stage());
  }
  loads_.resize(open_ + n);
  return std::span<LoadCommand>(loads_).subspan(open_, n);
}
void Box2DEngine::close_loads(std::size_t used) {
  if (open_ == ~std::size_t(0)) return;
  loads_.resize(open_ + std::min(used, loads_.size() - open_));
  open_ = ~std::size_t(0);
}

// --- the screen of loads (shared with ODE: load_screen.hpp) ----------------------------

void Box2DEngine::screen_loads(ResolverAccess& access, double dt) {
  Impl& m = *impl_;
  if (loads_.empty() && rated_.empty()) return;
  const double s = m.s;
  // What Box2D applies: forces in the plane, torques about z. Each load's
  // share of its body's change of velocity, in SI (Box2D's mass is in kg, its
  // inertia in kg (s m)^2, about the body's origin).
  auto inv_mass = [&](std::uint32_t bi) {
    const double mass = m.bodies[bi].b->GetMass();
    return mass > 0 ? 1 / mass : 0.0;
  };
  auto inv_inertia = [&](std::uint32_t bi) {
    const b2Body* b = m.bodies[bi].b;
    const double lc = double(b2Dot(b->GetLocalCenter(), b->GetLocalCenter()));
    const double I = (double(b->GetInertia()) - b->GetMass() * lc) / (s * s);
    return 1 / std::max(I, rigid::limits::min_inertia);
  };
  auto body_index = [&](std::uint32_t slot, std::uint32_t gen) -> std::int64_t {
    if (slot >= m.part_of_slot.size() || m.part_of_slot[slot] < 0) return -1;
    if (gen != 0 && store_.id_at(slot).generation != gen) return -1;
    const std::uint32_t b = m.parts[std::size_t(m.part_of_slot[slot])].body;
    return m.bodies[b].dynamic ? std::int64_t(b) : -1;
  };
  auto planar = [](Vec3 v) { return std::hypot(v.x, v.y); };
  // Out of the plane, dropped: reported once per stage and kind when it is
  // more than round-off of the load in the plane (1e-6 of it, and 1e-12 N or
  // N m): a mod written for 3D whose push Box2D cannot give.
  auto dropped = [&](double off, double in, std::size_t i, const char* kind, std::uint32_t slot) {
    if (!(off > 1e-12 && off > 1e-6 * in) && !std::isnan(off)) return;
    const bool rated = i >= loads_.size();
    const std::string& stage =
        rated ? rated_sources_.name_of(i - loads_.size()) : load_sources_.name_of(i);
    const std::pair<std::string, std::string> key{stage, kind};
    if (std::find(dropped_reported_.begin(), dropped_reported_.end(), key) !=
        dropped_reported_.end())
      return;
    dropped_reported_.push_back(key);
    std::string source =
        stage.empty() ? std::string("a load from outside any stage") : "stage '" + stage + "'";
    if (const PluginDef* d = world_.plugin_def(stage); d && !d->info.owner.empty())
      source = "mod '" + d->info.owner + "' (stage '" + stage + "')";
    const ObjectId id = store_.id_at(slot);
    const std::string what =
        rated ? rigid::LoadScreen::describe_rated(rated_[i - loads_.size()].force,
                                                  rated_[i - loads_.size()].torque)
              : rigid::LoadScreen::describe(loads_[i]);
    access.emit(Event{
        .type = "load_dropped",
        .a = id,
        .values = {{"dropped", off}},
        .text = source + " queued " + what + " on '" + store_.describe(id) + "': its " + kind +
                " was dropped (Box2D simulates the z = 0 plane only; further such loads from "
                "this stage are dropped without a word)"});
  };
  screen_.begin(m.bodies.size());
  for (std::size_t i = 0; i < loads_.size(); ++i) {
    const LoadCommand& c = loads_[i];
    const std::int64_t b = body_index(c.slot, c.generation);
    if (b < 0) continue;
    const auto bi = std::uint32_t(b);
    const double f = planar(c.value);
    switch (c.kind) {
      case Load::Force:
        screen_.add(bi, f * dt * inv_mass(bi), 0, i);
        dropped(std::abs(c.value.z), f, i, "force along z", c.slot);
        break;
      case Load::ForceAtPoint: {
        const b2Vec2 wc = m.bodies[bi].b->GetWorldCenter();
        const Vec3 r = c.point - Vec3{wc.x / s, wc.y / s, 0};
        const double t = rigid::LoadScreen::point_within_extent(c.point)
                             ? std::abs(r.x * c.value.y - r.y * c.value.x)
                             : HUGE_VAL;
        screen_.add(bi, f * dt * inv_mass(bi), t * dt * inv_inertia(bi), i);
        // Torque about x and y: a force along z anywhere, or one in the plane
        // at a point off it.
        dropped(std::max(std::abs(c.value.z), planar(cross(r, c.value))), f, i,
                "force along z or torque about x and y", c.slot);
        break;
      }
      case Load::Torque:
        screen_.add(bi, 0, std::abs(c.value.z) * dt * inv_inertia(bi), i);
        dropped(planar(c.value), std::abs(c.value.z), i, "torque about x and y", c.slot);
        break;
    }
  }
  for (std::size_t j = 0; j < rated_.size(); ++j) {
    const RatedLoad& r = rated_[j];
    const std::int64_t b = body_index(r.slot, r.generation);
    if (b < 0) continue;
    const auto bi = std::uint32_t(b);
    const double f = planar(r.force) + planar(r.force_rate) * dt;
    const double t = std::abs(r.torque.z) + std::abs(r.torque_rate.z) * dt;
    screen_.add(bi, f * dt * inv_mass(bi), t * dt * inv_inertia(bi), loads_.size() + j);
    const double off = std::max({std::abs(r.force.z), std::abs(r.force_rate.z) * dt,
                                 planar(r.torque), planar(r.torque_rate) * dt});
    dropped(off, std::max(f, t), loads_.size() + j, "force along z or torque about x and y",
            r.slot);
  }
  for (std::uint32_t bi = 0; bi < m.bodies.size(); ++bi) {
    if (!screen_.breaks(bi)) continue;
    const std::size_t i = screen_.culprit(bi);
    const bool rated = i >= loads_.size();
    const std::string& source =
        rated ? rated_sources_.name_of(i - loads_.size()) : load_sources_.name_of(i);
    const std::string what =
        rated ? rigid::LoadScreen::describe_rated(rated_[i - loads_.size()].force,
                                                  rated_[i - loads_.size()].torque)
              : rigid::LoadScreen::describe(loads_[i]);
    const auto values =
        rigid::LoadScreen::components(rated ? rated_[i - loads_.size()].force : loads_[i].value);
    const std::string text = screen_.refusal(bi, what, dt);
    // Refused as ODE refuses it: every part frozen with the event, the body
    // held still and static until the next step's rebuild drops it; its
    // loads are not applied (body_of skips a body that is not dynamic).
    for (const Impl::Part& part : m.parts)
      if (part.body == bi) access.refuse(part.id.index, source, text, values);
    Impl::Body& body = m.bodies[bi];
    body.b->SetLinearVelocity(b2Vec2(0, 0));
    body.b->SetAngularVelocity(0);
    body.b->SetType(b2_staticBody);
    body.dynamic = false;
    dirty_ = true;
  }
}

void Box2DEngine::report_waiting(ResolverAccess& access) {
  // One event when parts begin to wait (not one a step while a heap
  // empties), naming one of them; again after every waiting part came back.
  Impl& m = *impl_;
  const bool report = m.went_dormant > 0 && !m.waiting_reported;
  const std::size_t went = m.went_dormant;
  m.went_dormant = 0;
  m.waiting_reported = !m.dormant.empty() && (m.waiting_reported || report);
  if (!report) return;
  ObjectId id;
  for (const Impl::Part& part : m.parts)
    if (part.body == m.dormant_example) {
      id = part.id;
      break;
    }
  access.emit(
      Event{.type = "crowded",
            .a = id,
            .values = {{"went", double(went)},
                       {"waiting", double(m.dormant.size())},
                       {"limit", double(Impl::kCrowd)}},
            .text = "rigid_body.box2d: " + std::to_string(went) +
                    " bodies were taken out of the simulation, each sunk deep into more than " +
                    std::to_string(Impl::kCrowd) + " moving bodies ('" + store_.describe(id) +
                    "' among them): they wait, held still, until the parts around them have moved "
                    "apart (parts placed through each other in a heap?; docs/security.md)"});
}

void Box2DEngine::report_left_out(ResolverAccess& access) {
  // One event when pairs begin to be left out (not one a step while a heap
  // lasts), naming the part with the most pairs left out.
  Impl& m = *impl_;
  const bool limited = m.left_out > 0;
  if (limited && !limited_before_) {
    std::size_t worst = 0;
    for (std::size_t k = 0; k < m.left_out_of.size(); ++k)
      if (m.left_out_of[k] > m.left_out_of[worst]) worst = k;
    const ObjectId id = worst < m.parts.size() ? m.parts[worst].id : ObjectId{};
    access.emit(Event{
        .type = "contact_limit",
        .a = id,
        .values = {{"per_part", double(rigid::limits::contact_pairs_per_part)},
                   {"left_out", double(m.left_out)},
                   {"of_part", double(m.left_out_of[worst])}},
        .text = "rigid_body.box2d: " + std::to_string(m.left_out) +
                " pairs of overlapping parts were left out, each of whose bodies touched " +
                std::to_string(rigid::limits::contact_pairs_per_part) +
                " moving bodies already (the limit); they pass through each other. '" +
                store_.describe(id) + "' is in " + std::to_string(m.left_out_of[worst]) +
                " of them: parts placed through each other in a heap? (reported when it begins; "
                "docs/security.md)"});
  }
  limited_before_ = limited;
  if (limited) std::fill(m.left_out_of.begin(), m.left_out_of.end(), 0u);
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------
//
// The bytes: a version and whether the last advance left contact pairs out.
// Without it the first advance after a restore, which asks Box2D's filter
// again for every overlapping pair of the rebuilt world, reported a heap's
// `contact_limit` a second time.

namespace {
constexpr std::uint32_t kStateVersion = 1;
}

bool Box2DEngine::save_state(StateWriter& out) const {
  out.put(kStateVersion);
  out.put(std::uint8_t(limited_before_));
  return true;
}

void Box2DEngine::restore_state(StateReader& in) {
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kStateVersion));
  const auto limited = in.get<std::uint8_t>();
  if (limited > 1)
    throw InputError("the saved state of stage '" + in.stage() +
                     "' is damaged: a contact-limit flag of " + std::to_string(limited));
  limited_before_ = limited != 0;
}

// --- the step -------------------------------------------------------------------------

void Box2DEngine::advance(ResolverAccess& access, double dt) {
  Impl& m = *impl_;
  const double s = m.s;
  if (dirty_ || !m.world || edited_since_write(access)) build(access);

  auto position = access.writer<Vec3>("position");
  auto orientation = access.writer<Quat>("orientation");
  auto velocity = access.writer<Vec3>("velocity");
  auto angular = access.writer<Vec3>("angular_velocity");

  const auto pos_in = access.column<Vec3>("position");
  const auto rot_in = access.column<Quat>("orientation");
  const auto vel_in = access.column<Vec3>("velocity");
  const auto ang_in = access.column<Vec3>("angular_velocity");
  // Edits from outside between steps (the viewer, a timeline, a scene's
  // script): a part whose pose or velocity is not what we wrote moves its body there.
  // Only looked for when one of the four columns was written since our write
  // (every write bumps its column's version): a world where only this engine
  // moves things skips the comparison of every part.
  if (motion_[0] == kNoProperty) {
    std::size_t i = 0;
    for (const char* n : {"position", "orientation", "velocity", "angular_velocity"})
      motion_[i++] = access.property(n);
  }
  auto motion_versions = [&] {
    std::array<std::uint64_t, 4> v{};
    for (std::size_t i = 0; i < 4; ++i) v[i] = access.store().column(motion_[i]).version();
    return v;
  };
  const bool maybe_edited = motion_versions() != m.written_versions;
  for (Impl::Part& part : m.parts) {
    if (!maybe_edited) break;
    Impl::Body& body = m.bodies[part.body];
    if (!body.dynamic) continue;
    const std::uint32_t slot = part.id.index;
    const Vec3 p = pos_in.value_or(slot, {});
    const Quat q = rot_in.value_or(slot, {});
    const Vec3 v = vel_in.value_or(slot, {});
    const Vec3 w = ang_in.value_or(slot, {});
    if (p == part.pos && q == part.rot && v == part.vel && w == part.ang) continue;
    // An edit that takes the part out of the plane is refused as the scene
    // would have been at the build (the part freezes, with an out_of_bounds
    // event naming it, and the next step rebuilds without it), not projected
    // back into the plane unseen.
    if (const std::string why = off_plane(p, q, v, w, true); !why.empty()) {
      access.refuse(slot, "", why + " (Box2D simulates the z = 0 plane only)");
      dirty_ = true;
      continue;
    }
    b2Body* b = body.b;
    const double angle = angle_z(q) - part.angle;
    const b2Rot r{float(angle)};
    const b2Vec2 origin = b2Vec2(float(p.x * s), float(p.y * s)) - b2Mul(r, part.local);
    b->SetTransform(origin, float(angle));
    const b2Vec2 rc = b->GetWorldCenter() - b2Vec2(float(p.x * s), float(p.y * s));
    b->SetLinearVelocity(b2Vec2(float(v.x * s - w.z * rc.y), float(v.y * s + w.z * rc.x)));
    b->SetAngularVelocity(float(w.z));
    b->SetAwake(true);
    part.pos = p;  // where a sweep starts from
    // Carried into a heap (or a waiting body carried out of one: the next
    // wake_uncrowded puts it back).
    if (b->IsEnabled() && m.crowded_body(part.body)) m.make_dormant(part.body);
  }

  // Parts that pass through each other under the contact limit may have
  // buried some in a heap since; waiting parts whose spot cleared come back.
  if (limited_before_) m.settle_crowds();
  if (!m.dormant.empty()) m.wake_uncrowded();

  // Uniform gravity: each part's weight applied where the queue had it
  // (uniform_at_), as the force rigid_body_from_gravity would have queued,
  // so the bits are those of the queued forces; unless this advance's bodies
  // are not all in the field (a rebuild above) or g is beyond what the screen
  // lets a step give: then queued as those forces, and screened.
  bool weigh = false;
  const auto mass = access.column<double>("mass");
  if (std::exchange(uniform_, false)) {
    const double gn = std::hypot(uniform_g_.x, uniform_g_.y);
    if (gn * dt <= rigid::limits::speed && uniform_covers_all() && uniform_at_ <= loads_.size()) {
      weigh = true;
    } else {
      load_sources_.note(loads_.size(), uniform_source_);
      for (const std::uint32_t slot : uniform_parts_)
        if (mass.has(slot)) loads_.push_back({slot, 0, mass[slot] * uniform_g_, {}, Load::Force});
    }
  }
  screen_loads(access, dt);
  m.left_out = 0;
  m.want_impulses = *impulse_demand_ > 0;
  m.step_impulses.clear();
  m.pre_speeds.clear();
  // Substeps: the configured number, or as many as keep Box2D's step within
  // max_substep, or as many more as keep every body's move and turn within
  // 90 % of what Box2D allows a step (it clamps past that, silently). A body
  // too fast even for kMaxAutoSubsteps is refused.
  int n = substeps_for(config_, dt);
  {
    const double max_move = 0.9 * double(b2_maxTranslation),
                 max_turn = 0.9 * double(b2_maxRotation);
    for (std::size_t bi = 0; bi < m.bodies.size(); ++bi) {
      Impl::Body& body = m.bodies[bi];
      if (!body.dynamic) continue;
      {  // the usual case, without the square root: well within n substeps' reach
        const double v2 = double(body.b->GetLinearVelocity().LengthSquared()) * dt * dt,
                     w = double(body.b->GetAngularVelocity()) * dt, reach = 0.99 * n;
        if (v2 < reach * reach * max_move * max_move && w * w < reach * reach * max_turn * max_turn)
          continue;
      }
      const double v = double(body.b->GetLinearVelocity().Length()) * dt;
      const double w = std::abs(double(body.b->GetAngularVelocity())) * dt;
      const double need = std::ceil(std::max(v / max_move, w / max_turn));
      if (need <= n) continue;
      if (need <= kMaxAutoSubsteps) {
        n = int(need);
        continue;
      }
      for (const Impl::Part& part : m.parts)
        if (part.body == bi) {
          access.refuse(part.id.index, "",
                        "moves at " + num(v / dt / s) + " m/s and turns at " + num(w / dt) +
                            " rad/s, faster than Box2D can follow in " +
                            std::to_string(kMaxAutoSubsteps) + " substeps of this step",
                        {{"speed", v / dt / s}, {"angular_speed", w / dt}});
          break;
        }
      body.dynamic = false;
      body.b->SetType(b2_staticBody);
      dirty_ = true;
    }
  }
  const double h = dt / n;
  auto part_for = [&](std::uint32_t slot, std::uint32_t gen) -> const Impl::Part* {
    if (slot >= m.part_of_slot.size() || m.part_of_slot[slot] < 0) return nullptr;
    if (gen != 0 && store_.id_at(slot).generation != gen) return nullptr;
    const Impl::Part& part = m.parts[std::size_t(m.part_of_slot[slot])];
    return m.bodies[part.body].dynamic ? &part : nullptr;
  };
  auto body_of = [&](std::uint32_t slot, std::uint32_t gen) -> Impl::Body* {
    const Impl::Part* part = part_for(slot, gen);
    return part ? &m.bodies[part->body] : nullptr;
  };
  // A force on a part acts at the part's centre, as on ODE's engine: on a
  // body of several glued parts (the motor's rotor: a hub and eight magnet
  // spokes) that is off the body's centre of mass, and the force turns the
  // body. Box2D's ApplyForceToCenter would drop that torque (it did until
  // session 16: the magnets' pull on the spokes turned ODE's rotor and not
  // Box2D's, which ran 44 % slow). A part that is its body's centre of mass
  // (a body of one part) keeps ApplyForceToCenter, bit for bit.
  auto push = [&](const Impl::Part& part, b2Body* b, b2Vec2 f) {
    const bool awake = !config_.sleep;  // as `wake` below
    if (part.local == b->GetLocalCenter())
      b->ApplyForceToCenter(f, awake);
    else
      b->ApplyForce(f, b->GetWorldPoint(part.local), awake);
  };
  if (config_.sleep) {
    // A sleeper wakes when the load on it changes (a magnet switched on), not
    // because the same load (its weight) is queued again; loads on a sleeper
    // are then given with wake = false, and Box2D drops them.
    for (auto& body : m.bodies) body.force = {0, 0}, body.torque = 0;
    auto sum_weights = [&] {
      for (const std::uint32_t slot : uniform_parts_)
        if (Impl::Body* b = body_of(slot, 0); b && mass.has(slot)) {
          const Vec3 w = mass[slot] * uniform_g_;
          b->force += b2Vec2(float(w.x), float(w.y));
        }
    };
    for (std::size_t i = 0; i < loads_.size(); ++i) {
      if (weigh && i == uniform_at_) sum_weights();
      const LoadCommand& c = loads_[i];
      if (Impl::Body* b = body_of(c.slot, c.generation)) {
        if (c.kind == Load::Torque)
          b->torque += float(c.value.z);
        else
          b->force += b2Vec2(float(c.value.x), float(c.value.y));
      }
    }
    if (weigh && uniform_at_ == loads_.size()) sum_weights();
    for (const RatedLoad& r : rated_)
      if (Impl::Body* b = body_of(r.slot, r.generation))
        b->force += b2Vec2(float(r.force.x), float(r.force.y)), b->torque += float(r.torque.z);
    for (auto& body : m.bodies) {
      if (!body.dynamic) continue;
      if (!body.b->IsAwake() &&
          (body.force.x != body.last_force.x || body.force.y != body.last_force.y ||
           body.torque != body.last_torque))
        body.b->SetAwake(true);
      body.last_force = body.force, body.last_torque = body.torque;
    }
  }
  const bool wake = !config_.sleep;
  auto apply_weights = [&] {
    for (const std::uint32_t slot : uniform_parts_) {
      const Impl::Part* part = part_for(slot, 0);
      if (!part || !mass.has(slot)) continue;
      const Vec3 w = mass[slot] * uniform_g_;
      push(*part, m.bodies[part->body].b, b2Vec2(float(w.x * s), float(w.y * s)));
    }
  };
  // The energy books (box2d_energy.cpp): from the first advance of an engine
  // swapped in while a ledger keeps them.
  books_on_ = books_on_ || world_.energy_books_kept();
  if (books_on_)
    books_open(weigh, mass, [&](std::uint32_t slot, std::uint32_t gen, b2Vec2& local) -> b2Body* {
      const Impl::Part* part = part_for(slot, gen);
      return part ? (local = part->local, m.bodies[part->body].b) : nullptr;
    });
  for (int k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < loads_.size(); ++i) {
      if (weigh && i == uniform_at_) apply_weights();
      const LoadCommand& c = loads_[i];
      const Impl::Part* part = part_for(c.slot, c.generation);
      if (!part) continue;
      Impl::Body* b = &m.bodies[part->body];
      switch (c.kind) {
        case Load::Force:
          push(*part, b->b, b2Vec2(float(c.value.x * s), float(c.value.y * s)));
          break;
        case Load::ForceAtPoint:
          b->b->ApplyForce(b2Vec2(float(c.value.x * s), float(c.value.y * s)),
                           b2Vec2(float(c.point.x * s), float(c.point.y * s)), wake);
          break;
        case Load::Torque:
          b->b->ApplyTorque(float(c.value.z * s * s), wake);
          break;
      }
    }
    if (weigh && uniform_at_ == loads_.size()) apply_weights();
    const double tau = k * h;
    for (const RatedLoad& r : rated_) {
      const Impl::Part* part = part_for(r.slot, r.generation);
      if (!part) continue;
      Impl::Body* b = &m.bodies[part->body];
      const Vec3 f = r.force + r.force_rate * tau, t = r.torque + r.torque_rate * tau;
      push(*part, b->b, b2Vec2(float(f.x * s), float(f.y * s)));
      b->b->ApplyTorque(float(t.z * s * s), wake);
    }
    if (books_on_) books_before_drag(tau);
    for (auto& body : m.bodies) {
      if (!body.dynamic) continue;
      if (body.linear_damping > 0)
        body.b->SetLinearVelocity(float(damping_factor(body.linear_damping, h)) *
                                  body.b->GetLinearVelocity());
      if (body.angular_damping > 0)
        body.b->SetAngularVelocity(float(damping_factor(body.angular_damping, h)) *
                                   body.b->GetAngularVelocity());
    }
    if (books_on_) books_before_step(h);
    m.world->Step(float(h), config_.velocity_iterations, config_.position_iterations);
    if (books_on_) books_after_step(h);
  }
  m.sweep(dt);
  if (books_on_) books_close();
  loads_.clear();
  rated_.clear();
  load_sources_.clear();
  rated_sources_.clear();
  open_ = ~std::size_t(0);
  report_left_out(access);
  report_waiting(access);

  // Write the parts back: those of moving bodies, but not of a body that
  // was asleep at the last write-back too (Box2D has not moved it since:
  // what it would write is what the columns hold; the write at which it fell
  // asleep is made, with its velocity zeroed by Box2D).
  for (Impl::Body& body : m.bodies) {
    const bool asleep = body.dynamic && !body.b->IsAwake();
    body.still = asleep && body.written_asleep;
    body.written_asleep = asleep;
  }
  for (Impl::Part& part : m.parts) {
    const Impl::Body& body = m.bodies[part.body];
    if (!body.dynamic || body.still) continue;
    const b2Body* b = body.b;
    const b2Vec2 c = b->GetWorldPoint(part.local);
    const b2Vec2 v = b->GetLinearVelocityFromWorldPoint(c);
    const double angle = double(b->GetAngle()) + part.angle;
    const std::uint32_t slot = part.id.index;
    part.pos = {c.x / s, c.y / s, 0};
    if (!(angle == part.rot_angle)) part.rot = Quat::from_angle_z(angle), part.rot_angle = angle;
    part.vel = {v.x / s, v.y / s, 0};
    part.ang = {0, 0, double(b->GetAngularVelocity())};
    position.set(slot, part.pos);
    orientation.set(slot, part.rot);
    velocity.set(slot, part.vel);
    angular.set(slot, part.ang);
  }
  auto anchor = access.writer<Vec3>("anchor");
  for (const Impl::Hinge& hj : m.hinges) {
    const b2Vec2 a = hj.j->GetAnchorB();
    anchor.set(hj.id.index, {a.x / s, a.y / s, 0});
  }

  // The contacts after the step, for collisions.box2d, sorted by (a, b) and,
  // within a pair, in Box2D's list order (a capsule's fixtures make several
  // contacts per pair). The touching contacts are sorted as small keys, not
  // their points, and a step whose touching contacts are those of the step
  // before, in the same order (a pile at rest), reuses that step's order.
  auto& keys = m.contact_keys;
  auto& order = m.contact_order;
  // Pairs kept at the last advance are looked at again (their gap).
  if (!m.kept.empty()) m.touch_changed = true;
  if (m.touch_changed) {
    keys.clear();
    for (b2Contact* c = m.world->GetContactList(); c; c = c->GetNext()) {
      if (!c->IsTouching() || !c->IsEnabled()) continue;
      const ObjectId a = m.part_of(c->GetFixtureA()).id, b = m.part_of(c->GetFixtureB()).id;
      keys.push_back({std::min(a, b), std::max(a, b), c, std::uint32_t(keys.size())});
    }
    m.kept_contacts(keys);
  }
  if (m.touch_changed &&
      (keys.size() != m.last_keys.size() ||
       !std::equal(keys.begin(), keys.end(), m.last_keys.begin(), [](const auto& x, const auto& y) {
         return x.c == y.c && x.a == y.a && x.b == y.b;
       }))) {
    order.resize(keys.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
      const auto &kx = keys[x], &ky = keys[y];
      return pair_less(kx.a, kx.b, ky.a, ky.b) || (kx.a == ky.a && kx.b == ky.b && kx.seq < ky.seq);
    });
    m.last_keys = keys;
  }
  m.touch_changed = false;
  // The pairs' points are made when the contact set asks (pairs_into, geometry_into),
  // straight into its lists: the set is updated after every advance that
  // changed something, and nothing touches Box2D's world in between.
  if (m.pre_speeds.size() > 1)
    std::sort(m.pre_speeds.begin(), m.pre_speeds.end(),
              [](const auto& x, const auto& y) { return pair_less(x.a, x.b, y.a, y.b); });
  impulses_.clear();
  impulses_computed_ = m.want_impulses;
  if (m.want_impulses) {
    auto& si = m.step_impulses;
    std::stable_sort(si.begin(), si.end(),
                     [](const auto& x, const auto& y) { return pair_less(x.a, x.b, y.a, y.b); });
    for (const PairImpulse& q : si) {
      if (!impulses_.empty() && impulses_.back().a == q.a && impulses_.back().b == q.b) {
        impulses_.back().impulse = impulses_.back().impulse + q.impulse;
        impulses_.back().normal_impulse += q.normal_impulse;
      } else {
        impulses_.push_back(q);
      }
    }
  }
  note_versions(access);
  m.written_versions = motion_versions();
  ++state_version_;
}

std::vector<PredictedTouch> Box2DEngine::touching_ahead(std::span<const ObjectId> parts,
                                                        double seconds,
                                                        const ContactSet& now) const {
  std::vector<PredictedTouch> out;
  if (!impl_ || !impl_->world) return out;
  Impl& m = *impl_;
  // Each asked part's fixtures, with its body's transform `seconds` on and
  // the bounds there (skin included).
  struct Shape {
    ObjectId id;
    b2Fixture* f;
    b2Transform xf;
    bool moves;
    double lo[3], hi[3];
  };
  std::vector<Shape> shapes;
  bool any_moves = false;
  for (const ObjectId id : parts) {
    if (id.index >= m.part_of_slot.size() || m.part_of_slot[id.index] < 0) continue;
    const Impl::Part& part = m.parts[std::size_t(m.part_of_slot[id.index])];
    if (part.id != id) continue;
    b2Body* b = m.bodies[part.body].b;
    if (!b) continue;
    const b2Vec2 v = b->GetLinearVelocity();
    const float w = b->GetAngularVelocity();
    const bool moves = b->GetType() == b2_dynamicBody && (v.x != 0 || v.y != 0 || w != 0);
    any_moves = any_moves || moves;
    const b2Transform xf(b->GetPosition() + float(seconds) * v,
                         b2Rot(b->GetAngle() + float(seconds) * w));
    for (b2Fixture* f = b->GetFixtureList(); f; f = f->GetNext())
      if (&m.part_of(f) == &part) shapes.push_back(Shape{id, f, xf, moves, {}, {}});
  }
  if (!any_moves) return out;  // nothing moves: no pair can come to touch
  for (Shape& e : shapes) {
    b2AABB box;
    e.f->GetShape()->ComputeAABB(&box, e.xf, 0);
    e.lo[0] = box.lowerBound.x, e.lo[1] = box.lowerBound.y, e.lo[2] = 0;
    e.hi[0] = box.upperBound.x, e.hi[1] = box.upperBound.y, e.hi[2] = 0;
  }
  auto joined = [](const b2Body* a, const b2Body* b) {
    for (const b2JointEdge* e = a->GetJointList(); e; e = e->next)
      if (e->other == b && !e->joint->GetCollideConnected()) return true;
    return false;
  };
  for_each_overlap(shapes, [&](std::size_t i, std::size_t j) {
    const Shape &p = shapes[i], &q = shapes[j];
    if (!p.moves && !q.moves) return;  // neither can come to touch
    b2Body *ba = p.f->GetBody(), *bb = q.f->GetBody();
    if (p.id == q.id || ba == bb) return;
    if (!m.b2ContactFilter::ShouldCollide(p.f, q.f) || joined(ba, bb)) return;
    if (now.find(p.id, q.id)) return;  // touching now
    b2DistanceInput in;
    in.proxyA.Set(p.f->GetShape(), 0), in.proxyB.Set(q.f->GetShape(), 0);
    in.transformA = p.xf, in.transformB = q.xf, in.useRadii = true;
    b2SimplexCache cache;
    cache.count = 0;
    b2DistanceOutput d;
    b2Distance(&d, &cache, &in);
    if (d.distance >= 10 * b2_epsilon) return;
    const b2Vec2 mid = 0.5f * (d.pointA + d.pointB);
    const bool order = p.id < q.id;
    out.push_back({order ? p.id : q.id, order ? q.id : p.id, {mid.x / m.s, mid.y / m.s, 0}});
  });
  std::sort(out.begin(), out.end(), [](const PredictedTouch& x, const PredictedTouch& y) {
    return pair_less(x.a, x.b, y.a, y.b);
  });
  // A part of several fixtures may touch another with more than one: once.
  out.erase(std::unique(out.begin(), out.end(),
                        [](const PredictedTouch& x, const PredictedTouch& y) {
                          return x.a == y.a && x.b == y.b;
                        }),
            out.end());
  return out;
}

void Box2DEngine::pairs_into(std::vector<ContactPair>& pairs) const {
  const Impl& m = *impl_;
  for (const std::uint32_t k : m.contact_order) {
    const Impl::ContactKey& key = m.contact_keys[k];
    if (pairs.empty() || pairs.back().a != key.a || pairs.back().b != key.b) {
      ContactPair& p = pairs.emplace_back();
      p.a = key.a, p.b = key.b;
    }
  }
}

void Box2DEngine::geometry_into(std::span<ContactPair> pairs,
                                std::vector<ContactPoint>& points) const {
  // Points are written in the order advance() left (by pair, then Box2D's
  // list order), for the pairs asked (a merge by pair); a pair's approach
  // speed is the largest at its points now or at its beginning (PreSolve's).
  Impl& m = *impl_;
  const double s = m.s;
  const auto& keys = m.contact_keys;
  std::size_t ps = 0, j = 0;
  for (const std::uint32_t k : m.contact_order) {
    if (j == pairs.size()) break;
    const Impl::ContactKey& key = keys[k];
    while (j < pairs.size() && pair_less(pairs[j].a, pairs[j].b, key.a, key.b)) ++j;
    if (j == pairs.size() || pairs[j].a != key.a || pairs[j].b != key.b) continue;
    ContactPair& p = pairs[j];
    b2Contact* c = key.c;
    const bool a_is_A = m.part_of(c->GetFixtureA()).id == key.a;
    b2WorldManifold wm;
    int np = c->GetManifold()->pointCount;
    if (key.kept)
      np = m.kept_manifold(c, wm);
    else
      c->GetWorldManifold(&wm);
    const double speed = m.approach(c, wm, np, a_is_A);
    if (p.count == 0 && p.normal_speed == 0 && p.depth == 0) {  // the pair's first key
      p.first = std::uint32_t(points.size());
      while (ps < m.pre_speeds.size() &&
             pair_less(m.pre_speeds[ps].a, m.pre_speeds[ps].b, key.a, key.b))
        ++ps;
      for (std::size_t q = ps;
           q < m.pre_speeds.size() && m.pre_speeds[q].a == key.a && m.pre_speeds[q].b == key.b; ++q)
        p.normal_speed = std::max(p.normal_speed, m.pre_speeds[q].speed);
    }
    // ContactPoint's normal points from b towards a; Box2D's from A to B.
    const b2Vec2 nn = a_is_A ? -wm.normal : wm.normal;
    for (int i = 0; i < np; ++i) {
      const double depth = std::max(0.0, -double(wm.separations[i]) / s);
      points.push_back(ContactPoint{.position = {wm.points[i].x / s, wm.points[i].y / s, 0},
                                    .normal = {nn.x, nn.y, 0},
                                    .depth = depth});
      ++p.count;
      p.depth = std::max(p.depth, depth);
      p.normal_speed = std::max(p.normal_speed, speed);
    }
  }
}

std::size_t Box2DEngine::body_count() const {
  std::size_t n = 0;
  for (const auto& b : impl_->bodies) n += b.dynamic;
  return n;
}
b2World* Box2DEngine::box2d_world() const {
  return impl_->world.get();
}
std::uint64_t Box2DEngine::sweep_count() const {
  return impl_->sweeps;
}
std::size_t Box2DEngine::joint_count() const {
  return impl_->hinges.size();
}
std::size_t Box2DEngine::awake_count() const {
  std::size_t n = 0;
  for (const auto& b : impl_->bodies) n += b.dynamic && b.b->IsAwake() && b.b->IsEnabled();
  return n;
}
std::size_t Box2DEngine::waiting_count() const {
  return impl_->dormant.size();
}
std::uint64_t Box2DEngine::pair_filter_calls() const {
  return impl_->filter_calls;
}
std::uint64_t Box2DEngine::crowd_tests() const {
  return impl_->crowd_tests;
}
std::size_t Box2DEngine::box2d_contact_count() const {
  return impl_->world ? std::size_t(impl_->world->GetContactCount()) : 0;
}

// --- collisions.box2d ----------------------------------------------------------------

Box2DContacts::Box2DContacts(const Box2DEngine& engine, bool always_impulses) : engine_(&engine) {
  if (always_impulses) always_ = engine.demand_impulses();
  engine.attach_contacts(this);
}

Box2DContacts::~Box2DContacts() {
  if (engine_) engine_->attach_contacts(nullptr);
}

void Box2DContacts::engine_gone() {
  make_pending();
  engine_ = nullptr;
}

void Box2DContacts::update(const WorldView& world) {
  if (!engine_) return;  // its engine is gone (the set is retired): keep the last lists
  if (std::exchange(restored_, false)) {
    clear_changes();  // the saved lists stand, as after the saved run's last update
    return;
  }
  begin_update();
  engine_->pairs_into(current_);
  version_ = engine_->state_version();
  defer_geometry();
  publish(world, engine_->impulses(), engine_->impulses_computed(), world.step());
}

void Box2DContacts::make_geometry(std::span<ContactPair> pairs,
                                  std::vector<ContactPoint>& points) const {
  engine_->geometry_into(pairs, points);
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------
//
// The bytes: a version, the step of the last update, the impulse flags, the
// touching pairs (ContactPair, whole) and their points (ContactPoint).

namespace {
constexpr std::uint32_t kContactsVersion = 1;
// Saved as raw bytes (put_vector): no padding, every byte a field.
static_assert(sizeof(ContactPair) == 2 * sizeof(ObjectId) + 8 + 5 * 8 + sizeof(Vec3));
static_assert(sizeof(ContactPoint) == 2 * sizeof(Vec3) + 8);
}  // namespace

bool Box2DContacts::save_state(StateWriter& out) const {
  out.put(kContactsVersion);
  out.put(step_);
  out.put(std::uint8_t(impulses_known_));
  out.put(impulses_since_);
  const auto pairs = touching();
  out.put_vector(std::vector<ContactPair>(pairs.begin(), pairs.end()));
  const auto pts = points();
  out.put_vector(std::vector<ContactPoint>(pts.begin(), pts.end()));
  return true;
}

void Box2DContacts::restore_state(StateReader& in) {
  auto damaged = [&](const std::string& what) {
    throw InputError("the saved state of stage '" + in.stage() + "' is damaged: " + what);
  };
  if (const auto v = in.get<std::uint32_t>(); v != kContactsVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kContactsVersion));
  const auto step = in.get<std::uint64_t>();
  const auto known = in.get<std::uint8_t>();
  const auto since = in.get<std::uint64_t>();
  auto pairs = in.get_vector<ContactPair>();
  auto pts = in.get_vector<ContactPoint>();
  if (known > 1) damaged("an impulse flag of " + std::to_string(known));
  // The merge needs the pairs sorted and distinct, their points in range.
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const ContactPair& p = pairs[i];
    if (!(p.a < p.b) || (i > 0 && !pair_less(pairs[i - 1].a, pairs[i - 1].b, p.a, p.b)) ||
        p.began_step > step)
      damaged("its touching pairs are out of order or began after step " + std::to_string(step));
    if (std::uint64_t(p.first) + p.count > pts.size()) damaged("a pair's points are out of range");
  }
  restore_lists(std::move(pairs), std::move(pts));
  impulses_known_ = known != 0;
  impulses_since_ = since;
  step_ = step;
  restored_ = true;
}

}  // namespace alloy::box2d
