#include "runtime/property_store.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>

namespace alloy {

namespace {

template <class Fn>
decltype(auto) dispatch(PropertyKind kind, Fn&& fn) {
  switch (kind) {
    case PropertyKind::Number:
      return fn(std::type_identity<double>{});
    case PropertyKind::Integer:
      return fn(std::type_identity<std::int64_t>{});
    case PropertyKind::Bool:
      return fn(std::type_identity<std::uint8_t>{});
    case PropertyKind::Vec3:
      return fn(std::type_identity<Vec3>{});
    case PropertyKind::Quat:
      return fn(std::type_identity<Quat>{});
    case PropertyKind::String:
      return fn(std::type_identity<std::string>{});
    case PropertyKind::Ref:
      return fn(std::type_identity<ObjectId>{});
    case PropertyKind::RefList:
      return fn(std::type_identity<RefList>{});
    case PropertyKind::Enum:
      return fn(std::type_identity<EnumValue>{});
  }
  return fn(std::type_identity<double>{});
}

std::string value_kind_name(const PropertyValue& v) {
  static constexpr const char* names[] = {"number", "integer", "bool",    "vec3", "quat",
                                          "string", "ref",     "reflist", "enum"};
  return names[v.index()];
}

bool finite_value(const PropertyValue& v) {
  if (const double* d = std::get_if<double>(&v)) return std::isfinite(*d);
  if (const Vec3* p = std::get_if<Vec3>(&v)) return is_finite(*p);
  if (const Quat* q = std::get_if<Quat>(&v)) return is_finite(*q);
  return true;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string text(const PropertyValue& v) {
  if (const double* d = std::get_if<double>(&v)) return num(*d);
  if (const Vec3* p = std::get_if<Vec3>(&v))
    return "{" + num(p->x) + ", " + num(p->y) + ", " + num(p->z) + "}";
  if (const Quat* q = std::get_if<Quat>(&v))
    return "{" + num(q->w) + ", " + num(q->x) + ", " + num(q->y) + ", " + num(q->z) + "}";
  return value_kind_name(v);
}

/// The owner's bounds (PropertyDef::min, max, nonzero), in words a scene author reads.
void check_bounds(const PropertyDef& def, const PropertyValue& value, const ErrorLocation& where) {
  auto fail = [&](const std::string& what) {
    throw InputError(where, "'" + def.name + "' " + what);
  };
  auto in_bounds = [&](double x) {
    if (def.min && (def.min_exclusive ? !(x > *def.min) : !(x >= *def.min))) return false;
    return !(def.max && x > *def.max);
  };
  // The message names the bound that was crossed: "greater than 0" for a
  // negative mass, though mass also has an upper bound far away.
  auto bounds = [&](bool below) {
    if (def.min && def.max && (!below || *def.min != 0) && !def.min_exclusive)
      return "must lie between " + num(*def.min) + " and " + num(*def.max);
    if (below && *def.min == 0)
      return std::string(def.min_exclusive ? "must be greater than 0" : "must not be negative");
    if (below)
      return (def.min_exclusive ? "must be greater than " : "must be at least ") + num(*def.min);
    if (def.min)
      return (def.min_exclusive ? "must be greater than " : "must be at least ") + num(*def.min) +
             " and at most " + num(*def.max);
    return "must be at most " + num(*def.max);
  };
  auto below = [&](double x) { return def.min && !(def.max && x > *def.max); };
  if (def.min || def.max) {
    double x = 0;
    if (const double* d = std::get_if<double>(&value))
      x = *d;
    else if (const std::int64_t* i = std::get_if<std::int64_t>(&value))
      x = double(*i);
    if (const Vec3* p = std::get_if<Vec3>(&value)) {
      for (double c : {p->x, p->y, p->z})
        if (!in_bounds(c)) fail(bounds(below(c)) + " in every direction, got " + text(value));
    } else if ((std::holds_alternative<double>(value) ||
                std::holds_alternative<std::int64_t>(value)) &&
               !in_bounds(x)) {
      fail(bounds(below(x)) + ", got " + num(x));
    }
  }
  if (def.nonzero) {
    if (const Vec3* p = std::get_if<Vec3>(&value); p && *p == Vec3{})
      fail("must not be the zero vector");
    if (const Quat* q = std::get_if<Quat>(&value);
        q && q->w == 0 && q->x == 0 && q->y == 0 && q->z == 0)
      fail("must not be the zero quaternion");
  }
}

}  // namespace

void ColumnBase::refresh_members() {
  if (!members_dirty_) return;
  members_.clear();
  for (std::uint32_t s = 0; s < present_.size(); ++s)
    if (present_[s]) members_.push_back(s);
  members_dirty_ = false;
}

ObjectId PropertyStore::create() {
  std::uint32_t slot;
  if (!free_slots_.empty()) {
    // Reuse the oldest freed slot first, so that recent stale ids stay stale
    // for as long as possible.
    slot = free_slots_.front();
    free_slots_.erase(free_slots_.begin());
  } else {
    slot = std::uint32_t(generations_.size());
    generations_.push_back(1);
    alive_.push_back(0);
    names_.emplace_back();
    for (auto& c : columns_)
      if (c) c->resize(generations_.size());
  }
  alive_[slot] = 1;
  ++live_count_;
  ++log_.structure;
  return ObjectId{slot, generations_[slot]};
}

void PropertyStore::destroy(ObjectId id) {
  check_alive(id);
  for (auto& c : columns_)
    if (c && c->has(id.index)) c->reset(id.index);
  if (!names_[id.index].empty()) by_name_.erase(names_[id.index]);
  names_[id.index].clear();
  alive_[id.index] = 0;
  if (++generations_[id.index] == 0) generations_[id.index] = 1;
  free_slots_.push_back(id.index);
  --live_count_;
  ++log_.structure;
}

void PropertyStore::not_alive(ObjectId id) const {
  if (id.is_null()) throw AccessError("null object id");
  if (id.index >= generations_.size())
    throw AccessError("object #" + std::to_string(id.index) + " never existed");
  throw AccessError("object #" + std::to_string(id.index) + " (generation " +
                    std::to_string(id.generation) + ") was destroyed");
}

ObjectId PropertyStore::id_at(std::uint32_t slot) const {
  if (slot >= generations_.size() || !alive_[slot]) return ObjectId{};
  return ObjectId{slot, generations_[slot]};
}

void PropertyStore::set_name(ObjectId id, const std::string& name) {
  check_alive(id);
  if (name == names_[id.index]) return;
  if (!name.empty()) {
    if (auto it = by_name_.find(name); it != by_name_.end())
      throw InputError(ErrorLocation{"", 0, name},
                       "duplicate name: another object is already called '" + name + "'");
  }
  if (!names_[id.index].empty()) by_name_.erase(names_[id.index]);
  names_[id.index] = name;
  if (!name.empty()) by_name_.emplace(name, id);
}

ObjectId PropertyStore::find(std::string_view name) const {
  auto it = by_name_.find(name);
  return it == by_name_.end() ? ObjectId{} : it->second;
}

std::string PropertyStore::describe(ObjectId id) const {
  if (id.index < names_.size() && alive(id) && !names_[id.index].empty()) return names_[id.index];
  return "#" + std::to_string(id.index);
}

ColumnBase& PropertyStore::make_column(PropertyId id) const {
  if (id >= registry_.size()) throw AccessError("no property with id " + std::to_string(id));
  if (columns_.size() <= id) columns_.resize(registry_.size());
  auto& c = columns_[id];
  if (!c) {
    c = dispatch(registry_.def(id).kind,
                 [&]<class T>(std::type_identity<T>) -> std::unique_ptr<ColumnBase> {
                   return std::make_unique<Column<T>>(id, &log_);
                 });
    c->resize(generations_.size());
  }
  return *c;
}

PropertyValue PropertyStore::checked(ObjectId id, PropertyId prop,
                                     const PropertyValue& value) const {
  check_alive(id);
  const PropertyDef& def = registry_.def(prop);
  const ErrorLocation where{"", 0, describe(id)};
  // Enum values may be given by name.
  if (def.kind == PropertyKind::Enum) {
    if (const std::string* s = std::get_if<std::string>(&value)) {
      auto e = registry_.enum_value(prop, *s);
      if (!e) {
        std::string allowed;
        for (const auto& v : def.enum_values) allowed += (allowed.empty() ? "" : ", ") + v;
        throw InputError(where,
                         "'" + def.name + "' has no value '" + *s + "' (one of: " + allowed + ")");
      }
      return PropertyValue(*e);
    }
  }
  if (def.kind == PropertyKind::Integer) {
    // A whole double from a script is an integer; anything else is a type error.
    if (const double* d = std::get_if<double>(&value);
        d && std::floor(*d) == *d && std::isfinite(*d))
      return PropertyValue(std::int64_t(*d));
  }
  if (def.kind == PropertyKind::Number)
    if (const std::int64_t* i = std::get_if<std::int64_t>(&value))
      return checked(id, prop, PropertyValue(double(*i)));
  if (value_kind_name(value) != to_string(def.kind))
    throw InputError(where, "'" + def.name + "' expects " + std::string(to_string(def.kind)) +
                                ", got " + value_kind_name(value));
  if (!finite_value(value))
    throw InputError(where, "'" + def.name + "' must be a finite number, got " + text(value));
  check_bounds(def, value, where);
  if (const ObjectId* ref = std::get_if<ObjectId>(&value); ref && !ref->is_null() && !alive(*ref))
    throw InputError(where, "'" + def.name + "' refers to an object that does not exist");
  return value;
}

void PropertyStore::set(ObjectId id, PropertyId prop, const PropertyValue& value) {
  const PropertyValue v = checked(id, prop, value);
  if (registry_.def(prop).name == "name")  // the index first: it refuses duplicates
    if (const std::string* s = std::get_if<std::string>(&v)) set_name(id, *s);
  if (!column(prop).set_value(id.index, v))
    throw AccessError("column of '" + registry_.def(prop).name + "' refused a checked value");
}

void PropertyStore::remove(ObjectId id, PropertyId prop) {
  check_alive(id);
  ColumnBase& c = column(prop);
  if (!c.has(id.index)) return;
  c.reset(id.index);
}

PropertyValue PropertyStore::get(ObjectId id, PropertyId prop) const {
  check_alive(id);
  const ColumnBase* c = find_column(prop);
  if (!c || !c->has(id.index))
    throw AccessError(describe(id) + " does not carry '" + registry_.def(prop).name + "'");
  return c->get_value(id.index);
}

void PropertyStore::refresh() {
  // Every membership change moves the structure counter: nothing moved, nothing to do.
  const std::uint64_t now = log_.structure + log_.by_resolvers;
  if (refreshed_at_ == now) return;
  for (auto& c : columns_)
    if (c) c->refresh_members();
  refreshed_at_ = now;
}

std::vector<PropertyId> PropertyStore::take_resolver_changes() {
  std::vector<PropertyId> out;
  out.swap(log_.columns);
  for (PropertyId p : out) columns_[p]->logged_ = false;
  return out;
}

std::uint64_t PropertyStore::next_lineage() {
  static std::atomic<std::uint64_t> next{1};
  return next++;
}

void PropertyStore::restore(const Objects& objects, const std::vector<const ColumnBase*>& columns) {
  const std::size_t n = objects.generations.size();
  if (objects.alive.size() != n || objects.names.size() != n)
    throw InputError("a snapshot's object table is inconsistent: " + std::to_string(n) +
                     " slots, " + std::to_string(objects.alive.size()) + " alive flags, " +
                     std::to_string(objects.names.size()) + " names");
  for (std::uint32_t s : objects.free_slots)
    if (s >= n || objects.alive[s])
      throw InputError("a snapshot's free list names slot " + std::to_string(s) +
                       ", which is not free");
  // A snapshot may come from a file that someone edited (and whose checksum
  // they recomputed): everything the store and the engines rely on is checked
  // here, before anything changes, as an edit would be. Every free slot is on
  // the free list once; no column holds a value on a free slot; every value is
  // finite, within its property's bounds, and refers only to live objects.
  {
    std::vector<std::uint8_t> listed(n, 0);
    for (std::uint32_t s : objects.free_slots)
      if (listed[s]++)
        throw InputError("a snapshot's free list names slot " + std::to_string(s) + " twice");
    for (std::uint32_t s = 0; s < n; ++s)
      if (!objects.alive[s] && !listed[s])
        throw InputError("a snapshot's slot " + std::to_string(s) +
                         " holds no object but is not on its free list");
    auto alive_in = [&](ObjectId o) {
      return o.index < n && objects.alive[o.index] && objects.generations[o.index] == o.generation;
    };
    for (PropertyId p = 0; p < registry_.size() && p < columns.size(); ++p) {
      const ColumnBase* from = columns[p];
      if (!from) continue;
      const PropertyDef& def = registry_.def(p);
      const auto present = from->presence();
      for (std::uint32_t s = 0; s < present.size() && s < n; ++s) {
        if (!present[s]) continue;
        const std::string at = "a snapshot's '" + def.name + "' of slot " + std::to_string(s);
        if (!objects.alive[s]) throw InputError(at + ", which holds no object");
        const PropertyValue v = from->get_value(s);
        if (!finite_value(v)) throw InputError(at + " is not a finite number: " + text(v));
        check_bounds(def, v, ErrorLocation{"", 0, at});
        if (const ObjectId* ref = std::get_if<ObjectId>(&v);
            ref && !ref->is_null() && !alive_in(*ref))
          throw InputError(at + " refers to an object that is not alive in it");
        if (const RefList* list = std::get_if<RefList>(&v))
          for (const ObjectId& o : *list)
            if (!o.is_null() && !alive_in(o))
              throw InputError(at + " refers to an object that is not alive in it");
      }
    }
  }
  generations_ = objects.generations;
  alive_ = objects.alive;
  free_slots_ = objects.free_slots;
  names_ = objects.names;
  by_name_.clear();
  live_count_ = 0;
  for (std::uint32_t s = 0; s < n; ++s) {
    if (!alive_[s]) continue;
    ++live_count_;
    if (!names_[s].empty()) by_name_.emplace(names_[s], ObjectId{s, generations_[s]});
  }
  for (PropertyId p = 0; p < registry_.size(); ++p) {
    const ColumnBase* from = p < columns.size() ? columns[p] : nullptr;
    ColumnBase& c = column(p);
    if (from) {
      if (from->present_.size() != n)
        throw InputError("a snapshot's column '" + registry_.def(p).name + "' has " +
                         std::to_string(from->present_.size()) + " slots, its object table " +
                         std::to_string(n));
      c.assign(*from);
    } else {
      c.clear(n);
    }
  }
  ++log_.structure;
  refresh();
}

std::size_t PropertyStore::reinstate(const std::vector<const ColumnBase*>& columns) {
  std::size_t n = 0;
  for (PropertyId p = 0; p < registry_.size() && p < columns.size(); ++p)
    if (columns[p] && column(p).reinstate(*columns[p])) ++n;
  if (n) refresh();
  return n;
}

}  // namespace alloy
