#include "apps/viewer/editor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "runtime/error.hpp"

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
  return grab_all({part}, at);
}

EditResult Editor::grab_all(const std::vector<ObjectId>& parts, Vec2 at) {
  if (parts.empty() || !world_ || !world_->store().alive(parts.front()))
    return EditResult::refused("nothing to pick up there");
  const auto p0 = read_part(*world_, parts.front());
  if (!p0)
    return EditResult::refused(world_->describe(parts.front()) +
                               " is not a part that can be moved");
  held_.clear();
  turn_ = 0;
  grab_point_ = target_ = at;
  // Each part with what is joined to it, once, the part the hand took first.
  std::vector<ObjectId> group;
  std::set<ObjectId> members;
  for (ObjectId part : parts) {
    if (!world_->store().alive(part) || members.count(part)) continue;
    for (ObjectId id : joined_group(part))
      if (members.insert(id).second) group.push_back(id);
  }
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

Vec2 Editor::snapped(Vec2 hand, double grid, double reach) const {
  if (!carrying() || !world_) return hand;
  const Held& h = held_.front();
  const auto p = read_part(*world_, h.id);
  if (!p) return hand;
  const Vec2 centre = hand + viewer::rotate(h.offset, turn_);
  const double angle = h.angle + turn_;
  const Vec2 half = viewer::rotate({p->half_extent_x(), 0}, angle);
  // Ends first: the nearest pair of (an end of what is carried, an end of a
  // part that is not held) within reach.
  std::set<ObjectId> held;
  for (const Held& o : held_) held.insert(o.id);
  double best = reach;
  Vec2 shift;
  bool found = false;
  for (const Part2D& other : read_parts(*world_)) {
    if (held.count(other.id)) continue;
    const Vec2 oh = viewer::rotate({other.half_extent_x(), 0}, other.angle);
    for (const Vec2 mine : {centre - half, centre + half})
      for (const Vec2 theirs : {other.centre - oh, other.centre + oh}) {
        const double d = length(theirs - mine);
        if (d < best) best = d, shift = theirs - mine, found = true;
      }
  }
  if (found) return hand + shift;
  if (!(grid > 0)) return hand;
  const Vec2 on_grid{std::round(centre.x / grid) * grid, std::round(centre.y / grid) * grid};
  return hand + (on_grid - centre);
}

std::vector<ObjectId> Editor::parts_in(Vec2 a, Vec2 b) const {
  std::vector<ObjectId> out;
  if (!world_) return out;
  const double x0 = std::min(a.x, b.x), x1 = std::max(a.x, b.x);
  const double y0 = std::min(a.y, b.y), y1 = std::max(a.y, b.y);
  for (const Part2D& p : read_parts(*world_))
    if (!p.is_static && p.centre.x >= x0 && p.centre.x <= x1 && p.centre.y >= y0 &&
        p.centre.y <= y1)
      out.push_back(p.id);
  return out;
}

EditResult Editor::remove_all(const std::vector<ObjectId>& parts) {
  std::size_t removed = 0;
  for (ObjectId part : parts) {
    if (!world_ || !world_->store().alive(part)) continue;  // gone with an earlier one
    const EditResult r = remove(part);
    if (!r.ok) return r;
    ++removed;
  }
  if (removed == 0) return EditResult::refused("nothing to remove");
  return {true, "removed " + std::to_string(removed) + " parts"};
}

Editor::Clipboard Editor::copy(const std::vector<ObjectId>& parts) const {
  Clipboard clip;
  if (!world_) return clip;
  const PropertyStore& store = world_->store();
  const PropertyRegistry& reg = world_->properties();
  std::set<ObjectId> chosen;
  Vec2 sum;
  for (ObjectId id : parts) {
    const auto p = read_part(*world_, id);
    if (!p || !chosen.insert(id).second) continue;
    clip.from.push_back(id);
    sum = sum + p->centre;
  }
  clip.parts = clip.from.size();
  if (clip.parts == 0) return clip;
  clip.centre = sum * (1.0 / double(clip.parts));
  // Every other object whose references (at least one) all point at copied
  // parts: the joints, wires and springs among them.
  for (std::uint32_t s = 0; s < store.slot_count(); ++s) {
    const ObjectId o = store.id_at(s);
    if (!o || chosen.count(o)) continue;
    bool any = false, all = true;
    for (PropertyId p = 0; p < reg.size() && all; ++p) {
      if (!store.has(o, p)) continue;
      const PropertyValue v = store.get(o, p);
      auto see = [&](ObjectId r) {
        if (r.is_null()) return;
        any = true;
        if (!chosen.count(r)) all = false;
      };
      if (const ObjectId* r = std::get_if<ObjectId>(&v)) see(*r);
      if (const RefList* l = std::get_if<RefList>(&v))
        for (ObjectId r : *l) see(r);
    }
    if (any && all) clip.from.push_back(o);
  }
  const PropertyId name_id = reg.id("name");
  for (ObjectId id : clip.from) {
    Clipboard::Object obj;
    for (PropertyId p = 0; p < reg.size(); ++p) {
      if (!store.has(id, p)) continue;
      if (p == name_id)
        obj.name = std::get<std::string>(store.get(id, p));
      else
        obj.values.emplace_back(p, store.get(id, p));
    }
    clip.objects.push_back(std::move(obj));
  }
  return clip;
}

EditResult Editor::paste(const Clipboard& clip, Vec2 offset, std::vector<ObjectId>* made) {
  if (!world_) return EditResult::refused("no world");
  if (clip.empty()) return EditResult::refused("nothing to paste: copy some parts first (Ctrl+C)");
  std::vector<ObjectId> fresh;
  const EditResult r = guarded([&] {
    const PropertyRegistry& reg = world_->properties();
    const auto position = reg.find("position"), anchor = reg.find("anchor");
    const auto spring_b = reg.find("spring_b"), spring_anchor_b = reg.find("spring_anchor_b");
    std::map<ObjectId, ObjectId> to_new;
    for (std::size_t i = 0; i < clip.objects.size(); ++i) {
      const std::string& name = clip.objects[i].name;
      // bar_2 copied is bar_3 (the next free), not bar_2_2.
      std::string base = name;
      if (const auto cut = base.find_last_of('_');
          cut != std::string::npos && cut + 1 < base.size() &&
          base.find_first_not_of("0123456789", cut + 1) == std::string::npos)
        base.erase(cut);
      fresh.push_back(world_->create(name.empty() ? "" : unique_name(base)));
      to_new[clip.from[i]] = fresh.back();
    }
    auto remap = [&](ObjectId r) {
      const auto it = to_new.find(r);
      return it == to_new.end() ? ObjectId{} : it->second;
    };
    const Vec3 by{offset.x, offset.y, 0};
    for (std::size_t i = 0; i < clip.objects.size(); ++i) {
      const Clipboard::Object& obj = clip.objects[i];
      // A spring with no part b has a point of the board for that end: it moves too.
      bool board_end = true;
      for (const auto& [p, v] : obj.values)
        if (spring_b && p == *spring_b && !std::get<ObjectId>(v).is_null()) board_end = false;
      for (const auto& [p, v] : obj.values) {
        PropertyValue value = v;
        if (ObjectId* ref = std::get_if<ObjectId>(&value)) *ref = remap(*ref);
        if (RefList* list = std::get_if<RefList>(&value))
          for (ObjectId& ref : *list) ref = remap(ref);
        const bool placed = (position && p == *position) || (anchor && p == *anchor) ||
                            (board_end && spring_anchor_b && p == *spring_anchor_b);
        if (placed) value = std::get<Vec3>(value) + by;
        world_->set(fresh[i], p, value);
      }
    }
    for (ObjectId id : fresh) world_->check(id);
    return EditResult{true, "pasted " + std::to_string(clip.parts) + " parts"};
  });
  if (!r.ok) {
    for (ObjectId id : fresh)
      if (world_->store().alive(id)) world_->destroy(id);
    return r;
  }
  if (made) made->assign(fresh.begin(), fresh.begin() + std::ptrdiff_t(clip.parts));
  return r;
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
        if (has(o, "joint") || has(o, "wire_from") || has(o, "wire_to") ||
            has(o, "spring_stiffness")) {
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
                                                      " joint(s), spring(s) or wire(s)")};
  });
}

}  // namespace alloy::viewer

