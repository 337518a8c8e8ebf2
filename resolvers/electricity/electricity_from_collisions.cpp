#include "resolvers/electricity/electricity_from_collisions.hpp"

#include <algorithm>

namespace alloy::electricity {

ElectricityFromCollisions::ElectricityFromCollisions(ElectricityResolver& target,
                                                     const ContactSet& contacts)
    : target_(target), contacts_(contacts) {}

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

  auto terminal = [&](ObjectId part, const ContactPair& pair) {
    const auto points = contacts_.points(pair);
    if (points.empty() || !position.has(part.index)) return 0;
    Vec3 mean{};
    for (const auto& pt : points) mean += pt.position;
    mean = mean / double(points.size());
    return terminal_at(position[part.index], orientation.value_or(part.index, Quat{}), mean);
  };

  // Compare with what we connected before; both lists are sorted by (a, b).
  std::vector<std::pair<ObjectId, ObjectId>> now;
  now.reserve(touching.size());
  std::size_t k = 0;
  for (const ContactPair* p : touching) {
    const std::pair<ObjectId, ObjectId> key{p->a, p->b};
    for (; k < connected_.size() && connected_[k] < key; ++k)
      target_.disconnect(connected_[k].first, connected_[k].second);
    if (k < connected_.size() && connected_[k] == key)
      ++k;  // still touching: nothing to say
    else
      target_.connect(p->a, p->b, terminal(p->a, *p), terminal(p->b, *p));
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
        ctx.settings().check_known(kFromCollisionsName, {});
        return std::make_unique<ElectricityFromCollisions>(
            ctx.target<ElectricityResolver>(), ctx.dependency<ContactSet>("collisions"));
      },
  });
}

}  // namespace alloy::electricity
