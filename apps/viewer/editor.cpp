#include "apps/viewer/editor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

namespace alloy::viewer {

namespace {

/// Runs an edit; any exception becomes a refusal with its message.
template <class F>
EditResult guarded(F&& f) {
  try {
    return f();
  } catch (const std::exception& e) {
    return EditResult::refused(e.what());
  }
}

}  // namespace

void Editor::attach(World* world) {
  world_ = world;
  held_.clear();
  turn_ = 0;
}

bool Editor::has(ObjectId id, const char* prop) const {
  const auto pid = world_->properties().find(prop);
  return pid && world_->store().has(id, *pid);
}

ObjectId Editor::pick(Vec2 point, double margin) const {
  if (!world_) return {};
  ObjectId best;
  bool best_static = true;
  double best_area = 0;
  for (const Part2D& p : read_parts(*world_)) {
    if (!contains(p, point, margin)) continue;
    const double a = area(p);
    const bool better =
        !best || (best_static && !p.is_static) || (best_static == p.is_static && a < best_area);
    if (better) {
      best = p.id;
      best_static = p.is_static;
      best_area = a;
    }
  }
  return best;
}

std::vector<ObjectId> Editor::joined_group(ObjectId part) const {
  std::vector<ObjectId> group{part};
  const PropertyStore& store = world_->store();
  const auto joint = world_->properties().find("joint");
  if (!joint) return group;
  std::set<ObjectId> in{part};
  // Grow until no joint adds a part: kit scenes have a handful of joints.
  for (bool grew = true; grew;) {
    grew = false;
    for (const ObjectId j : carriers(store, *joint)) {
      const auto a = world_->value<ObjectId>(j, "body_a");
      const auto b = world_->value<ObjectId>(j, "body_b");
      const bool has_a = a && store.alive(*a), has_b = b && store.alive(*b);
      const bool touches = (has_a && in.count(*a)) || (has_b && in.count(*b));
      if (!touches) continue;
      for (auto o : {a, b})
        if (o && store.alive(*o) && !in.count(*o)) {
          in.insert(*o);
          group.push_back(*o);
          grew = true;
        }
    }
  }
  return group;
}

EditResult Editor::grab(ObjectId part, Vec2 at) {
  if (!world_ || !world_->store().alive(part))
    return EditResult::refused("nothing to pick up there");
  const auto p0 = read_part(*world_, part);
  if (!p0) return EditResult::refused(world_->describe(part) + " is not a part that can be moved");
  held_.clear();
  turn_ = 0;
  grab_point_ = target_ = at;
  const std::vector<ObjectId> group = joined_group(part);
  const std::set<ObjectId> members(group.begin(), group.end());
  for (ObjectId id : group) {
    const auto p = read_part(*world_, id);
    if (!p) continue;
    const double z = world_->value<Vec3>(id, "position").value_or(Vec3{}).z;
    held_.push_back({id, p->centre - at, p->angle, z, false, has(id, "mass") && !p->is_static});
  }
  // The joints among them (and those that pin them to the play area) move too.
  if (const auto joint = world_->properties().find("joint")) {
    const PropertyStore& store = world_->store();
    for (const ObjectId j : carriers(store, *joint)) {
      const auto a = world_->value<ObjectId>(j, "body_a");
      const auto anchor = world_->value<Vec3>(j, "anchor");
      if (!a || !members.count(*a) || !anchor) continue;
      held_.push_back({j, xy(*anchor) - at, 0, anchor->z, true, false});
    }
  }
  return {};
}

void Editor::place(const std::vector<Held>& group, Vec2 hand, double turn) {
  const auto position = world_->properties().id("position");
  for (const Held& h : group) {
    if (!world_->store().alive(h.id)) continue;
    const Vec2 c = hand + viewer::rotate(h.offset, turn);
    if (h.is_joint) {
      world_->set(h.id, "anchor", Vec3{c.x, c.y, h.z});
      continue;
    }
    world_->set(h.id, position, Vec3{c.x, c.y, h.z});
    world_->set(h.id, "orientation", Quat::from_angle_z(h.angle + turn));
    if (h.moving) {
      world_->set(h.id, "velocity", Vec3{});
      world_->set(h.id, "angular_velocity", Vec3{});
    }
  }
}

void Editor::hold() {
  if (!carrying() || !world_) return;
  // A part destroyed while held (a mod, a reload) ends the carry quietly.
  if (!world_->store().alive(held_.front().id)) {
    held_.clear();
    return;
  }
  try {
    place(held_, target_, turn_);
  } catch (const std::exception&) {
    held_.clear();  // a refused edit (a non-finite hand) drops the part where it was
  }
}

double Editor::worst_overlap(const std::vector<ObjectId>& group, std::string* with) const {
  const std::set<ObjectId> members(group.begin(), group.end());
  std::vector<Part2D> mine, others;
  for (const Part2D& p : read_parts(*world_)) (members.count(p.id) ? mine : others).push_back(p);
  double worst = 0;
  for (const Part2D& a : mine)
    for (const Part2D& b : others) {
      const double d = overlap_depth(a, b);
      if (d > worst) {
        worst = d;
        if (with) *with = world_->describe(b.id);
      }
    }
  return worst;
}

EditResult Editor::move_out(const std::vector<Held>& group, Vec2 hand, double turn,
                            Vec2 fallback_hand, double fallback_turn) {
  std::vector<ObjectId> ids;
  for (const Held& h : group)
    if (!h.is_joint) ids.push_back(h.id);
  std::string inside;
  if (worst_overlap(ids, &inside) <= kOverlapTolerance) return {};
  // Nearest free place, where "near" counts a way up as shorter than a way
  // sideways and that as shorter than a way down: a part dropped into a floor
  // comes to lie on it, not under it.
  struct Candidate {
    double cost, r;
    Vec2 offset;
  };
  std::vector<Candidate> candidates;
  constexpr int kDirections = 24;
  for (double r = 0.0025; r <= 1.0; r += 0.0025)
    for (int k = 0; k < kDirections; ++k) {
      const double a = 2 * std::numbers::pi * k / kDirections;
      const Vec2 u{std::cos(a), std::sin(a)};
      candidates.push_back({r * (2 - u.y), r, u * r});
    }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  for (const Candidate& c : candidates) {
    place(group, hand + c.offset, turn);
    if (worst_overlap(ids, nullptr) <= kOverlapTolerance) {
      char cm[32];
      std::snprintf(cm, sizeof cm, "%.1f cm", c.r * 100);
      return {true, world_->describe(ids.front()) + " was dropped inside " + inside + ": moved " +
                        cm + " to where it fits"};
    }
  }
  place(group, fallback_hand, fallback_turn);
  return {true, world_->describe(ids.front()) + " was dropped inside " + inside +
                    " and there is no free place nearby: put back where it was"};
}

EditResult Editor::drop() {
  if (!carrying()) return {};
  return guarded([&] {
    place(held_, target_, turn_);
    std::vector<Held> group = std::move(held_);
    held_.clear();
    const double turn = turn_;
    turn_ = 0;
    return move_out(group, target_, turn, grab_point_, 0);
  });
}

EditResult Editor::settle(ObjectId part) {
  if (!world_ || !world_->store().alive(part)) return EditResult::refused("no such part");
  return guarded([&] {
    const auto p = read_part(*world_, part);
    if (!p) return EditResult{};
    EditResult r = grab(part, p->centre);
    if (!r.ok) return r;
    std::vector<Held> group = std::move(held_);
    held_.clear();
    return move_out(group, p->centre, 0, p->centre, 0);
  });
}

EditResult Editor::rotate(ObjectId part, double radians) {
  return guarded([&] {
    const auto p = read_part(*world_, part);
    if (!p) return EditResult::refused("nothing to turn there");
    EditResult r = grab(part, p->centre);
    if (!r.ok) return r;
    turn(radians);
    return drop();
  });
}

EditResult Editor::set_pinned(ObjectId part, bool pinned) {
  return guarded([&] {
    const auto p = read_part(*world_, part);
    if (!p) return EditResult::refused("nothing to pin there");
    if (p->is_static)
      return EditResult::refused(world_->describe(part) + " is fixed already (static)");
    if (!has(part, "mass") && !has(part, "density"))
      return EditResult::refused(world_->describe(part) + " has no mass: it does not move anyway");
    world_->set(part, "pinned", pinned);
    if (pinned) {
      world_->set(part, "velocity", Vec3{});
      world_->set(part, "angular_velocity", Vec3{});
    }
    return EditResult{true,
                      world_->describe(part) + (pinned ? " pinned to the board" : " unpinned")};
  });
}

EditResult Editor::toggle_pin(ObjectId part) {
  const bool pinned = world_ && world_->value<bool>(part, "pinned").value_or(false);
  return set_pinned(part, !pinned);
}

bool Editor::electrical(ObjectId id) const {
  if (has(id, "wire_from") || has(id, "wire_to")) return false;
  return has(id, "emf") || has(id, "inductance") || has(id, "capacitance") ||
         has(id, "switch_closed") || world_->value<bool>(id, "conductive").value_or(false);
}

bool Editor::two_terminal(ObjectId id) const {
  return has(id, "emf") || has(id, "inductance") || has(id, "capacitance") ||
         has(id, "switch_closed") ||
         (world_->value<bool>(id, "conductive").value_or(false) && has(id, "resistance"));
}

std::string Editor::unique_name(const std::string& base) const {
  if (!world_->find(base)) return base;
  for (int n = 2;; ++n) {
    std::string name = base + "_" + std::to_string(n);
    if (!world_->find(name)) return name;
  }
}

EditResult Editor::connect_wire(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b) {
  if (!world_) return EditResult::refused("no world");
  const PropertyStore& store = world_->store();
  if (!store.alive(a) || !store.alive(b))
    return EditResult::refused("a wire needs a part at each end");
  if (a == b)
    return EditResult::refused("a wire from " + world_->describe(a) +
                               " to itself joins nothing: not made");
  for (ObjectId id : {a, b})
    if (!electrical(id))
      return EditResult::refused(
          world_->describe(id) +
          " does not conduct (a wire ends on a battery, a coil or a conductive part)");
  if (!world_->properties().find("wire_from"))
    return EditResult::refused("no electricity plugin is registered: wires cannot be made");
  return guarded([&] {
    auto terminal = [&](ObjectId id, Vec2 at) -> std::int64_t {
      if (!two_terminal(id)) return 0;
      const auto p = read_part(*world_, id);
      return p && p->to_local(at).x > 0 ? 1 : 0;
    };
    const ObjectId w = world_->create(unique_name("wire"));
    try {
      world_->set(w, "wire_from", a);
      world_->set(w, "wire_to", b);
      if (two_terminal(a)) world_->set(w, "wire_from_terminal", terminal(a, at_a));
      if (two_terminal(b)) world_->set(w, "wire_to_terminal", terminal(b, at_b));
    } catch (...) {
      world_->destroy(w);
      throw;
    }
    return EditResult{true, "wired " + world_->describe(a) + " to " + world_->describe(b)};
  });
}

EditResult Editor::remove(ObjectId part) {
  if (!world_ || !world_->store().alive(part))
    return EditResult::refused("nothing to remove there");
  return guarded([&] {
    const std::string name = world_->describe(part);
    if (carrying())
      for (const Held& h : held_)
        if (h.id == part) held_.clear();
    // Joints and wires that hold it go with it; any other reference is dropped,
    // so that no stale id is left for a resolver to trip on.
    const PropertyStore& store = world_->store();
    const PropertyRegistry& reg = world_->properties();
    std::vector<ObjectId> doomed;
    std::vector<std::pair<ObjectId, PropertyId>> cut;
    for (std::uint32_t s = 0; s < store.slot_count(); ++s) {
      const ObjectId o = store.id_at(s);
      if (!o || o == part) continue;
      for (PropertyId p = 0; p < reg.size(); ++p) {
        const PropertyKind kind = reg.def(p).kind;
        if ((kind != PropertyKind::Ref && kind != PropertyKind::RefList) || !store.has(o, p))
          continue;
        const PropertyValue v = store.get(o, p);
        bool refers = false;
        if (const ObjectId* r = std::get_if<ObjectId>(&v)) refers = *r == part;
        if (const RefList* l = std::get_if<RefList>(&v))
          refers = std::find(l->begin(), l->end(), part) != l->end();
        if (!refers) continue;
        if (has(o, "joint") || has(o, "wire_from") || has(o, "wire_to")) {
          doomed.push_back(o);
          break;
        }
        cut.push_back({o, p});
      }
    }
    for (auto [o, p] : cut) {
      const PropertyValue v = store.get(o, p);
      if (const RefList* l = std::get_if<RefList>(&v)) {
        RefList kept;
        for (ObjectId r : *l)
          if (r != part) kept.push_back(r);
        world_->set(o, p, kept);
      } else {
        world_->remove(o, reg.def(p).name);
      }
    }
    for (ObjectId o : doomed) world_->destroy(o);
    world_->destroy(part);
    return EditResult{true, "removed " + name +
                                (doomed.empty() ? ""
                                                : " and " + std::to_string(doomed.size()) +
                                                      " joint(s) or wire(s)")};
  });
}

}  // namespace alloy::viewer
