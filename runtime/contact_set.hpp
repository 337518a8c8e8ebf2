// Contacts as every reader sees them, whichever engine finds them: the
// `collisions` derived set's published lists (paper 3.3). The ODE rigid body's
// CollisionSet (resolvers/rigid_body/collisions.hpp) and any other engine's
// contact provider derive from ContactSet and fill the same lists, so that
// electricity, sound, Lua mods and the viewer read contacts without naming an
// engine.
//
// An update's lists, each sorted by (a, b):
//   began    pairs that touch now and did not at the last update
//   ongoing  pairs that touched then and still do
//   ended    pairs that touched then and do not now
// with contact points, normals, depths, the approach speed, and the impulse
// the rigid body applied to the pair in its last advance (while some reader
// demands impulses: see ImpulseDemand).
//
// Geometry made on first read. A provider whose points are costly to make
// (Box2D: a world manifold and two body velocities per contact) may publish
// the pairs alone and make the points, and each pair's first, count,
// normal_speed and depth, when a reader first asks for them in that update
// (make_geometry): a step that nobody reads pays for the pairs (the events
// need them) and for the few began pairs' geometry (their events carry the
// impact speed and depth), not for a thousand resting pairs' points. Every
// value a reader gets is the one an eager provider gives, bit for bit. Two
// consequences, both documented where they apply: the lists are made at once
// at every update while some stage declared the set among its inputs (a
// reader: PluginContext), because an ended pair carries the depth and speed
// of its last update and those cannot be made once the engine has moved on;
// and without such a stage, an ended pair whose last update nobody read
// carries depth and normal_speed 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"
#include "runtime/stage.hpp"

namespace alloy {

class WorldView;

/// One point of contact between two parts a and b (a < b by ObjectId).
struct ContactPoint {
  Vec3 position;  ///< world frame, m
  /// Unit normal pointing from b towards a: moving a along +normal by `depth`
  /// separates the parts (ODE's convention with a as body 1).
  Vec3 normal;
  double depth = 0;  ///< penetration, m (>= 0)
};

/// The impulse the rigid body applied to a pair of parts over its last advance.
struct PairImpulse {
  ObjectId a, b;  ///< a < b
  /// Total contact impulse on a (normal and friction), N*s; b got -impulse.
  Vec3 impulse;
  double normal_impulse = 0;  ///< its normal part, N*s (>= 0)
};

/// Two parts in contact (or, in ended(), no longer in contact).
struct ContactPair {
  ObjectId a, b;  ///< a < b
  /// Points [first, first + count) of ContactSet::points(); count is 0 for ended pairs.
  std::uint32_t first = 0, count = 0;
  /// Approach speed along the normal, m/s: > 0 when the parts close in. The
  /// largest over the pair's points; at `began`, the impact speed.
  double normal_speed = 0;
  double depth = 0;  ///< deepest penetration, m
  /// Impulse the rigid body applied to this pair in its last advance (on a,
  /// N*s). This and the next two are 0 unless ContactSet::impulses_known().
  Vec3 impulse;
  double normal_impulse = 0;  ///< its normal part, N*s
  /// Normal impulse summed over every advance since the pair began, N*s.
  double total_impulse = 0;
  std::uint64_t began_step = 0;  ///< world step at which the pair began
};

/// A stage's declaration that it reads contact impulses (ContactPair::impulse,
/// normal_impulse, total_impulse, the impulse of contact_ended). The rigid
/// body computes them (ODE's joint feedback on every contact joint, about 2 %
/// of a pile's step) only while at least one demand is held: a scene pays
/// nothing for impulses nobody reads. Hold it for as long as the stage reads
/// them (a member); it may outlive the rigid body it was taken from.
class ImpulseDemand {
 public:
  ImpulseDemand() = default;
  explicit ImpulseDemand(std::shared_ptr<std::size_t> count) : count_(std::move(count)) {
    if (count_) ++*count_;
  }
  ImpulseDemand(ImpulseDemand&& o) noexcept = default;
  ImpulseDemand& operator=(ImpulseDemand&& o) noexcept {
    if (this != &o) release(), count_ = std::move(o.count_);
    return *this;
  }
  ImpulseDemand(const ImpulseDemand&) = delete;
  ImpulseDemand& operator=(const ImpulseDemand&) = delete;
  ~ImpulseDemand() { release(); }
  /// Whether this holds a demand (a default-constructed one does not).
  explicit operator bool() const { return bool(count_); }

