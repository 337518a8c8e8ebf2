#include "resolvers/electricity/electricity_from_collisions.hpp"

#include <algorithm>

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
  return true;
}

void ElectricityFromCollisions::restore_state(StateReader& in) {
  const auto ids = in.get_vector<ObjectId>();
  connected_.clear();
  for (std::size_t i = 0; i + 1 < ids.size(); i += 2) connected_.emplace_back(ids[i], ids[i + 1]);
  before_ = connected_;
}

void ElectricityFromCollisions::apply(const WorldView& world) {
  before_ = connected_;
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
    const auto soon = contacts_.touching_ahead(world, conductors_, 0.5 * world.dt());
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