// --- joining parts ------------------------------------------------------------------

namespace alloy::viewer {

std::vector<ObjectId> Editor::pick_all(Vec2 point, double margin) const {
  std::vector<Part2D> under;
  if (!world_) return {};
  for (const Part2D& p : read_parts(*world_))
    if (contains(p, point, margin)) under.push_back(p);
  std::stable_sort(under.begin(), under.end(), [](const Part2D& a, const Part2D& b) {
    if (a.is_static != b.is_static) return !a.is_static;
    return area(a) < area(b);
  });
  std::vector<ObjectId> out;
  for (const Part2D& p : under) out.push_back(p.id);
  return out;
}

ObjectId Editor::joint_between(ObjectId a, ObjectId b) const {
  const auto joint = world_->properties().find("joint");
  if (!joint) return {};
  for (const ObjectId j : carriers(world_->store(), *joint)) {
    const ObjectId ja = world_->value<ObjectId>(j, "body_a").value_or(ObjectId{});
    const ObjectId jb = world_->value<ObjectId>(j, "body_b").value_or(ObjectId{});
    if ((ja == a && jb == b) || (ja == b && jb == a)) return j;
  }
  return {};
}

ObjectId Editor::pick_joint(Vec2 point, double margin) const {
  if (!world_) return {};
  const auto joint = world_->properties().find("joint");
  if (!joint) return {};
  ObjectId best;
  double best_d = margin;
  for (const ObjectId j : carriers(world_->store(), *joint)) {
    auto anchor = world_->value<Vec3>(j, "anchor");
    if (enum_of(j, "joint") == "fixed")  // drawn on its first part (scene_draw)
      if (const auto a = world_->value<ObjectId>(j, "body_a"); a && world_->store().alive(*a))
        anchor = world_->value<Vec3>(*a, "position");
    if (!anchor) continue;
    const double d = length(xy(*anchor) - point);
    if (d <= best_d) best = j, best_d = d;
  }
  return best;
}

ObjectId Editor::pick_spring(Vec2 point, double margin) const {
  if (!world_) return {};
  const auto k = world_->properties().find("spring_stiffness");
  if (!k) return {};
  ObjectId best;
  double best_d = margin;
  for (const ObjectId sp : carriers(world_->store(), *k))
    if (const auto ends = spring_ends(*world_, sp)) {
      // The middle 80 %: its ends lie on its parts, and a click there means the part.
      const Vec2 d = ends->b - ends->a;
      const Vec2 a = ends->a + d * 0.1, b = ends->b - d * 0.1;
      const double dist = segment_distance(point, a, b);
      if (dist <= best_d) best = sp, best_d = dist;
    }
  return best;
}

EditResult Editor::spring_between(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b, ObjectId* made) {
  if (!world_ || !world_->store().alive(a))
    return EditResult::refused("a spring starts on a part: click a part first");
  if (b && !world_->store().alive(b)) return EditResult::refused("no part at the spring's end");
  if (a == b) return EditResult::refused("a spring from a part to itself holds nothing");
  if (!world_->properties().find("spring_stiffness"))
    return EditResult::refused("no spring plugin is registered (rigid_body_from_springs)");
  const double span = length(at_b - at_a);
  if (span < 0.005)
    return EditResult::refused("the ends are too close for a spring (5 mm at least)");
  return guarded([&] {
    // Each end in its part's frame, from its centre of mass, so that it
    // moves with the part; an end on the board stays where it was clicked.
    auto local = [&](ObjectId part, Vec2 at) {
      const Vec3 c = world_->value<Vec3>(part, "position").value_or(Vec3{});
      const Quat q = world_->value<Quat>(part, "orientation").value_or(Quat{});
      const Quat inverse{q.w, -q.x, -q.y, -q.z};
      return alloy::rotate(inverse, Vec3{at.x, at.y, c.z} - c);
    };
    const std::string name = unique_name("spring");
    const ObjectId sp = world_->create(name);
    try {
      world_->set(sp, "spring_a", a);
      world_->set(sp, "spring_anchor_a", local(a, at_a));
      if (b) world_->set(sp, "spring_b", b);
      const double z = world_->value<Vec3>(a, "position").value_or(Vec3{}).z;
      world_->set(sp, "spring_anchor_b", b ? local(b, at_b) : Vec3{at_b.x, at_b.y, z});
      world_->set(sp, "spring_stiffness", kSpringStiffness);
      world_->set(sp, "spring_rest_length", span);
      world_->set(sp, "spring_damping", kSpringDamping);
      world_->check(sp);
    } catch (...) {
      world_->destroy(sp);
      throw;
    }
    if (made) *made = sp;
    char cm[32];
    std::snprintf(cm, sizeof cm, "%.1f cm", span * 100);
    return EditResult{true, "a " + std::string(cm) + " spring from " + world_->describe(a) +
                                " to " + (b ? world_->describe(b) : std::string("the board")) +
                                " (" + std::to_string(int(kSpringStiffness)) +
                                " N/m; the inspector edits it)"};
  });
}

EditResult Editor::make_joint(const char* kind, ObjectId a, ObjectId b, Vec2 at, ObjectId* made) {
  const auto joint_prop = world_->properties().find("joint");
  if (!joint_prop) return EditResult::refused("no rigid body plugin is registered: no joints");
  const PropertyDef& def = world_->properties().def(*joint_prop);
  const auto it = std::find(def.enum_values.begin(), def.enum_values.end(), kind);
  if (it == def.enum_values.end())
    return EditResult::refused(std::string("the rigid body has no '") + kind + "' joint");
  const std::string what = std::string(kind) == "hinge" ? "hinge" : "glue";
  if (const ObjectId j = joint_between(a, b))
    return EditResult::refused(world_->describe(a) + " and " +
                               (b ? world_->describe(b) : std::string("the board")) +
                               " are joined already (by " + world_->describe(j) + ")");
  const double z = world_->value<Vec3>(a, "position").value_or(Vec3{}).z;
  const ObjectId j = world_->create(unique_name(what));
  try {
    world_->set(j, "joint", EnumValue{std::int32_t(it - def.enum_values.begin())});
    world_->set(j, "body_a", a);
    if (b) world_->set(j, "body_b", b);
    // Glue's anchor is its first part's centre, as the kit makes it (the
    // rigid body does not move a fixed joint's anchor; it is drawn there).
    const Vec3 centre = world_->value<Vec3>(a, "position").value_or(Vec3{at.x, at.y, z});
    world_->set(j, "anchor", what == "hinge" ? Vec3{at.x, at.y, z} : centre);
    if (what == "hinge") world_->set(j, "axis", Vec3{0, 0, 1});
  } catch (...) {
    world_->destroy(j);
    throw;
  }
  if (made) *made = j;
  const std::string other = b ? world_->describe(b) : std::string("the board");
  return {true, (what == "hinge" ? "hinged " : "glued ") + world_->describe(a) + " to " + other};
}

EditResult Editor::hinge_at(Vec2 at, double margin, ObjectId* made) {
  if (!world_) return EditResult::refused("no world");
  return guarded([&] {
    const std::vector<ObjectId> under = pick_all(at, margin);
    if (under.empty())
      return EditResult::refused(
          "a hinge goes through a part: click on a part (where two overlap, it joins them)");
    const auto a = read_part(*world_, under[0]);
    if (a->is_static)
      return EditResult::refused(world_->describe(under[0]) +
                                 " is fixed (static): a hinge through it alone holds nothing");
    return make_joint("hinge", under[0], under.size() > 1 ? under[1] : ObjectId{}, at, made);
  });
}

EditResult Editor::glue_at(Vec2 at, double margin, ObjectId* made) {
  if (!world_) return EditResult::refused("no world");
  return guarded([&] {
    const std::vector<ObjectId> under = pick_all(at, margin);
    if (under.empty())
      return EditResult::refused("glue goes where two parts overlap or touch: click there");
    const auto a = read_part(*world_, under[0]);
    if (a->is_static)
      return EditResult::refused(world_->describe(under[0]) + " is fixed (static) already");
    return make_joint("fixed", under[0], under.size() > 1 ? under[1] : ObjectId{}, at, made);
  });
}

EditResult Editor::string_between(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b, double slack,
                                  ObjectId* made) {
  if (!world_ || !world_->store().alive(a))
    return EditResult::refused("a string starts on a part: click a part first");
  if (b && !world_->store().alive(b)) return EditResult::refused("no part at the string's end");
  if (a == b) return EditResult::refused("a string from a part to itself holds nothing");
  if (!world_->properties().find("spring_slack"))
    return EditResult::refused("no string plugin is registered (rigid_body_from_springs)");
  const double span = length(at_b - at_a);
  if (span < 0.005)
    return EditResult::refused("the ends are too close for a string (5 mm at least)");
  const double total = span * std::max(1.0, slack);
  // As stiff as the step allows on these parts, so that it barely stretches:
  // (h w)^2 = kStringFigure with w^2 = k / m, m the parts' reduced mass (a
  // fixed part counts as infinitely heavy), and a damper of a sixth of the
  // critical one for the stretch's own bounce; under the springs' limit of 1.
  auto inverse_mass = [&](ObjectId part) {
    if (!part) return 0.0;
    if (world_->value<bool>(part, "static").value_or(false) ||
        world_->value<bool>(part, "pinned").value_or(false))
      return 0.0;
    const double m = world_->value<double>(part, "mass").value_or(0);
    return m > 0 ? 1 / m : 0.0;
  };
  const double inv = inverse_mass(a) + inverse_mass(b), h = world_->dt();
  double k = kStringMaxStiffness, c = 0;
  if (inv > 0 && h > 0) {
    k = std::min(kStringMaxStiffness, kStringFigure / (h * h * inv));
    c = std::sqrt(k / inv) / 3;  // a sixth of the critical 2 sqrt(k m)
  }
  return guarded([&] {
    auto local = [&](ObjectId part, Vec2 at) {
      const Vec3 centre = world_->value<Vec3>(part, "position").value_or(Vec3{});
      const Quat q = world_->value<Quat>(part, "orientation").value_or(Quat{});
      const Quat inverse{q.w, -q.x, -q.y, -q.z};
      return alloy::rotate(inverse, Vec3{at.x, at.y, centre.z} - centre);
    };
    const ObjectId st = world_->create(unique_name("string"));
    try {
      world_->set(st, "spring_a", a);
      world_->set(st, "spring_anchor_a", local(a, at_a));
      if (b) world_->set(st, "spring_b", b);
      const double z = world_->value<Vec3>(a, "position").value_or(Vec3{}).z;
      world_->set(st, "spring_anchor_b", b ? local(b, at_b) : Vec3{at_b.x, at_b.y, z});
      world_->set(st, "spring_stiffness", k);
      world_->set(st, "spring_rest_length", total);
      world_->set(st, "spring_damping", c);
      world_->set(st, "spring_slack", true);
      world_->check(st);
    } catch (...) {
      world_->destroy(st);
      throw;
    }
    if (made) *made = st;
    char cm[32];
    std::snprintf(cm, sizeof cm, "%.1f cm", total * 100);
    return EditResult{true, "a " + std::string(cm) + " string from " + world_->describe(a) +
                                " to " + (b ? world_->describe(b) : std::string("the board"))};
  });
}

// --- sizes and properties -----------------------------------------------------------

EditResult Editor::resize(ObjectId part, Vec2 size) {
  if (!world_ || !world_->store().alive(part)) return EditResult::refused("no such part");
  return guarded([&] {
    const auto p = read_part(*world_, part);
    if (!p) return EditResult::refused(world_->describe(part) + " has no shape to resize");
    constexpr double kSmallest = 0.002;
    if (!(size.x >= kSmallest) || !(size.y >= kSmallest))
      return EditResult::refused("a part is at least 2 mm across");
    // The mass follows the volume; a part given a mass without a density
    // keeps its mean density all the same.
    double ratio = 1;
    switch (p->shape) {
      case Shape2D::Box: {
        const Vec3 s = world_->value<Vec3>(part, "size").value_or(Vec3{});
        ratio = (size.x * size.y) / (s.x * s.y);
        world_->set(part, "size", Vec3{size.x, size.y, s.z});
        break;
      }
      case Shape2D::Disk: {
        const double r = p->radius, nr = size.x / 2;
        const bool cylinder = enum_of(part, "shape") == "cylinder";
        ratio = cylinder ? (nr * nr) / (r * r) : (nr * nr * nr) / (r * r * r);
        world_->set(part, "radius", nr);
        break;
      }
      case Shape2D::Capsule: {
        const double r = p->radius, l = 2 * p->half_length;
        const double nr = size.y / 2, nl = std::max(0.0, size.x - size.y);
        const double v0 = std::numbers::pi * r * r * (l + 4.0 / 3 * r),
                     v1 = std::numbers::pi * nr * nr * (nl + 4.0 / 3 * nr);
        ratio = v1 / v0;
        world_->set(part, "radius", nr);
        world_->set(part, "length", nl);
        break;
      }
    }
    if (const auto m = world_->value<double>(part, "mass"); m && *m > 0)
      world_->set(part, "mass", *m * ratio);
    char buf[96];
    if (p->shape == Shape2D::Disk)
      std::snprintf(buf, sizeof buf, ": radius %.1f mm", size.x * 500);
    else
      std::snprintf(buf, sizeof buf, ": %.1f x %.1f mm", size.x * 1000, size.y * 1000);
    return EditResult{true, "resized " + world_->describe(part) + buf};
  });
}

std::string Editor::enum_of(ObjectId id, const char* prop) const {
  const auto pid = world_->properties().find(prop);
  if (!pid || !world_->store().has(id, *pid)) return "";
  const PropertyValue v = world_->store().get(id, *pid);
  const EnumValue* e = std::get_if<EnumValue>(&v);
  const auto& names = world_->properties().def(*pid).enum_values;
  return e && e->index >= 0 && std::size_t(e->index) < names.size() ? names[std::size_t(e->index)]
                                                                    : "";
}

EditResult Editor::set_property(ObjectId id, const std::string& property,
                                const PropertyValue& value) {
  if (!world_ || !world_->store().alive(id)) return EditResult::refused("no such object");
  const auto pid = world_->properties().find(property);
  if (!pid) return EditResult::refused("unknown property '" + property + "'");
  const PropertyDef& def = world_->properties().def(*pid);
  // The bounds in words, for the message when a value is refused.
  std::string range;
  char buf[64];
  if (def.min) {
    std::snprintf(buf, sizeof buf, "%s %g", def.min_exclusive ? ">" : ">=", *def.min);
    range += buf;
  }
  if (def.max) {
    std::snprintf(buf, sizeof buf, "%s<= %g", range.empty() ? "" : ", ", *def.max);
    range += buf;
  }
  const std::optional<PropertyValue> before =
      world_->store().has(id, *pid) ? std::optional(world_->store().get(id, *pid)) : std::nullopt;
  try {
    world_->set(id, *pid, value);
  } catch (const std::exception& e) {
    return EditResult::refused(
        world_->describe(id) + "." + property + ": " + e.what() +
        (range.empty() ? "" : " (range " + range + (def.unit.empty() ? "" : " " + def.unit) + ")"));
  }
  // The whole object's checks too (a hinge's limits in order, a spring
  // stable at the step): a value that breaks one is taken back.
  try {
    world_->check(id);
  } catch (const InputError& e) {
    if (before)
      world_->set(id, *pid, *before);
    else
      world_->remove(id, property);
    return EditResult::refused(e.what());
  }
  return EditResult{true, "set " + world_->describe(id) + "." + property};
}

const std::vector<Editor::MaterialDef>& Editor::materials() {
  // The kit's table (mods/kit/materials.lua): what a part of each material
  // weighs, grips and bounces, and whether it conducts.
  static const std::vector<MaterialDef> list = {
      {"steel", 7850, 0.5, 0.6, true},   {"iron", 7870, 0.5, 0.5, true},
      {"brass", 8500, 0.4, 0.5, true},   {"copper", 8960, 0.45, 0.4, true},
      {"bronze", 8600, 0.35, 0.6, true}, {"wood", 700, 0.4, 0.5, false},
      {"rubber", 1100, 0.9, 0.8, false}, {"felt", 300, 0.6, 0.05, false},
  };
  return list;
}

EditResult Editor::set_material(ObjectId part, const std::string& material) {
  if (!world_ || !world_->store().alive(part)) return EditResult::refused("no such part");
  const auto& list = materials();
  const auto m = std::find_if(list.begin(), list.end(),
                              [&](const MaterialDef& d) { return material == d.name; });
  if (m == list.end()) return EditResult::refused("the kit has no material '" + material + "'");
  return guarded([&] {
    const auto mass = world_->value<double>(part, "mass");
    const auto density = world_->value<double>(part, "density");
    if (mass && density && *density > 0) world_->set(part, "mass", *mass * m->density / *density);
    if (density || mass) world_->set(part, "density", m->density);
    world_->set(part, "friction", m->friction);
    world_->set(part, "restitution", m->restitution);
    if (m->conductive)
      world_->set(part, "conductive", true);
    else if (has(part, "conductive"))
      world_->remove(part, "conductive");
    return EditResult{true, world_->describe(part) + " is " + m->name + " now"};
  });
}

}  // namespace alloy::viewer