 private:
  void release() {
    if (count_) --*count_, count_.reset();
  }
  std::shared_ptr<std::size_t> count_;
};

/// Two parts that would touch a while on, were each to move on with its
/// present velocity (ContactSet::touching_ahead).
struct PredictedTouch {
  ObjectId a, b;  ///< a < b
  Vec3 point;     ///< the mean of the touch's points, world frame, at the predicted poses, m
};

/// Calls f(i, j) (i < j after sorting) for each pair of `boxes` whose axis-
/// aligned bounds overlap, by sort and sweep along x: n log n plus the pairs
/// whose x extents overlap, not n^2 / 2 (a prediction among thousands of
/// resting conductive parts, adv21). `Box` has double-convertible lo[3] and
/// hi[3]; `boxes` is sorted by lo[0] in place (ties keep their order).
template <class Box, class F>
void for_each_overlap(std::vector<Box>& boxes, F&& f) {
  std::stable_sort(boxes.begin(), boxes.end(),
                   [](const Box& x, const Box& y) { return x.lo[0] < y.lo[0]; });
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size() && !(boxes[j].lo[0] > boxes[i].hi[0]); ++j)
      if (!(boxes[i].lo[1] > boxes[j].hi[1] || boxes[j].lo[1] > boxes[i].hi[1] ||
            boxes[i].lo[2] > boxes[j].hi[2] || boxes[j].lo[2] > boxes[i].hi[2]))
        f(i, j);
}

/// Orders pairs by (a, b): the deterministic order of every contact list.
constexpr bool pair_less(ObjectId a1, ObjectId b1, ObjectId a2, ObjectId b2) {
  return a1 < a2 || (a1 == a2 && b1 < b2);
}

/// The contact lists of one update (see the header). An engine's provider
/// fills them in its update(): it swaps current_ into previous_ (begin_update),
/// finds the pairs touching now into current_ and their points into points_,
/// sorts current_ by (a, b), and calls publish(), which merges the two sorted
/// lists into began / ongoing / ended, carries each ongoing pair's began_step and
/// total impulse, merges in the impulses of the last advance, and emits
/// contact_began and contact_ended.
class ContactSet : public DerivedSet {
 public:
  std::span<const ContactPair> began() const { return made().began_; }
  std::span<const ContactPair> ongoing() const;
  /// began and ongoing together, sorted by (a, b): every pair that touches now.
  std::span<const ContactPair> touching() const { return made().current_; }
  /// Pairs that ended at the last update, with the depth and normal_speed of
  /// the update before (0 if that update's geometry was never made: see the
  /// header) and no points.
  std::span<const ContactPair> ended() const { return ended_; }
  /// The contact points of began and ongoing pairs.
  std::span<const ContactPoint> points() const { return made().points_; }
  std::span<const ContactPoint> points(const ContactPair& p) const {
    return std::span<const ContactPoint>(made().points_).subspan(p.first, p.count);
  }
  /// Declares a reader: a stage that listed this set among its inputs
  /// (called by PluginContext when it hands the set out). From then on every
  /// update makes its geometry at once (see the header), as the reader will
  /// read it, and ended pairs always carry their last depth and speed.
  void add_reader() { readers_ = true; }
  bool has_readers() const { return readers_; }
  /// The world step of the last update: began() and ended() are about that
  /// step (the set is skipped, and keeps its lists, while nothing moves).
  std::uint64_t step() const { return step_; }
  /// Whether a and b touch (in either order), and the pair if so.
  const ContactPair* find(ObjectId a, ObjectId b) const;

  /// Takes over the pairs and points of the set this one replaces (a swap of
  /// engines), before this one's first update: that update then reports as
  /// ended the pairs that no longer touch, as ongoing (with their began step
  /// and total impulse) those that still do, and as began only new ones, as if
  /// one engine had run throughout. Without it a swap re-announced every
  /// resting pair as began and never ended the old engine's pairs, so that a
  /// circuit closed through a contact stayed closed for good.
  void carry_over(const ContactSet& from);
  /// Declares that the caller reads the pairs' impulses: they are computed
  /// from the rigid body's next advance on while it is held.
  virtual ImpulseDemand demand_impulses() const = 0;
  /// The pairs of `parts` (sorted by ObjectId) that do not touch now and
  /// would touch if every one of them moved on for `seconds` with its
  /// present velocity and angular velocity (published `velocity`,
  /// `angular_velocity`), sorted by (a, b), under the set's own rules (joined
  /// parts, two static parts and waiting parts never touch). Asked after the
  /// set's update in the same step; the set's lists do not change. A contact
  /// that a circuit reads is made between two steps: electricity_from_collisions
  /// asks this to connect a touch that comes within half a step at the step
  /// before it is seen (docs/electricity.md "Contacts between steps").
  /// An engine that cannot tell returns nothing (the default).
  virtual std::vector<PredictedTouch> touching_ahead(const WorldView& world,
                                                     std::span<const ObjectId> parts,
                                                     double seconds) const {
    (void)world, (void)parts, (void)seconds;
    return {};
  }
  /// Steps between a touch and this set's first update that reports it: 0
  /// for a set that finds its contacts at the poses the step ends with (ODE),
  /// 1 for one that finds them at the start of its engine's step (Box2D).
  /// electricity_from_collisions keeps a predicted touch connected this many
  /// more updates while it waits for the report.
  virtual int report_lag() const { return 0; }
  /// Whether the pairs of the last update carry the impulses the rigid body
  /// applied (some stage demanded them); if not, the impulse fields are 0.
  bool impulses_known() const { return impulses_known_; }
  /// Whether the pair's total_impulse covers every advance since it began
  /// (impulses were computed for all of them).
  bool total_known(const ContactPair& p) const {
    return impulses_known_ && p.began_step + 1 >= impulses_since_;
  }

