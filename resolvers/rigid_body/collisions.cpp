#include "resolvers/rigid_body/collisions.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

#include "resolvers/rigid_body/ode_support.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"

namespace alloy::rigid {

namespace {
// Category bits: static parts are only tested against movable ones, so ODE's
// space skips floor-against-wall pairs before any callback.
constexpr unsigned long kStaticBit = 1, kMovableBit = 2;

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

bool by_pair(const ContactPair& x, const ContactPair& y) {
  return pair_less(x.a, x.b, y.a, y.b);
}

// --- narrow phase: cylinders and the contact point of round parts ---------------------

constexpr int kCylinderPoints = 16;  // ODE's cylinder colliders write at most 8

Vec3 geom_axis(dGeomID g) {  // the geom's local z in the world: a cylinder's or capsule's axis
  const dReal* r = dGeomGetRotation(g);
  return {r[2], r[6], r[10]};
}

/// How far the geom reaches from its centre along the unit direction d, m
/// (its support function): where its surface is deepest in a part it touches
/// along d. Negative for a shape that is not round (no reach is needed).
double round_reach(dGeomID g, Vec3 d) {
  switch (dGeomGetClass(g)) {
    case dSphereClass:
      return dGeomSphereGetRadius(g);
    case dCapsuleClass: {
      dReal r, len;
      dGeomCapsuleGetParams(g, &r, &len);
      return r + 0.5 * len * std::abs(dot(d, geom_axis(g)));
    }
    case dCylinderClass: {
      dReal r, len;
      dGeomCylinderGetParams(g, &r, &len);
      const double along = dot(d, geom_axis(g));
      return r * std::sqrt(std::max(0.0, 1 - along * along)) + 0.5 * len * std::abs(along);
    }
    default:
      return -1;
  }
}

/// Two cylinders with parallel axes, each centred within the other's slab
/// (disks side by side in the play area): circle against circle, the normal
/// across the axes. ODE's cylinder pair (libccd) takes the shallowest way out
/// instead, which for two disks overlapping by more than their thickness is
/// along the axis: planar disks would then pass through each other. Returns
/// -1 when the pair is not side by side (ODE's collider decides then). One
/// point, midway through the overlap and the axial span the two share: a
/// line contact's middle, which pushes without turning either across its axis.
int collide_side_by_side(dGeomID g1, dGeomID g2, int max, dContactGeom* out) {
  const Vec3 a = geom_axis(g1);
  if (std::abs(dot(a, geom_axis(g2))) < 1 - 1e-9) return -1;  // 0.003 degrees
  dReal r1, h1, r2, h2;
  dGeomCylinderGetParams(g1, &r1, &h1);
  dGeomCylinderGetParams(g2, &r2, &h2);
  const Vec3 c1 = to_vec3(dGeomGetPosition(g1)), c2 = to_vec3(dGeomGetPosition(g2));
  const Vec3 d = c2 - c1;
  const double axial = dot(d, a);
  // The thinner one's mid-plane inside the thicker one's slab: side by side.
  // (Stacked coins, one on the other's face, are ODE's case.)
  if (std::abs(axial) > 0.5 * std::max(h1, h2)) return -1;
  const Vec3 across = d - a * axial;
  const double dist = length(across);
  const double depth = r1 + r2 - dist;
  if (!(depth > 0) || max < 1) return 0;
  // From g1 to g2 across the axes (any direction across them when concentric).
  const Vec3 u = dist > 1e-12 * (r1 + r2)
                     ? across / dist
                     : unit(cross(a, std::abs(a.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
  // The points: on the line of centres, midway through the overlap, at both
  // ends of the axial span the two share (a line contact; its two ends give
  // no torque across the axis).
  const double lo = std::max(-0.5 * h1, axial - 0.5 * h2),
               hi = std::min(0.5 * h1, axial + 0.5 * h2);
  const Vec3 p = c1 + u * (r1 - 0.5 * depth) + a * (0.5 * (lo + hi));
  dContactGeom& c = out[0];
  c = dContactGeom{};
  c.pos[0] = p.x, c.pos[1] = p.y, c.pos[2] = p.z;
  c.normal[0] = -u.x, c.normal[1] = -u.y, c.normal[2] = -u.z;  // ODE: pushes g1 out of g2
  c.depth = depth;
  c.g1 = g1, c.g2 = g2;
  c.side1 = c.side2 = -1;
  return 1;
}

/// Keeps `max` of the n points, spread out: the deepest, then each time the
/// one farthest from those kept. ODE's cylinder colliders write their points
/// in order round the rim and stop when the buffer is full: a coin lying
/// flat, asked for 4 of its 8, gets 4 on one side and tips over.
int spread_points(dContactGeom* points, int n, int max) {
  if (n <= max) return n;
  int deepest = 0;
  for (int k = 1; k < n; ++k)
    if (points[k].depth > points[deepest].depth) deepest = k;
  std::swap(points[0], points[deepest]);
  for (int kept = 1; kept < max; ++kept) {
    int best = kept;
    double best_d2 = -1;
    for (int k = kept; k < n; ++k) {
      double d2 = 1e300;
      for (int j = 0; j < kept; ++j) {
        const Vec3 d = to_vec3(points[k].pos) - to_vec3(points[j].pos);
        d2 = std::min(d2, dot(d, d));
      }
      if (d2 > best_d2) best_d2 = d2, best = k;
    }
    std::swap(points[kept], points[best]);
  }
  return max;
}

// ODE's hash space numbers its cells with ints, the smallest cells 1/8 m wide
// (levels -3 to 10): a geom whose bounds reach beyond about 2^28 m, or are not
// finite, fails its assertion in collide(). Parts within the rigid body's
// limits reach a few 1e6 m at most; beyond 2^27 m a geom is left out.
constexpr double kIndexable = 134217728.0;

/// Whether the hash space can number the cells of the geom's bounds.
bool indexable(dGeomID g) {
  dReal b[6];
  dGeomGetAABB(g, b);
  for (const dReal v : b)
    if (!(std::abs(v) < kIndexable)) return false;
  return true;
}

/// A space ODE left locked: an error thrown through dSpaceCollide skips the
/// unlock, and a locked space can be neither changed nor destroyed (ODE
/// asserts in both, and in its destructor). It is kept, untouched, for the
/// rest of the process, reachable, so that the leak checker does not report
/// it: one space and its geoms per failed collide.
void keep_locked_space(dSpaceID space) {
  static std::mutex mutex;
  static auto* kept = new std::vector<dSpaceID>();  // never freed: see above
  std::lock_guard lock(mutex);
  kept->push_back(space);
}
}  // namespace

int collide_parts(dxGeom* g1, dxGeom* g2, int max, dContactGeom* out) {
  if (max < 1) return 0;
  const bool cyl1 = dGeomGetClass(g1) == dCylinderClass, cyl2 = dGeomGetClass(g2) == dCylinderClass;
  if (cyl1 && cyl2)
    if (const int n = collide_side_by_side(g1, g2, max, out); n >= 0) return n;
  int n;
  if ((cyl1 || cyl2) && max < kCylinderPoints) {
    // All of a cylinder's points (8 round a face at most), then a spread few.
    thread_local std::array<dContactGeom, kCylinderPoints> all;
    n = spread_points(all.data(),
                      dCollide(g1, g2, kCylinderPoints, all.data(), sizeof(dContactGeom)), max);
    std::copy_n(all.begin(), std::max(n, 0), out);
  } else {
    n = dCollide(g1, g2, max, out, sizeof(dContactGeom));
  }
  // ODE's colliders place a point either on one part's surface or on the
  // other's (sphere on box: on the box). Resting contacts keep an overlap of
  // the surface layer, so a ball's point on the box is a layer nearer its
  // centre than its surface, and friction turns it about that shorter radius:
  // it rolls slower than a ball of its radius (5 cm: 0.12 %). When one
  // part is round (sphere, capsule, cylinder) and the other is not, the point
  // goes onto the round part's surface, along the normal: the normal force's
  // line is unchanged, and the rolling radius is the part's own.
  for (int k = 0; k < n; ++k) {
    dContactGeom& c = out[k];
    const Vec3 normal = to_vec3(c.normal), p = to_vec3(c.pos);
    const double reach1 = round_reach(g1, -normal), reach2 = round_reach(g2, normal);
    if ((reach1 >= 0) == (reach2 >= 0)) continue;  // both round or neither
    Vec3 q;
    if (reach1 >= 0) {  // g1's surface deepest in g2 lies along -normal
      const Vec3 c1 = to_vec3(dGeomGetPosition(g1));
      q = p + normal * (-reach1 - dot(p - c1, normal));
    } else {
      const Vec3 c2 = to_vec3(dGeomGetPosition(g2));
      q = p + normal * (reach2 - dot(p - c2, normal));
    }
    c.pos[0] = q.x, c.pos[1] = q.y, c.pos[2] = q.z;
  }
  return n;
}

struct CollisionSet::Impl {
  struct Geom {
    dGeomID geom = nullptr;
    ObjectId id;
    bool capsule = false;
    bool cylinder = false;
    bool placed = false;
    bool movable = false;
    double inscribed = 0;                ///< radius of the largest sphere inside the shape, m
    double radius = 0, half_length = 0;  ///< a cylinder's, m
    Vec3 pos;
    Quat q;
    /// How far the part reaches from its centre along the unit direction n,
    /// m, where a sweep stops it short of a surface: a cylinder's own reach
    /// (a disk moving in the play area reaches its radius, not half its
    /// thickness); for the other shapes their inscribed radius.
    double reach(Vec3 n) const {
      if (!cylinder) return inscribed;
      const double along = dot(n, rotate(normalized(q), Vec3{0, 0, 1}));
      return radius * std::sqrt(std::max(0.0, 1 - along * along)) + half_length * std::abs(along);
    }
  };

  explicit Impl(int max_contacts) : buffer(std::size_t(max_contacts)) {
    ensure_ode();
    space = dHashSpaceCreate(nullptr);
  }
  ~Impl() {
    clear_geoms();
    if (ray) dGeomDestroy(ray);
    dSpaceDestroy(space);
  }

  void resolve_ids(const WorldView& v) {
    if (have_ids) return;
    position = v.property("position"), orientation = v.property("orientation");
    velocity = v.property("velocity"), angular_velocity = v.property("angular_velocity");
    shape = v.property("shape"), size = v.property("size"), radius = v.property("radius");
    length = v.property("length"), static_ = v.property("static");
    joint = v.property("joint"), body_a = v.property("body_a"), body_b = v.property("body_b");
    for (PropertyId p : {shape, size, radius, length, static_})
      shape_columns.push_back(&v.store().column(p));
    for (PropertyId p : {joint, body_a, body_b}) joint_columns.push_back(&v.store().column(p));
    have_ids = true;
  }

  static bool changed(const std::vector<const ColumnBase*>& cols,
                      std::vector<std::uint64_t>& seen) {
    bool any = seen.size() != cols.size();
    seen.resize(cols.size());
    for (std::size_t i = 0; i < cols.size(); ++i)
      if (cols[i]->version() != seen[i]) seen[i] = cols[i]->version(), any = true;
    return any;
  }

  void clear_geoms() {
    for (std::uint32_t s : geom_slots) dGeomDestroy(geoms[s].geom);
    geom_slots.clear();
    geoms.clear();
  }

  void rebuild_geoms(const WorldView& v) {
    clear_geoms();
    const PropertyStore& store = v.store();
    geoms.resize(store.slot_count());
    const auto pos = v.column<Vec3>(position);
    const auto shp = v.column<EnumValue>(shape);
    const auto sz = v.column<Vec3>(size);
    const auto rad = v.column<double>(radius);
    const auto len = v.column<double>(length);
    const auto stat = v.column<std::uint8_t>(static_);
    for (std::uint32_t s : shp.members()) {
      if (!pos.has(s)) continue;  // not placed in the world yet
      const ObjectId id = store.id_at(s);
      const ErrorLocation where{"", 0, store.describe(id)};
      Geom& g = geoms[s];
      switch (Shape(shp[s].index)) {
        case Shape::Box: {
          const Vec3 e = sz.value_or(s, {});
          if (!(e.x > 0 && e.y > 0 && e.z > 0))
            throw InputError(where, "a box needs a size with every extent > 0");
          g.geom = dCreateBox(space, e.x, e.y, e.z);
          g.inscribed = 0.5 * std::min({e.x, e.y, e.z});
          break;
        }
        case Shape::Sphere:
          if (!(rad.value_or(s, 0) > 0)) throw InputError(where, "a sphere needs a radius > 0");
          g.geom = dCreateSphere(space, rad[s]);
          g.inscribed = rad[s];
          break;
        case Shape::Capsule:
          if (!(rad.value_or(s, 0) > 0) || !(len.value_or(s, 0) >= 0))
            throw InputError(where, "a capsule needs a radius > 0 and a length >= 0");
          g.geom = dCreateCapsule(space, rad[s], len.value_or(s, 0));
          g.capsule = true;
          g.inscribed = rad[s];
          break;
        case Shape::Cylinder:
          // Along the part's z, ODE's cylinder axis: no axis rotation needed.
          if (!(rad.value_or(s, 0) > 0) || !(len.value_or(s, 0) > 0))
            throw InputError(where, "a cylinder needs a radius > 0 and a length > 0");
          g.geom = dCreateCylinder(space, rad[s], len[s]);
          g.cylinder = true;
          g.radius = rad[s], g.half_length = 0.5 * len[s];
          g.inscribed = std::min(rad[s], 0.5 * len[s]);
          break;
      }
      g.id = id;
      const bool is_static = stat.value_or(s, 0);
      g.movable = !is_static;
      dGeomSetCategoryBits(g.geom, is_static ? kStaticBit : kMovableBit);
      dGeomSetCollideBits(g.geom, is_static ? kMovableBit : kStaticBit | kMovableBit);
      dGeomSetData(g.geom, reinterpret_cast<void*>(std::uintptr_t(s)));
      geom_slots.push_back(s);
    }
  }

  void rebuild_joined(const WorldView& v) {
    joined.clear();
    const auto j = v.column<EnumValue>(joint);
    const auto a = v.column<ObjectId>(body_a);
    const auto b = v.column<ObjectId>(body_b);
    for (std::uint32_t s : j.members()) {
      if (!a.has(s) || !b.has(s) || a[s].is_null() || b[s].is_null()) continue;
      joined.push_back(pair_key(a[s].index, b[s].index));
    }
    jointed.assign(geoms.size(), false);
    for (std::uint32_t s : j.members())
      for (const ObjectId o : {a.value_or(s, {}), b.value_or(s, {})})
        if (!o.is_null() && o.index < jointed.size()) jointed[o.index] = true;
    std::sort(joined.begin(), joined.end());
  }

  void place(const WorldView& v) {
    const auto pos = v.column<Vec3>(position);
    const auto rot = v.column<Quat>(orientation);
    for (std::uint32_t s : geom_slots) {
      Geom& g = geoms[s];
      const Vec3 x = pos[s];
      const Quat q = rot.value_or(s, Quat{});
      // Unchanged parts (static ones, resting ones) keep their cached bounds.
      if (g.placed && x == g.pos && q == g.q) continue;
      // Far enough in one step to have crossed a thin part: sweep it after the
      // narrow phase (a quarter of the inscribed radius squared: half of it).
      if (ccd && g.placed && g.movable && !(s < jointed.size() && jointed[s])) {
        const Vec3 d = x - g.pos;
        if (dot(d, d) > 0.25 * g.inscribed * g.inscribed) candidates.push_back({s, g.pos});
      }
      g.placed = true, g.pos = x, g.q = q;
      dGeomSetPosition(g.geom, x.x, x.y, x.z);
      dQuaternion oq;
      to_ode(g.capsule ? normalized(q) * capsule_axis_rotation() : normalized(q), oq);
      dGeomSetQuaternion(g.geom, oq);
      if (!out_of_range.empty()) recheck(s, g);
    }
  }

  // --- ODE errors in the collisions pass ------------------------------------------
  /// Slots whose geom was beyond what the hash space indexes when a collide
  /// failed (sorted): each is disabled (out of every pair and sweep) while it
  /// stays there, and enabled again once back.
  std::vector<std::uint32_t> out_of_range;
  /// Inside dSpaceCollide or dSpaceCollide2: an error thrown now leaves the space locked.
  bool colliding = false;

  void recheck(std::uint32_t s, Geom& g) {
    const auto it = std::lower_bound(out_of_range.begin(), out_of_range.end(), s);
    if (it == out_of_range.end() || *it != s) return;
    if (indexable(g.geom)) {
      dGeomEnable(g.geom);
      out_of_range.erase(it);
      return;
    }
    dGeomDisable(g.geom);
    if (!candidates.empty() && candidates.back().slot == s) candidates.pop_back();
  }

  /// After an ODE error: notes the geoms the hash space cannot index (the
  /// likely cause, named in the report) and drops every geom, with the space
  /// if ODE left it locked. The next update builds them again.
  std::vector<std::uint32_t> abandon_geoms() {
    std::vector<std::uint32_t> culprits;
    for (std::uint32_t s : geom_slots)
      if (!indexable(geoms[s].geom)) culprits.push_back(s);
    for (std::uint32_t s : culprits)
      if (!std::binary_search(out_of_range.begin(), out_of_range.end(), s))
        out_of_range.insert(std::lower_bound(out_of_range.begin(), out_of_range.end(), s), s);
    bool locked = colliding;
    colliding = false;
    if (!locked) {
      try {
        clear_geoms();
      } catch (const OdeError&) {
        locked = true;  // ODE refused to let go of them: give up the space as well
      }
    }
    if (locked) {
      keep_locked_space(space);
      geom_slots.clear();
      geoms.clear();
      space = dHashSpaceCreate(nullptr);
    }
    geoms_dirty = joints_dirty = true;
    return culprits;
  }

  /// A part's motion, read once per touching pair (not once per point).
  struct Motion {
    Vec3 v, w, x;
    bool spins;
    Vec3 at(Vec3 p) const { return spins ? v + cross(w, p - x) : v; }
  };
  Motion motion(std::uint32_t s) const {
    const bool spins = angvel.has(s);
    return {vel.value_or(s, {}), spins ? angvel[s] : Vec3{}, geoms[s].pos, spins};
  }

  static void near_callback(void* data, dGeomID g1, dGeomID g2) {
    auto& m = *static_cast<Impl*>(data);
    auto s1 = std::uint32_t(reinterpret_cast<std::uintptr_t>(dGeomGetData(g1)));
    auto s2 = std::uint32_t(reinterpret_cast<std::uintptr_t>(dGeomGetData(g2)));
    // Live objects have distinct slots, so slot order is ObjectId order. Always
    // collide a before b: the points then do not depend on the space's order.
    if (s1 > s2) std::swap(s1, s2), std::swap(g1, g2);
    if (!m.waiting.empty() && (m.is_waiting(s1) || m.is_waiting(s2))) return;
    if (!m.joined.empty() && std::binary_search(m.joined.begin(), m.joined.end(), pair_key(s1, s2)))
      return;
    if (m.pair_count[s1] >= limits::contact_pairs_per_part &&
        m.pair_count[s2] >= limits::contact_pairs_per_part)
      return m.leave_out(s1, s2);
    const int n = collide_parts(g1, g2, int(m.buffer.size()), m.buffer.data());
    if (n <= 0) return;
    m.pair_count[s1] += m.geoms[s2].movable, m.pair_count[s2] += m.geoms[s1].movable;
    ContactPair& pair = m.pairs->emplace_back();
    pair.a = m.geoms[s1].id;
    pair.b = m.geoms[s2].id;
    pair.first = std::uint32_t(m.points->size());
    pair.count = std::uint32_t(n);
    pair.normal_speed = -1e300;
    const Motion m1 = m.motion(s1), m2 = m.motion(s2);
    for (int k = 0; k < n; ++k) {
      const dContactGeom& c = m.buffer[std::size_t(k)];
      const ContactPoint& p = m.points->emplace_back(to_vec3(c.pos), to_vec3(c.normal), c.depth);
      pair.depth = std::max(pair.depth, p.depth);
      const double closing = dot(m2.at(p.position) - m1.at(p.position), p.normal);
      pair.normal_speed = std::max(pair.normal_speed, closing);
    }
  }

  // --- the bound on pairs (limits::contact_pairs_per_part) --------------------------
  // A pair whose two parts each touch that many moving parts already is left
  // out before its narrow phase: its parts pass through each other.
  std::vector<std::uint32_t> pair_count;   // by slot: pairs kept with a moving part
  std::size_t left_out = 0;                // pairs left out this update
  std::vector<std::uint32_t> left_out_of;  // by slot: pairs of it left out this update
  bool limited_before = false;             // the last update left pairs out

  void leave_out(std::uint32_t s1, std::uint32_t s2) {
    if (left_out_of.size() < geoms.size()) left_out_of.resize(geoms.size(), 0);
    ++left_out_of[s1], ++left_out_of[s2];
    ++left_out;
  }

  // --- parts buried in a heap (see the header; docs/security.md) -------------------
  static constexpr std::uint32_t kCrowd = limits::contact_pairs_per_part;
  /// A waiting part comes back when sunk into at most this many: into room
  /// the heap's parts made by moving apart, not into the heap again
  /// (rigid_body.box2d's measure: at kCrowd, parts came back into a mass
  /// where the pair limit left pairs out).
  static constexpr std::uint32_t kWake = 4;
  std::vector<ObjectId> waiting;                       // in the order they went
  std::vector<std::uint8_t> waiting_flag;              // by slot
  std::size_t went = 0;                                // since the last report (for the event)
  bool waiting_reported = false;                       // the event was sent and some still wait
  ObjectId waiting_example;                            // a part that went, for the event
  std::uint64_t crowd_tests = 0;                       // shape tests made by crowded(), in all
  std::vector<std::uint32_t> crowd_check, crowd_back;  // scratch of settle_crowds() and wake()

  bool is_waiting(std::uint32_t s) const { return s < waiting_flag.size() && waiting_flag[s]; }

  /// Whether parts s and t overlap deeper than half the sum of their inscribed radii.
  bool deep(std::uint32_t s, std::uint32_t t) {
    ++crowd_tests;
    const int n = collide_parts(geoms[s].geom, geoms[t].geom, int(buffer.size()), buffer.data());
    double depth = 0;
    for (int k = 0; k < n; ++k) depth = std::max(depth, double(buffer[std::size_t(k)].depth));
    return depth > 0.5 * (geoms[s].inscribed + geoms[t].inscribed);
  }

  /// Whether slot s is sunk deep into more than `limit` movable parts of the
  /// grid that do not wait, and of `also` (slots outside the grid). Walks the
  /// cells its bounds cover and stops at the first limit + 1 found, so that a
  /// part in a heap costs about limit + 1 shape tests.
  bool crowded(std::uint32_t s, std::uint32_t limit, const std::vector<std::uint32_t>& also) {
    dReal b[6];
    dGeomGetAABB(geoms[s].geom, b);
    Bounds rb;
    for (int k = 0; k < 3; ++k) rb.lo[k] = b[2 * k], rb.hi[k] = b[2 * k + 1];
    std::uint32_t count = 0;
    auto found = [&](std::uint32_t t, const Bounds& tb) {
      if (t == s || !geoms[t].movable || is_waiting(t) || !overlap(rb, tb)) return false;
      return deep(s, t) && ++count > limit;
    };
    std::int64_t lo[3], hi[3];
    double cells = 1;
    for (int k = 0; k < 3; ++k)
      lo[k] = cell_of(rb.lo[k]), hi[k] = cell_of(rb.hi[k]), cells *= double(hi[k] - lo[k] + 1);
    if (cells > 64) {  // a part as large as the grid's big ones: every part
      for (std::uint32_t i = 0; i < live.size(); ++i)
        if (found(live[i], live_bounds[i])) return true;
    } else if (visit_cells(lo, hi,
                           [&](std::uint32_t i) { return found(live[i], live_bounds[i]); })) {
      return true;
    }
    for (const std::uint32_t i : big)
      if (found(live[i], live_bounds[i])) return true;
    for (const std::uint32_t t : also) {
      dGeomGetAABB(geoms[t].geom, b);
      Bounds tb;
      for (int k = 0; k < 3; ++k) tb.lo[k] = b[2 * k], tb.hi[k] = b[2 * k + 1];
      if (found(t, tb)) return true;
    }
    return false;
  }

  /// Of the movable parts of the grid that do not wait, in slot order, those
  /// in a bucket of more than kCrowd entries (`left_out` false: where a heap
  /// can be) or with pairs left out (`left_out` true): each crowded by the
  /// parts that do not wait goes to wait (a heap of n keeps its last kCrowd +
  /// 1 at its spot). Whether any went.
  bool settle_crowds(bool pairs_left_out) {
    const std::size_t before = waiting.size();
    waiting_flag.resize(geoms.size(), 0);
    std::vector<std::uint32_t>& check = crowd_check;
    check.clear();
    if (pairs_left_out) {
      for (std::uint32_t i = 0; i < live.size(); ++i)
        if (live[i] < left_out_of.size() && left_out_of[live[i]] > 0) check.push_back(i);
    } else {
      for (std::size_t bkt = 0; bkt + 1 < bucket_start.size(); ++bkt)
        if (bucket_start[bkt + 1] - bucket_start[bkt] > kCrowd)
          for (std::uint32_t p = bucket_start[bkt]; p < bucket_start[bkt + 1]; ++p)
            check.push_back(table[p].part);
      std::sort(check.begin(), check.end());
      check.erase(std::unique(check.begin(), check.end()), check.end());
    }
    for (const std::uint32_t i : check) {
      const std::uint32_t s = live[i];
      if (geoms[s].movable && !waiting_flag[s] && crowded(s, kCrowd, {})) {
        waiting_flag[s] = 1;
        waiting.push_back(geoms[s].id);
        if (went++ == 0) waiting_example = geoms[s].id;
      }
    }
    return waiting.size() > before;
  }
  /// Whether a bucket of the grid holds more than kCrowd entries.
  bool crowded_bucket() const {
    for (std::size_t bkt = 0; bkt + 1 < bucket_start.size(); ++bkt)
      if (bucket_start[bkt + 1] - bucket_start[bkt] > kCrowd) return true;
    return false;
  }

  /// Puts back, in the order they went, the waiting parts no longer crowded
  /// (the grid holds the parts that do not wait). Whether any came back.
  bool wake() {
    std::vector<std::uint32_t>& back = crowd_back;
    back.clear();
    std::size_t kept = 0;
    for (const ObjectId id : waiting) {
      const std::uint32_t s = id.index;
      if (crowded(s, kWake, back)) {
        waiting[kept++] = id;
        continue;
      }
      waiting_flag[s] = 0;
      back.push_back(s);
    }
    waiting.resize(kept);
    return !back.empty();
  }

  /// After the geoms were built again: parts no longer there, or no longer
  /// movable, stop waiting.
  void recheck_waiting() {
    waiting_flag.assign(geoms.size(), 0);
    std::size_t kept = 0;
    for (const ObjectId id : waiting) {
      if (id.index >= geoms.size() || !geoms[id.index].geom || geoms[id.index].id != id ||
          !geoms[id.index].movable)
        continue;
      waiting_flag[id.index] = 1;
      waiting[kept++] = id;
    }
    waiting.resize(kept);
  }

  // --- continuous detection -----------------------------------------------------
  struct Candidate {
    std::uint32_t slot;
    Vec3 from;  ///< the centre's position at the previous update
  };
  /// The first surface a ray from a swept part's centre meets.
  struct RayHit {
    const Impl* m = nullptr;
    std::uint32_t self = 0;
    const std::vector<ContactPair>* touching = nullptr;  ///< pairs of the previous update, sorted
    double t = 1e300;                                    ///< distance along the ray, m
    std::uint32_t slot = 0;
    Vec3 position, normal;
  };

  static void ray_callback(void* data, dGeomID o1, dGeomID o2) {
    auto& h = *static_cast<RayHit*>(data);
    const Impl& m = *h.m;
    dGeomID other = o1 == m.ray ? o2 : o1;
    const auto s = std::uint32_t(reinterpret_cast<std::uintptr_t>(dGeomGetData(other)));
    if (s == h.self) return;
    if (!m.joined.empty() &&
        std::binary_search(m.joined.begin(), m.joined.end(), pair_key(h.self, s)))
      return;
    // Parts it touched already: the discrete contact is handling them.
    ContactPair key;
    key.a = m.geoms[std::min(s, h.self)].id, key.b = m.geoms[std::max(s, h.self)].id;
    if (std::binary_search(h.touching->begin(), h.touching->end(), key, by_pair)) return;
    dContactGeom c;
    if (dCollide(m.ray, other, 1, &c, sizeof(dContactGeom)) <= 0 || !(c.depth < h.t)) return;
    h.t = c.depth, h.slot = s, h.position = to_vec3(c.pos), h.normal = to_vec3(c.normal);
  }

  // --- broad phase ------------------------------------------------------------------
  // ODE's spaces grow faster than linear on alloy's scenes (measured in
  // docs/performance.md "Collisions to 100,000 bodies"): the hash space's
  // cell hash (level*1000 + x*100 + y*10 + z) sends the cells of a dense grid
  // of parts into the same buckets, and sweep-and-prune's one axis holds a
  // whole row of a pile. So the pairs come from a uniform grid of our own,
  // rebuilt every update in O(n): each part's bounds go into the cells they
  // cover (a hash table sized to the entries, filled by a counting sort), and
  // two parts are tested in the one cell that holds the low corner of their
  // bounds' intersection, so no pair is tested twice. The geoms stay in ODE's
  // hash space, which is used only when a part lies beyond kIndexable (ODE's
  // collide then reports it as before: see engine_failed).
  struct Bounds {
    double lo[3], hi[3];
    std::int64_t cell[3];  ///< the grid cell of lo
  };
  struct Entry {
    std::int64_t cell[3];
    std::uint32_t part;  ///< index into live
    std::uint32_t bucket;
  };
  std::vector<std::uint32_t> live;  // slots of the enabled geoms, ascending
  std::vector<Bounds> live_bounds;  // by index into live
  std::vector<std::uint32_t> big;   // indices into live of parts too large for the grid
  std::vector<Entry> entries, table;
  std::vector<std::uint32_t> bucket_start;
  std::vector<double> extents;
  std::vector<std::uint32_t> seen;  // by index into live: the last ray query that saw it
  std::uint32_t query = 0;
  double cell = 1;                                     ///< grid spacing, m
  static constexpr std::int64_t kMaxCellsPerAxis = 4;  ///< larger parts are "big"

  std::int64_t cell_of(double x) const { return std::int64_t(std::floor(x / cell)); }
  static std::uint64_t cell_hash(const std::int64_t c[3]) {
    std::uint64_t h = std::uint64_t(c[0]) * 0x9E3779B97F4A7C15ull;
    h ^= std::uint64_t(c[1]) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= std::uint64_t(c[2]) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return h ^ (h >> 29);
  }
  static bool overlap(const Bounds& a, const Bounds& b) {
    // Touching bounds overlap, as in ODE's spaces.
    for (int k = 0; k < 3; ++k)
      if (a.lo[k] > b.hi[k] || b.lo[k] > a.hi[k]) return false;
    return true;
  }

  /// The enabled geoms and their bounds; false if one lies beyond kIndexable
  /// (or is not finite): then ODE's hash space must collide, and report it.
  bool gather() {
    live.clear(), live_bounds.clear(), extents.clear();
    for (std::uint32_t s : geom_slots) {
      const dGeomID g = geoms[s].geom;
      if (!dGeomIsEnabled(g) || is_waiting(s)) continue;
      dReal b[6];
      dGeomGetAABB(g, b);
      for (const dReal v : b)
        if (!(std::abs(v) < kIndexable)) return false;
      Bounds& o = live_bounds.emplace_back();
      for (int k = 0; k < 3; ++k) o.lo[k] = b[2 * k], o.hi[k] = b[2 * k + 1];
      extents.push_back(std::max({b[1] - b[0], b[3] - b[2], b[5] - b[4]}));
      live.push_back(s);
    }
    return true;
  }

  /// Builds the grid over the gathered bounds: the spacing is twice the
  /// median part's largest extent (a typical part covers 1 to 8 cells); a
  /// part covering more than kMaxCellsPerAxis cells along an axis (a floor,
  /// a wall) is kept apart and tested against every part.
  void build_grid() {
    big.clear(), entries.clear(), table.clear(), bucket_start.clear();
    if (live.empty()) return;  // nothing to find (and no stale cells from the last update)
    std::vector<double>& e = extents;
    std::nth_element(e.begin(), e.begin() + std::ptrdiff_t(e.size() / 2), e.end());
    cell = std::max(2 * e[e.size() / 2], 1e-6);
    for (std::uint32_t i = 0; i < live.size(); ++i) {
      Bounds& b = live_bounds[i];
      std::int64_t hi[3];
      bool is_big = false;
      for (int k = 0; k < 3; ++k) {
        b.cell[k] = cell_of(b.lo[k]), hi[k] = cell_of(b.hi[k]);
        is_big = is_big || hi[k] - b.cell[k] >= kMaxCellsPerAxis;
      }
      if (is_big) {
        big.push_back(i);
        continue;
      }
      for (std::int64_t x = b.cell[0]; x <= hi[0]; ++x)
        for (std::int64_t y = b.cell[1]; y <= hi[1]; ++y)
          for (std::int64_t z = b.cell[2]; z <= hi[2]; ++z) entries.push_back({{x, y, z}, i, 0});
    }
    // A counting sort of the entries by bucket: linear, no comparison sort.
    std::size_t size = 16;
    while (size < 2 * entries.size()) size *= 2;
    bucket_start.assign(size + 1, 0);
    for (Entry& en : entries) {
      en.bucket = std::uint32_t(cell_hash(en.cell) & (size - 1));
      ++bucket_start[en.bucket + 1];
    }
    for (std::size_t b = 0; b < size; ++b) bucket_start[b + 1] += bucket_start[b];
    table.resize(entries.size());
    std::vector<std::uint32_t>& fill = order_fill;
    fill.assign(bucket_start.begin(), bucket_start.end() - 1);
    for (const Entry& en : entries) table[fill[en.bucket]++] = en;
  }
  std::vector<std::uint32_t> order_fill;

  /// Whether ODE's category bits let the two collide (static parts meet only movable ones).
  static bool may_collide(dGeomID a, dGeomID b) {
    return (dGeomGetCategoryBits(a) & dGeomGetCollideBits(b)) ||
           (dGeomGetCategoryBits(b) & dGeomGetCollideBits(a));
  }
  void test(std::uint32_t i, std::uint32_t j) {
    if (!overlap(live_bounds[i], live_bounds[j])) return;
    const dGeomID a = geoms[live[i]].geom, b = geoms[live[j]].geom;
    if (may_collide(a, b)) near_callback(this, a, b);
  }

  /// Every pair of enabled geoms whose bounds overlap goes to near_callback
  /// once (the grid built over them first).
  void collide_grid() {
    for (std::size_t bkt = 0; bkt + 1 < bucket_start.size(); ++bkt) {
      const std::uint32_t from = bucket_start[bkt], to = bucket_start[bkt + 1];
      for (std::uint32_t p = from; p < to; ++p)
        for (std::uint32_t q = p + 1; q < to; ++q) {
          const Entry &x = table[p], &y = table[q];
          if (x.cell[0] != y.cell[0] || x.cell[1] != y.cell[1] || x.cell[2] != y.cell[2]) continue;
          // Tested only in the cell of the low corner of the two bounds'
          // intersection (which both cover), so once.
          const Bounds &bx = live_bounds[x.part], &by = live_bounds[y.part];
          bool home = true;
          for (int k = 0; k < 3; ++k) home = home && x.cell[k] == std::max(bx.cell[k], by.cell[k]);
          if (home) test(x.part, y.part);
        }
    }
    for (std::size_t k = 0; k < big.size(); ++k) {
      for (std::uint32_t i = 0; i < live.size(); ++i)
        if (i != big[k] && !std::binary_search(big.begin(), big.end(), i)) test(big[k], i);
      for (std::size_t l = k + 1; l < big.size(); ++l) test(big[k], big[l]);
    }
  }

  /// Each grid part (its index into live) with an entry in the cells lo..hi,
  /// once, to `visit`; stops, and returns true, when `visit` returns true.
  template <class Visit>
  bool visit_cells(const std::int64_t (&lo)[3], const std::int64_t (&hi)[3], Visit&& visit) {
    if (++query == 0) seen.assign(seen.size(), 0), query = 1;
    seen.resize(live.size(), 0);
    if (bucket_start.size() <= 1) return false;
    const std::size_t size = bucket_start.size() - 1;
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
          const std::int64_t c[3] = {x, y, z};
          const std::size_t bkt = cell_hash(c) & (size - 1);
          for (std::uint32_t p = bucket_start[bkt]; p < bucket_start[bkt + 1]; ++p) {
            const Entry& en = table[p];
            if (en.cell[0] != x || en.cell[1] != y || en.cell[2] != z || seen[en.part] == query)
              continue;
            seen[en.part] = query;
            if (visit(en.part)) return true;
          }
        }
    return false;
  }

  /// The enabled geoms whose bounds overlap the ray's, in slot order, to
  /// ray_callback: the cells the ray's bounds cover (every part if they cover
  /// many), and the big parts.
  void collide_ray(RayHit& hit) {
    if (live.empty()) return;
    dReal r[6];
    dGeomGetAABB(ray, r);
    Bounds rb;
    for (int k = 0; k < 3; ++k) rb.lo[k] = r[2 * k], rb.hi[k] = r[2 * k + 1];
    std::vector<std::uint32_t>& found = ray_found;
    found.clear();
    std::int64_t lo[3], hi[3];
    double cells = 1;
    for (int k = 0; k < 3; ++k)
      lo[k] = cell_of(rb.lo[k]), hi[k] = cell_of(rb.hi[k]), cells *= double(hi[k] - lo[k] + 1);
    if (cells > double(std::max<std::size_t>(64, live.size()))) {
      for (std::uint32_t i = 0; i < live.size(); ++i) found.push_back(i);
    } else {
      visit_cells(lo, hi, [&](std::uint32_t i) { return found.push_back(i), false; });
      found.insert(found.end(), big.begin(), big.end());
      std::sort(found.begin(), found.end());
    }
    for (std::uint32_t i : found)
      if (overlap(rb, live_bounds[i])) ray_callback(&hit, ray, geoms[live[i]].geom);
  }
  std::vector<std::uint32_t> ray_found;
  std::vector<std::uint32_t> swept_at, swept_made_at;  // scratch of sweep()
  bool grid = false;  ///< this update's pairs came from the grid (else from ODE's space)

  bool ccd = true;
  dGeomID ray = nullptr;  // not in the space; made at the first sweep
  std::vector<Candidate> candidates;

  dSpaceID space = nullptr;
  std::vector<Geom> geoms;  // by slot
  std::vector<std::uint32_t> geom_slots;
  std::vector<std::uint64_t> joined;  // slot pairs held by a joint, sorted
  // Parts held by a joint are not swept: moving one back would tear the joint
  // open, and a swinging chain's links are not projectiles.
  std::vector<bool> jointed;  // by slot
  std::vector<dContactGeom> buffer;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order;  // sort keys of the step's pairs
  std::vector<std::uint32_t> bucket;                           // per slot: counting sort by a
  std::vector<ContactPair> sorted;

  /// Sorts the step's pairs by slot pair (the same order as by (a, b): live
  /// objects have distinct slots), through 16-byte keys rather than by moving
  /// the pairs. The keys are sorted by a with a counting sort over the slots,
  /// then by b within each a by insertion (a part touches a few others): for
  /// a pile this is a third of std::sort's work. Keys are unique (one pair per
  /// two parts), so the order is the same as any sort's.
  void sort_pairs(std::vector<ContactPair>& pairs) {
    const std::size_t n = pairs.size(), slots = geoms.size();
    order.resize(n);
    if (n * 4 < slots) {  // few pairs among many slots: the buckets would cost more
      for (std::uint32_t k = 0; k < n; ++k)
        order[k] = {(std::uint64_t(pairs[k].a.index) << 32) | pairs[k].b.index, k};
      std::sort(order.begin(), order.end());
    } else {
      bucket.assign(slots + 1, 0);
      for (const ContactPair& p : pairs) ++bucket[p.a.index + 1];
      for (std::size_t s = 1; s <= slots; ++s) bucket[s] += bucket[s - 1];
      for (std::uint32_t k = 0; k < n; ++k)
        order[bucket[pairs[k].a.index]++] = {
            (std::uint64_t(pairs[k].a.index) << 32) | pairs[k].b.index, k};
      for (std::size_t i = 1; i < n; ++i) {  // runs of equal a: short
        const auto key = order[i];
        std::size_t j = i;
        for (; j > 0 && key.first < order[j - 1].first; --j) order[j] = order[j - 1];
        order[j] = key;
      }
    }
    sorted.clear();
    for (const auto& [key, k] : order) sorted.push_back(pairs[k]);
    std::swap(pairs, sorted);
  }
  bool geoms_dirty = true, joints_dirty = true;

  bool have_ids = false;
  PropertyId position{}, orientation{}, velocity{}, angular_velocity{}, shape{}, size{}, radius{},
      length{}, static_{}, joint{}, body_a{}, body_b{};
  std::vector<const ColumnBase*> shape_columns, joint_columns;
  std::vector<std::uint64_t> shape_seen, joint_seen;

  // Valid during one update's dSpaceCollide.
  ColumnView<Vec3> vel, angvel;
  std::vector<ContactPair>* pairs = nullptr;
  std::vector<ContactPoint>* points = nullptr;
};

CollisionSet::CollisionSet(const RigidBodyResolver& rigid, int max_contacts, bool always_impulses)
    : rigid_(rigid), impl_(std::make_unique<Impl>(max_contacts)) {
  if (always_impulses) always_ = rigid_.demand_impulses();
}

ImpulseDemand CollisionSet::demand_impulses() const {
  return rigid_.demand_impulses();
}

std::vector<PredictedTouch> CollisionSet::touching_ahead(const WorldView& world,
                                                         std::span<const ObjectId> parts,
                                                         double seconds) const {
  Impl& m = *impl_;
  std::vector<PredictedTouch> out;
  if (m.geoms_dirty || !(seconds > 0) || parts.size() < 2) return out;
  const auto velocity = world.column<Vec3>(m.velocity);
  const auto spin = world.column<Vec3>(m.angular_velocity);
  // The parts that can be tested, each moving one moved to where its
  // velocities take it, with its bounds there.
  struct Candidate {
    std::uint32_t slot;
    bool moves;
    double lo[3], hi[3];
  };
  std::vector<Candidate> boxes;
  boxes.reserve(parts.size());
  auto set_pose = [&](const Impl::Geom& g, Vec3 x, Quat q) {
    dGeomSetPosition(g.geom, x.x, x.y, x.z);
    dQuaternion oq;
    to_ode(g.capsule ? normalized(q) * capsule_axis_rotation() : normalized(q), oq);
    dGeomSetQuaternion(g.geom, oq);
  };
  bool any_moves = false;
  for (const ObjectId id : parts) {
    const std::uint32_t s = id.index;
    if (s >= m.geoms.size()) continue;
    const Impl::Geom& g = m.geoms[s];
    if (!g.geom || !g.placed || g.id != id || m.is_waiting(s) || !dGeomIsEnabled(g.geom)) continue;
    Candidate& c = boxes.emplace_back(Candidate{s, false, {}, {}});
    if (g.movable) {
      const Vec3 v = velocity.value_or(s, Vec3{}), w = spin.value_or(s, Vec3{});
      const double turn = length(w) * seconds;
      const Quat q = turn > 0 ? Quat::from_axis_angle(w / length(w), turn) * g.q : g.q;
      c.moves = (v != Vec3{} || turn > 0) && is_finite(v) && is_finite(q);
      if (c.moves) set_pose(g, g.pos + v * seconds, q);
      any_moves = any_moves || c.moves;
    }
  }
  if (!any_moves) return out;  // nothing moves: no pair can come to touch
  for (Candidate& c : boxes) {
    dReal b[6];
    dGeomGetAABB(m.geoms[c.slot].geom, b);
    for (int k = 0; k < 3; ++k) c.lo[k] = b[2 * k], c.hi[k] = b[2 * k + 1];
  }
  for_each_overlap(boxes, [&](std::size_t i, std::size_t j) {
    if (!boxes[i].moves && !boxes[j].moves) return;  // neither can come to touch
    std::uint32_t s1 = boxes[i].slot, s2 = boxes[j].slot;
    if (s1 > s2) std::swap(s1, s2);
    const Impl::Geom &g1 = m.geoms[s1], &g2 = m.geoms[s2];
    if (std::binary_search(m.joined.begin(), m.joined.end(), pair_key(s1, s2))) return;
    if (find(g1.id, g2.id)) return;  // touching now
    const int n = collide_parts(g1.geom, g2.geom, int(m.buffer.size()), m.buffer.data());
    if (n <= 0) return;
    Vec3 mean{};
    for (int k = 0; k < n; ++k) mean += to_vec3(m.buffer[std::size_t(k)].pos);
    out.push_back({g1.id, g2.id, mean / double(n)});
  });
  // Back where they were, bit for bit (place() compares the cached poses).
  for (const Candidate& c : boxes)
    if (c.moves) set_pose(m.geoms[c.slot], m.geoms[c.slot].pos, m.geoms[c.slot].q);
  std::sort(out.begin(), out.end(), [](const PredictedTouch& x, const PredictedTouch& y) {
    return pair_less(x.a, x.b, y.a, y.b);
  });
  return out;
}

CollisionSet::~CollisionSet() = default;

void CollisionSet::on_structure_changed(const WorldView&) {
  impl_->geoms_dirty = true;
  impl_->joints_dirty = true;
}

void CollisionSet::update(const WorldView& world) {
  ensure_ode();
  Impl& m = *impl_;
  m.resolve_ids(world);
  m.ccd = rigid_.config().ccd;
  // After a restore this update repeats the last one of the run that saved
  // (restore_state): at its step, with the parts it swept.
  const bool repeat = std::exchange(restored_, false);
  std::vector<Impl::Candidate> restored_candidates;
  if (repeat) std::swap(restored_candidates, m.candidates);
  m.candidates.clear();
  prior_known_ = impulses_known_, prior_since_ = impulses_since_;

  // Narrow phase into current_, then sort: ODE's pair order is not ours to rely on.
  begin_update();
  try {
    // Parts added or changed (every spawn rebuilds): the grid's full cells
    // are checked for a heap before the narrow phase.
    bool fresh = false;
    if (Impl::changed(m.shape_columns, m.shape_seen) || m.geoms_dirty) {
      m.rebuild_geoms(world);
      m.geoms_dirty = false;
      if (!m.waiting.empty()) m.recheck_waiting();
      fresh = true;
    }
    if (Impl::changed(m.joint_columns, m.joint_seen) || m.joints_dirty) {
      m.rebuild_joined(world);
      m.joints_dirty = false;
    }
    m.place(world);
    // Fresh geoms have no previous positions: the swept parts are the saved run's.
    // (A slot without a geom can only come from damaged bytes: left out.)
    if (repeat)
      for (const Impl::Candidate& c : restored_candidates)
        if (c.slot < m.geoms.size() && m.geoms[c.slot].geom && m.geoms[c.slot].movable)
          m.candidates.push_back(c);
    m.vel = world.column<Vec3>(m.velocity);
    m.angvel = world.column<Vec3>(m.angular_velocity);
    m.pairs = &current_;
    m.points = &points_;
    m.grid = m.gather();
    if (m.grid) {
      // Waiting parts whose spot cleared come back (Impl::wake), and after a
      // rebuild the parts of a cell holding more than kCrowd are checked for
      // a heap before the narrow phase (Impl::settle_crowds).
      m.build_grid();
      if (!m.waiting.empty() && m.wake()) m.gather(), m.build_grid();
      if (fresh && m.crowded_bucket() && m.settle_crowds(false)) m.gather(), m.build_grid();
    }
    m.pair_count.assign(m.geoms.size(), 0);
    m.left_out = 0;
    if (m.grid) {
      m.collide_grid();
      // Pairs left out (a part carried into a heap, a heap across cells):
      // their parts are checked, and the pairs are found again without
      // those that went to wait.
      if (m.left_out > 0 && m.settle_crowds(true)) {
        current_.clear(), points_.clear();
        m.gather();
        m.pair_count.assign(m.geoms.size(), 0);
        m.left_out = 0;
        std::fill(m.left_out_of.begin(), m.left_out_of.end(), 0u);
        m.build_grid();
        m.collide_grid();
      }
    } else {  // a part beyond the grid's range: ODE's collide reports it (engine_failed)
      m.colliding = true;
      dSpaceCollide(m.space, &m, &Impl::near_callback);
      m.colliding = false;
    }
    sweep(world);
  } catch (const OdeError& e) {
    engine_failed(world, e.what());
    return;
  } catch (...) {
    // Bad input (InputError from a shape) or the host's own failure: the set
    // stays as the last update left it, and a space this left locked goes.
    if (m.colliding) m.abandon_geoms();
    abandon_update();
    throw;
  }
  m.sort_pairs(current_);
  report_left_out(world);
  waiting_ = m.waiting;
  report_waiting(world);

  // A repeated update is of the step the saved run's last update was (the
  // set may have been skipped since, while nothing it reads changed).
  publish(world, rigid_.impulses(), rigid_.impulses_computed(), repeat ? step_ : world.step());
}

void CollisionSet::engine_failed(const WorldView& world, const std::string& what) {
  // ODE stopped half way through (an assertion: ODE's handler throws, see
  // ode_support.hpp). The process goes on: this update keeps the last one's
  // pairs and points (no pair begins or ends, nothing is swept), the geoms
  // are built again at the next update, and the parts the hash space cannot
  // index are left out of collisions until they are back in range.
  Impl& m = *impl_;
  const std::vector<std::uint32_t> culprits = m.abandon_geoms();
  abandon_update();
  clear_changes();
  sweeps_.clear();
  step_ = world.step();
  Event e{.type = "engine_error", .text = "collisions: " + what};
  const PropertyStore& store = world.store();
  for (std::size_t k = 0; k < culprits.size() && k < 3; ++k) {
    const ObjectId id = store.id_at(culprits[k]);
    if (k == 0) e.a = id;
    e.text += (k == 0 ? "; " : ", ") + store.describe(id);
  }
  if (culprits.size() > 3) e.text += " and " + std::to_string(culprits.size() - 3) + " more";
  if (!culprits.empty())
    e.text += std::string(culprits.size() == 1 ? " lies" : " lie") +
              " beyond the range of collision detection (" + std::to_string(int(kIndexable)) +
              " m) and " + (culprits.size() == 1 ? "takes" : "take") +
              " no part in collisions until back within it";
  e.text += " (this step's contacts are the last step's)";
  world.emit(std::move(e));
}

void CollisionSet::report_left_out(const WorldView& world) {
  // One event when pairs begin to be left out (not one a step while a heap
  // lasts), naming the part with the most pairs left out.
  Impl& m = *impl_;
  const bool limited = m.left_out > 0;
  if (limited && !m.limited_before) {
    std::uint32_t worst = 0;
    for (std::uint32_t s = 0; s < m.left_out_of.size(); ++s)
      if (m.left_out_of[s] > m.left_out_of[worst]) worst = s;
    const PropertyStore& store = world.store();
    const ObjectId id = m.geoms[worst].id;
    world.emit(Event{
        .type = "contact_limit",
        .a = id,
        .values = {{"per_part", double(limits::contact_pairs_per_part)},
                   {"left_out", double(m.left_out)},
                   {"of_part", double(m.left_out_of[worst])}},
        .text = "collisions: " + std::to_string(m.left_out) +
                " pairs of overlapping parts were left out, each of whose parts touched " +
                std::to_string(limits::contact_pairs_per_part) +
                " moving parts already (the limit); they pass through each other. '" +
                store.describe(id) + "' is in " + std::to_string(m.left_out_of[worst]) +
                " of them: parts placed through each other in a heap? (reported when it begins; "
                "docs/security.md)"});
  }
  m.limited_before = limited;
  if (limited) std::fill(m.left_out_of.begin(), m.left_out_of.end(), 0u);
}

void CollisionSet::report_waiting(const WorldView& world) {
  // One event when parts begin to wait (not one a step while a heap
  // empties), naming one of them; again after every waiting part came back.
  Impl& m = *impl_;
  const bool report = m.went > 0 && !m.waiting_reported;
  const std::size_t went = m.went;
  m.went = 0;
  m.waiting_reported = !m.waiting.empty() && (m.waiting_reported || report);
  if (!report) return;
  const ObjectId id = m.waiting_example;
  world.emit(
      Event{.type = "crowded",
            .a = id,
            .values = {{"went", double(went)},
                       {"waiting", double(m.waiting.size())},
                       {"limit", double(Impl::kCrowd)}},
            .text = "collisions: " + std::to_string(went) +
                    " parts were taken out of collisions, each sunk deep into more than " +
                    std::to_string(Impl::kCrowd) + " moving parts ('" + world.store().describe(id) +
                    "' among them): they wait, held still, until the parts around them have moved "
                    "apart (parts placed through each other in a heap?; docs/security.md)"});
}

std::uint64_t CollisionSet::crowd_tests() const {
  return impl_->crowd_tests;
}

void CollisionSet::sweep(const WorldView& world) {
  Impl& m = *impl_;
  sweeps_.clear();
  if (m.candidates.empty()) return;
  if (!m.ray) m.ray = dCreateRay(nullptr, 1);
  const double dt = world.dt();
  // The overlap a swept part is left with: the rigid body's resting overlap,
  // so that the next narrow phase finds the contact and the solver keeps it.
  const double layer = rigid_.config().surface_layer;
  // A swept part's discrete pairs (and swept pairs made before it that it
  // is part of) give way to its swept contact. Removed in one pass after the
  // loop, not per part: a crowd falling fast sweeps thousands of parts.
  const std::size_t discrete = current_.size();
  std::vector<std::uint32_t>& swept_at = m.swept_at;  // by slot: 1 + order of its sweep, 0: none
  swept_at.resize(m.geoms.size(), 0);
  std::vector<std::uint32_t>& made_at = m.swept_made_at;  // by swept pair: 1 + order of its sweep
  made_at.clear();
  std::uint32_t order = 0;
  for (const Impl::Candidate& cand : m.candidates) {
    if (m.is_waiting(cand.slot)) continue;  // out of collisions, held still
    const Impl::Geom& g = m.geoms[cand.slot];
    const Vec3 d = g.pos - cand.from;
    const double len = length(d);
    // Only motion along the part's velocity is swept: an edit that moves a
    // part (a player carrying it through a wall) is not undone.
    if (length(d - m.vel.value_or(cand.slot, {}) * dt) > 0.5 * len) continue;
    const Vec3 dir = d / len;
    dGeomRaySet(m.ray, cand.from.x, cand.from.y, cand.from.z, dir.x, dir.y, dir.z);
    dGeomRaySetLength(m.ray, len);
    Impl::RayHit hit{.m = &m, .self = cand.slot, .touching = &previous_};
    if (m.grid) {
      m.collide_ray(hit);
    } else {
      m.colliding = true;
      dSpaceCollide2(m.ray, reinterpret_cast<dGeomID>(m.space), &hit, &Impl::ray_callback);
      m.colliding = false;
    }
    if (!(hit.t <= len)) continue;  // the centre crossed no surface: the discrete test sees it

    // Back along the path to where the part, a sphere of its inscribed radius,
    // touches the surface it crossed with the resting overlap.
    Vec3 n = hit.normal;
    if (dot(n, dir) > 0) n = -n;  // out of the surface, towards where the part came from
    const double incidence = std::max(-dot(n, dir), 0.05);
    const double reach = g.reach(n);
    const double along = std::max(0.0, hit.t - (reach - layer) / incidence);
    const Vec3 centre = cand.from + dir * along;
    sweeps_.push_back({g.id, centre - g.pos});

    // Its discrete pairs were found at the tunnelled pose: the swept contact replaces them.
    swept_at[cand.slot] = ++order;
    const bool self_first = cand.slot < hit.slot;
    ContactPair pair;
    pair.a = m.geoms[self_first ? cand.slot : hit.slot].id;
    pair.b = m.geoms[self_first ? hit.slot : cand.slot].id;
    const ContactPoint p{centre - n * reach, self_first ? n : -n,
                         std::max(0.0, reach - dot(centre - hit.position, n))};
    pair.first = std::uint32_t(points_.size());
    pair.count = 1;
    pair.depth = p.depth;
    const std::uint32_t sa = self_first ? cand.slot : hit.slot,
                        sb = self_first ? hit.slot : cand.slot;
    pair.normal_speed = dot(m.motion(sb).at(p.position) - m.motion(sa).at(p.position), p.normal);
    points_.push_back(p);
    current_.push_back(pair);
    made_at.push_back(order);
  }
  if (order > 0) {
    std::size_t kept = 0;
    for (std::size_t k = 0; k < current_.size(); ++k) {
      const ContactPair& p = current_[k];
      const std::uint32_t made = k < discrete ? 0 : made_at[k - discrete];
      if (swept_at[p.a.index] > made || swept_at[p.b.index] > made) continue;
      current_[kept++] = p;
    }
    current_.resize(kept);
    for (const Impl::Candidate& cand : m.candidates) swept_at[cand.slot] = 0;
  }
  std::sort(sweeps_.begin(), sweeps_.end(),
            [](const Sweep& x, const Sweep& y) { return x.part < y.part; });
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------
//
// The set keeps between updates the pairs that touch (with the step each
// began and its impulse total), whether impulses were known, and each part's
// previous position (for sweeps). A restored set is primed by one update, as
// every derived set is: so it saves its memory as it was *before* its last
// update, and that priming update repeats the last one: the same pairs begin
// and end, with the same began_step, totals and durations. Its events are not
// published again (the world drops the priming's events).
//
// The bytes: a version, the step of the last update, the impulse flags before
// it, the pairs that touched before it (a, b, began_step, total_impulse; the
// speed and depth too of those that ended at it, which the ended pairs carry),
// and the parts it swept with their previous positions. About 32 bytes a
// touching pair.

namespace {
constexpr std::uint32_t kStateVersion = 1;
struct SavedPair {
  ObjectId a, b;
  std::uint64_t began_step;
  double total_impulse;
};
struct SavedEnd {
  ObjectId a, b;
  double normal_speed, depth;
};
struct SavedCandidate {
  std::uint64_t slot;  // 64 bits: no padding, whose bytes would be arbitrary
  Vec3 from;
};
}  // namespace

bool CollisionSet::save_state(StateWriter& out) const {
  out.put(kStateVersion);
  out.put(step_);
  out.put(std::uint8_t(prior_known_));
  out.put(prior_since_);
  std::vector<SavedPair> pairs;
  pairs.reserve(previous_.size());
  for (const ContactPair& p : previous_) pairs.push_back({p.a, p.b, p.began_step, p.total_impulse});
  out.put_vector(pairs);
  std::vector<SavedEnd> ends;
  for (const ContactPair& p : ended_) ends.push_back({p.a, p.b, p.normal_speed, p.depth});
  out.put_vector(ends);
  std::vector<SavedCandidate> candidates;
  for (const Impl::Candidate& c : impl_->candidates) candidates.push_back({c.slot, c.from});
  out.put_vector(candidates);
  return true;
}

void CollisionSet::restore_state(StateReader& in) {
  auto damaged = [&](const std::string& what) {
    throw InputError("the saved state of stage '" + in.stage() + "' is damaged: " + what);
  };
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kStateVersion));
  const auto step = in.get<std::uint64_t>();
  const auto known = in.get<std::uint8_t>();
  const auto since = in.get<std::uint64_t>();
  const auto pairs = in.get_vector<SavedPair>();
  const auto ends = in.get_vector<SavedEnd>();
  const auto candidates = in.get_vector<SavedCandidate>();
  if (known > 1) damaged("an impulse flag of " + std::to_string(known));
  // The merge needs the pairs sorted and distinct; each must have begun by then.
  std::vector<ContactPair> prior;
  prior.reserve(pairs.size());
  for (const SavedPair& s : pairs) {
    ContactPair p;
    p.a = s.a, p.b = s.b, p.began_step = s.began_step, p.total_impulse = s.total_impulse;
    if (!(p.a < p.b) || p.began_step > step || (!prior.empty() && !by_pair(prior.back(), p)))
      damaged("its touching pairs are out of order or began after step " + std::to_string(step));
    prior.push_back(p);
  }
  for (const SavedEnd& e : ends) {
    ContactPair key;
    key.a = e.a, key.b = e.b;
    auto it = std::lower_bound(prior.begin(), prior.end(), key, by_pair);
    if (it == prior.end() || it->a != e.a || it->b != e.b)
      damaged("a pair ended that did not touch");
    it->normal_speed = e.normal_speed, it->depth = e.depth;
  }
  // Slots are checked against the geoms at the update (they are not built yet).
  std::vector<Impl::Candidate> swept;
  for (const SavedCandidate& c : candidates) {
    if (!std::isfinite(c.from.x) || !std::isfinite(c.from.y) || !std::isfinite(c.from.z))
      damaged("a swept part's previous position is not finite");
    swept.push_back({std::uint32_t(std::min<std::uint64_t>(c.slot, ObjectId::kNoIndex)), c.from});
  }
  // update() swaps current_ into previous_ first: the prior pairs go there.
  current_ = std::move(prior);
  points_.clear();
  began_.clear(), ended_.clear(), sweeps_.clear();
  ongoing_.clear(), ongoing_made_ = false;
  impl_->candidates = std::move(swept);
  // Parts that waited are not saved: the priming update finds the buried
  // ones again, as rigid_body.box2d's rebuild does (docs/saves.md).
  impl_->waiting.clear(), impl_->waiting_flag.clear(), waiting_.clear();
  impl_->went = 0, impl_->waiting_reported = false;
  impulses_known_ = known != 0;
  impulses_since_ = since;
  step_ = step;
  restored_ = true;
}

}  // namespace alloy::rigid
