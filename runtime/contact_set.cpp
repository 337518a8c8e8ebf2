#include "runtime/contact_set.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "runtime/world.hpp"

namespace alloy {

namespace {
bool by_pair(const ContactPair& x, const ContactPair& y) {
  return pair_less(x.a, x.b, y.a, y.b);
}
}  // namespace

const ContactPair* ContactSet::find(ObjectId a, ObjectId b) const {
  if (b < a) std::swap(a, b);
  ContactPair key;
  key.a = a, key.b = b;
  const auto& current = made().current_;
  auto it = std::lower_bound(current.begin(), current.end(), key, by_pair);
  return it != current.end() && it->a == a && it->b == b ? &*it : nullptr;
}

void ContactSet::make_geometry(std::span<ContactPair>, std::vector<ContactPoint>&) const {
  throw std::logic_error("a contact set deferred its geometry but cannot make it");
}

void ContactSet::make_pending() const {
  if (!pending_) return;
  if (!geometry_available())
    throw std::logic_error(
        "contacts were read after their engine advanced without the contact set updating (a "
        "contact set must update after every advance of its engine: give it the engine's "
        "`every`)");
  pending_ = false;
  points_.clear();
  make_geometry(current_, points_);
  // began_ holds copies of some of current_'s pairs, made at publish with the
  // same geometry but points of their own: point them into points_.
  std::size_t i = 0;
  for (ContactPair& p : began_) {
    while (by_pair(current_[i], p)) ++i;
    p.first = current_[i].first, p.count = current_[i].count;
  }
}

std::span<const ContactPair> ContactSet::ongoing() const {
  made();
  if (!ongoing_made_) {
    // current_ without began_ (both sorted by pair, began_ a subsequence of it).
    ongoing_.clear();
    std::size_t b = 0;
    for (const ContactPair& p : current_) {
      if (b < began_.size() && began_[b].a == p.a && began_[b].b == p.b)
        ++b;
      else
        ongoing_.push_back(p);
    }
    ongoing_made_ = true;
  }
  return ongoing_;
}

void ContactSet::carry_over(const ContactSet& from) {
  from.make_pending();
  pending_ = previous_pending_ = false;
  current_ = from.current_;
  points_ = from.points_;
  previous_.clear(), previous_points_.clear();
  clear_changes();
  step_ = from.step_;
}

void ContactSet::restore_lists(std::vector<ContactPair> pairs, std::vector<ContactPoint> points) {
  pending_ = previous_pending_ = false;
  current_ = std::move(pairs);
  points_ = std::move(points);
  previous_.clear(), previous_points_.clear();
  clear_changes();
}

void ContactSet::begin_update() {
  // The present lists become the previous ones as they are: an update whose
  // geometry nobody read leaves its pairs' depth and speed 0 (the header).
  std::swap(previous_, current_);
  current_.clear();
  std::swap(points_, previous_points_);
  points_.clear();
  previous_pending_ = pending_;
  pending_ = false;
}

void ContactSet::abandon_update() {
  std::swap(previous_, current_);
  std::swap(points_, previous_points_);
  pending_ = previous_pending_;
  previous_pending_ = false;
}

void ContactSet::clear_changes() {
  began_.clear(), ended_.clear();
  ongoing_.clear(), ongoing_made_ = false;
}

void ContactSet::publish(const WorldView& world, std::span<const PairImpulse> impulses,
                         bool computed, std::uint64_t step) {
  // The rigid body's impulses are for the pairs it was given, i.e. those that
  // touched at the previous update: merge them in by pair. Empty when nobody
  // demanded them.
  if (computed && !impulses_known_) impulses_since_ = step;
  impulses_known_ = computed;
  // A merge cursor over the impulses, for one ascending pass over pairs.
  auto impulse_cursor = [&] {
    return [&, k = std::size_t(0)](ContactPair& p) mutable {
      while (k < impulses.size() && pair_less(impulses[k].a, impulses[k].b, p.a, p.b)) ++k;
      if (k < impulses.size() && impulses[k].a == p.a && impulses[k].b == p.b) {
        p.impulse = impulses[k].impulse;
        p.normal_impulse = impulses[k].normal_impulse;
        p.total_impulse += p.normal_impulse;
      }
    };
  };
  auto take_impulse = impulse_cursor();

  // began / ongoing / ended by a merge of two sorted lists (ongoing pairs stay
  // in current_ only: ongoing() picks them out when asked).
  clear_changes();
  std::size_t i = 0, j = 0;
  while (i < current_.size() || j < previous_.size()) {
    const bool take_new =
        j == previous_.size() || (i < current_.size() && !by_pair(previous_[j], current_[i]));
    const bool take_old =
        i == current_.size() || (j < previous_.size() && !by_pair(current_[i], previous_[j]));
    if (take_new && take_old) {  // the same pair: ongoing
      ContactPair& p = current_[i++];
      p.began_step = previous_[j].began_step;
      p.total_impulse = previous_[j++].total_impulse;
      take_impulse(p);
    } else if (take_new) {
      ContactPair& p = current_[i++];
      p.began_step = step;
      take_impulse(p);
      began_.push_back(p);
    } else {
      ContactPair p = previous_[j++];
      p.first = p.count = 0;
      p.impulse = {};
      p.normal_impulse = 0;
      ended_.push_back(p);
    }
  }
  // Impulses of ended pairs (their last push apart), in a second ordered pass.
  auto take_ended = impulse_cursor();
  for (ContactPair& p : ended_) take_ended(p);
  // Deferred geometry: the began pairs' now (their events carry it), every
  // pair's at the first read, or now if a stage declared it reads the set.
  if (pending_) {
    scratch_.clear();
    make_geometry(began_, scratch_);
    if (readers_) make_pending();
  }

  for (const ContactPair& p : began_) {
    Event e;
    e.type = "contact_began";
    e.a = p.a, e.b = p.b;
    e.values = {{"speed", p.normal_speed}, {"depth", p.depth}};
    world.emit(std::move(e));
  }
  for (const ContactPair& p : ended_) {
    Event e;
    e.type = "contact_ended";
    e.a = p.a, e.b = p.b;
    // No impulse rather than a wrong one when it was not computed throughout.
    const double duration = double(step - p.began_step) * world.dt();
    if (total_known(p))
      e.values = {{"impulse", p.total_impulse}, {"duration", duration}};
    else
      e.values = {{"duration", duration}};
    world.emit(std::move(e));
  }
  step_ = step;
}

}  // namespace alloy