 protected:
  /// Starts an update: the present pairs become the previous ones, and the
  /// present lists are emptied for the provider to fill.
  void begin_update();
  /// Undoes begin_update() (an update that failed keeps the last lists).
  void abandon_update();
  /// Ends an update whose pairs are in current_ (sorted by (a, b)) and points
  /// in points_: see the class comment. `impulses` are the rigid body's of
  /// its last advance, sorted by (a, b), for the pairs it was given;
  /// `computed` says whether it computed any. `step` is the world step the
  /// update is about (the present one, except when a restored set repeats
  /// the saved run's last update).
  void publish(const WorldView& world, std::span<const PairImpulse> impulses, bool computed,
               std::uint64_t step);
  /// Clears began, ended and the lazily made ongoing list (an update that
  /// keeps the last pairs but reports no change).
  void clear_changes();
  /// Replaces the present lists by saved ones (a provider's restore_state):
  /// nothing deferred, no previous lists, no change reported.
  void restore_lists(std::vector<ContactPair> pairs, std::vector<ContactPoint> points);

  /// Geometry on first read (see the header). A provider that fills only the
  /// pairs (a, b) of current_ calls defer_geometry() before publish(); the
  /// set then asks make_geometry() for the began pairs' geometry at publish
  /// (their events), and for every pair's at the first read.
  void defer_geometry() { pending_ = true; }
  /// Fills each of `pairs` (sorted by (a, b), each touching now, with first,
  /// count, normal_speed and depth 0) with its first and count, appending its
  /// points to `points`, and its normal_speed and depth: the same values, in
  /// the same order, whichever subset is asked. Only providers that defer
  /// geometry are asked; the default refuses.
  virtual void make_geometry(std::span<ContactPair> pairs, std::vector<ContactPoint>& points) const;
  /// Whether the present update's geometry can still be made: a provider
  /// whose engine moves on (its next advance) without this set updating
  /// after it returns false, and a read then throws rather than read the new
  /// state as the old (a contact set updated less often than its engine).
  virtual bool geometry_available() const { return true; }
  /// Makes the present update's geometry now, if it was deferred and not
  /// yet made: for a provider whose engine is about to lose what it needs
  /// (a rebuild, a restore, its end).
  void make_pending() const;

  // Lists that a first read completes (make_pending) are mutable: reading is const.
  mutable std::vector<ContactPair> began_;
  std::vector<ContactPair> ended_;
  mutable std::vector<ContactPair> current_;  // began + ongoing, sorted
  std::vector<ContactPair> previous_;         // the last update's
  mutable std::vector<ContactPoint> points_;
  std::vector<ContactPoint> previous_points_;

  // ongoing() is made from current_ when first asked for after an update: a
  // pile's pairs are nearly all ongoing (1,000 boxes: about 1,000 pairs a
  // step, 2 of them new), and most readers read touching().
  mutable std::vector<ContactPair> ongoing_;
  mutable bool ongoing_made_ = false;
  std::uint64_t step_ = 0;
  bool impulses_known_ = false;
  std::uint64_t impulses_since_ = 0;  ///< first step of the present run of known impulses

 private:
  /// This set with its present geometry made (make_pending): what every
  /// reading accessor goes through.
  const ContactSet& made() const {
    if (pending_) make_pending();
    return *this;
  }
  mutable bool pending_ = false;       // the present update's geometry is deferred, not yet made
  bool previous_pending_ = false;      // the same, of the update before (abandon_update)
  bool readers_ = false;               // add_reader()
  std::vector<ContactPoint> scratch_;  // the began pairs' points at publish (discarded)
};

}  // namespace alloy
