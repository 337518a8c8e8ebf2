#include "resolvers/electricity/electricity_from_collisions.hpp"

#include <algorithm>
#include <string>

#include "runtime/error.hpp"

namespace alloy::electricity {

ElectricityFromCollisions::ElectricityFromCollisions(ElectricityResolver& target,
                                                     const ContactSet& contacts, bool ahead)
    : target_(target), contacts_(contacts), ahead_(ahead) {}

int ElectricityFromCollisions::terminal_at(Vec3 part_position, Quat part_orientation, Vec3 point) {
  const Quat inverse{part_orientation.w, -part_orientation.x, -part_orientation.y,
                     -part_orientation.z};
  return rotate(inverse, point - part_position).x > 0 ? 1 : 0;
}

bool ElectricityFromCollisions::save_state(StateWriter& out) const {
  std::vector<ObjectId> ids;  // a, b of each pair
  for (const auto& [a, b] : before_) ids.push_back(a), ids.push_back(b);
  out.put_vector(ids);
  if (ahead_) {  // the predicted pairs waiting for their report (none without ahead)
    std::vector<ObjectId> waiting;
    std::vector<std::int32_t> waited;
    for (const auto& [pair, n] : waiting_before_)
      waiting.push_back(pair.first), waiting.push_back(pair.second), waited.push_back(n);
    out.put_vector(waiting);
    out.put_vector(waited);
  }
  return true;
}

void ElectricityFromCollisions::restore_state(StateReader& in) {
  const auto ids = in.get_vector<ObjectId>();
  connected_.clear();
  for (std::size_t i = 0; i + 1 < ids.size(); i += 2) connected_.emplace_back(ids[i], ids[i + 1]);
  before_ = connected_;
  waiting_.clear();
  if (in.remaining() > 0) {  // saved with ahead on
    const auto waiting = in.get_vector<ObjectId>();
    const auto waited = in.get_vector<std::int32_t>();
    auto damaged = [&](const std::string& what) {
      return InputError("the saved state of stage '" + in.stage() + "' is damaged: " + what);
    };
    if (waiting.size() != 2 * waited.size())
      throw damaged("its waiting pairs and their counts differ");
    for (std::size_t i = 0; i < waited.size(); ++i) {
      // A count is the updates a pair has waited for its report: at most a
      // contact set's report lag, never negative (a damaged one would hold a
      // circuit closed through parts apart for as long as it says).
      if (waited[i] < 0 || waited[i] > kMaxReportLag)
        throw damaged("a waiting pair's count " + std::to_string(waited[i]) + " is not 0 to " +
                      std::to_string(kMaxReportLag));
      waiting_.push_back({{waiting[2 * i], waiting[2 * i + 1]}, waited[i]});
    }
    std::sort(waiting_.begin(), waiting_.end());
  }
  waiting_before_ = waiting_;
}

void ElectricityFromCollisions::apply(const WorldView& world) {
  before_ = connected_;
  waiting_before_ = waiting_;
  const auto conductive = conductive_.column<std::uint8_t>(world);
  const auto position = position_.column<Vec3>(world);
  const auto orientation = orientation_.column<Quat>(world);
  auto conducts = [&](ObjectId o) { return conductive.has(o.index) && conductive[o.index] != 0; };

  // The touching pairs of two conductive parts, in (a, b) order: began and
  // ongoing are each sorted, so merge them.
  std::vector<const ContactPair*> touching;
  const auto began = contacts_.began(), ongoing = contacts_.ongoing();
  touching.reserve(began.size() + ongoing.size());
  std::size_t i = 0, j = 0;
  while (i < began.size() || j < ongoing.size()) {
    const bool take_began =
        j == ongoing.size() ||
        (i < began.size() && pair_less(began[i].a, began[i].b, ongoing[j].a, ongoing[j].b));
    const ContactPair& p = take_began ? began[i++] : ongoing[j++];
    if (conducts(p.a) && conducts(p.b)) touching.push_back(&p);
  }

  auto terminal_of = [&](ObjectId part, Vec3 point) {
    if (!position.has(part.index)) return 0;
    return terminal_at(position[part.index], orientation.value_or(part.index, Quat{}), point);
  };
  auto terminal = [&](ObjectId part, const ContactPair& pair) {
    const auto points = contacts_.points(pair);
    if (points.empty()) return 0;
    Vec3 mean{};
    for (const auto& pt : points) mean += pt.position;
    return terminal_of(part, mean / double(points.size()));
  };

  // What should be connected over the next step, sorted by (a, b): the pairs
  // touching now; with ahead_, also those predicted to touch within half a
  // step (their terminals from the predicted points).
  struct Want {
    ObjectId a, b;
    int terminal_a, terminal_b;
  };
  std::vector<Want> want;
  want.reserve(touching.size());
  if (!ahead_) {
    for (const ContactPair* p : touching)
      want.push_back({p->a, p->b, terminal(p->a, *p), terminal(p->b, *p)});
  } else {
    conductors_.clear();
    for (const std::uint32_t slot : conductive.members())
      if (conductive[slot] != 0 && position.has(slot))
        conductors_.push_back(world.store().id_at(slot));
    std::sort(conductors_.begin(), conductors_.end());
    // Half of the step the connection will act over: the world's, or the
    // electricity's own when it runs every n-th step (this apply then feeds
    // its next advance, n steps long).
    const double span = world.dt() * world.every(kResolverName);
    const auto soon = contacts_.touching_ahead(world, conductors_, 0.5 * span);
    // A predicted pair waits for the set to report it: a set that reports a
    // step late (Box2D) would otherwise see it neither touching nor predicted
    // (a part that bounced in that step) and open the circuit for a step
    // between the prediction and the report (adv21). Held report_lag()
    // updates past the prediction, then let go if still unreported.
    const int lag = std::clamp(contacts_.report_lag(), 0, kMaxReportLag);
    using Key = std::pair<ObjectId, ObjectId>;
    std::vector<Key> touching_keys, soon_keys;
    for (const ContactPair* p : touching) touching_keys.push_back({p->a, p->b});
    for (const PredictedTouch& q : soon) soon_keys.push_back({q.a, q.b});
    std::vector<std::pair<Key, std::int32_t>> waiting;
    for (const Key& key : soon_keys) waiting.push_back({key, 0});
    std::vector<Key> held;
    for (const auto& [key, n] : waiting_) {
      if (std::binary_search(touching_keys.begin(), touching_keys.end(), key)) continue;
      const bool again = std::binary_search(soon_keys.begin(), soon_keys.end(), key);
      if (again || n >= lag) continue;
      held.push_back(key);
      waiting.push_back({key, n + 1});
    }
    std::sort(waiting.begin(), waiting.end());
    waiting_ = std::move(waiting);
    std::size_t t = 0, f = 0;
    while (t < touching.size() || f < soon.size()) {
      const ContactPair* p = t < touching.size() ? touching[t] : nullptr;
      const PredictedTouch* q = f < soon.size() ? &soon[f] : nullptr;
      if (p && q && p->a == q->a && p->b == q->b) {
        want.push_back({p->a, p->b, terminal(p->a, *p), terminal(p->b, *p)});
        ++t, ++f;
      } else if (p && (!q || pair_less(p->a, p->b, q->a, q->b))) {
        want.push_back({p->a, p->b, terminal(p->a, *p), terminal(p->b, *p)});
        ++t;
      } else {
        want.push_back({q->a, q->b, terminal_of(q->a, q->point), terminal_of(q->b, q->point)});
        ++f;
      }
    }
    // Held pairs are connected already: their terminals are not sent again.
    for (const auto& key : held) want.push_back({key.first, key.second, 0, 0});
    std::sort(want.begin(), want.end(),
              [](const Want& x, const Want& y) { return pair_less(x.a, x.b, y.a, y.b); });
  }

  // Compare with what we connected before; both lists are sorted by (a, b).
  std::vector<std::pair<ObjectId, ObjectId>> now;
  now.reserve(want.size());
  std::size_t k = 0;
  for (const Want& w : want) {
    const std::pair<ObjectId, ObjectId> key{w.a, w.b};
    for (; k < connected_.size() && connected_[k] < key; ++k)
      target_.disconnect(connected_[k].first, connected_[k].second);
    if (k < connected_.size() && connected_[k] == key)
      ++k;  // still touching: nothing to say
    else
      target_.connect(w.a, w.b, w.terminal_a, w.terminal_b);
    now.push_back(key);
  }
  for (; k < connected_.size(); ++k) target_.disconnect(connected_[k].first, connected_[k].second);
  connected_ = std::move(now);
}

void register_electricity_from_collisions(PluginRegistry& registry) {
  registry.add({
      .info = {.name = kFromCollisionsName,
               .kind = StageKind::Interaction,
               .reads = {prop::kConductive, "position", "orientation"},
               .derived = {"collisions"},
               .target = kResolverName,
               .doc = "conductive parts that touch are connected; parted, disconnected"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        const PluginSettings& s = ctx.settings();
        s.check_known(kFromCollisionsName, {"ahead"});
        return std::make_unique<ElectricityFromCollisions>(ctx.target<ElectricityResolver>(),
                                                           ctx.dependency<ContactSet>("collisions"),
                                                           s.boolean("ahead", false));
      },
  });
}

}  // namespace alloy::electricity
