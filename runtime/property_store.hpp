// Objects and their properties, stored as columns (struct of arrays, paper 3.1).
//
// Every registered property has one column. A column holds one value slot per
// object slot plus a presence flag: an object "carries" a property when its
// flag is set. Columns keep a change counter (`version`) that moves whenever a
// value changes, and a membership counter that moves when objects start or stop
// carrying the property; derived sets and the scheduler compare these counters
// to skip work.
//
// The store itself has no notion of permission: it is private to the World,
// which hands out read-only views to everyone and writers only to resolvers
// for the columns they declared (see access.hpp).
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/error.hpp"
#include "runtime/property_types.hpp"

namespace alloy {

/// The store's record of membership changes, which the columns update: an
/// edit's (scene, player, timeline) or an object's creation or destruction is
/// structural and rebuilds every resolver; a resolver's, through a
/// ColumnWriter, is logged by column, so that the world rebuilds only the
/// stages that read or write those columns.
struct MembershipLog {
  std::uint64_t structure = 0;      ///< objects created or destroyed, memberships edited
  std::uint64_t by_resolvers = 0;   ///< memberships changed through ColumnWriter
  std::vector<PropertyId> columns;  ///< columns behind by_resolvers since the last take
};

class ColumnBase {
 public:
  ColumnBase(PropertyId id, MembershipLog* log) : id_(id), log_(log) {}
  virtual ~ColumnBase() = default;

  PropertyId id() const { return id_; }
  bool has(std::uint32_t slot) const { return slot < present_.size() && present_[slot]; }
  /// Moves whenever a value of this column changes.
  std::uint64_t version() const { return version_; }
  /// Moves whenever an object starts or stops carrying this property.
  std::uint64_t membership_version() const { return membership_version_; }
  /// Slots of the objects that carry this property, ascending.
  std::span<const std::uint32_t> members() const { return members_; }
  std::size_t count() const { return members_.size(); }

  virtual PropertyValue get_value(std::uint32_t slot) const = 0;

  /// A copy of the values and presence flags of every slot, with the change
  /// counters, for a snapshot. The copy is never written: it has no log.
  virtual std::unique_ptr<ColumnBase> clone() const = 0;
  /// Appends the exact bits of the value in `slot` to `out`, for state
  /// hashes (state_hash.hpp defines the encoding of each kind).
  virtual void encode(std::uint32_t slot, std::string& out) const = 0;
  /// Memory the values and flags take, in bytes (for snapshot sizes).
  virtual std::size_t bytes() const = 0;
  /// The presence flag of every slot (1: the object carries the property).
  std::span<const std::uint8_t> presence() const { return present_; }

 protected:
  friend class PropertyStore;
  virtual void resize(std::size_t slots) = 0;
  virtual void reset(std::uint32_t slot) = 0;
  /// Takes the values and presence flags of `from` (a clone of a column of
  /// the same kind), and moves both change counters: everything that compares
  /// them (derived sets, delta snapshots) sees a change.
  virtual void assign(const ColumnBase& from) = 0;
  /// `slots` slots, none carrying the property (a restore that has no
  /// values for it); moves both change counters.
  virtual void clear(std::size_t slots) = 0;
  /// Takes the values of `from` (a clone of a column of the same kind) if
  /// some differ from ours in a bit: moves the value counter only, or both
  /// when the presence flags differ too (then as assign). Returns whether
  /// anything changed.
  virtual bool reinstate(const ColumnBase& from) = 0;
  /// Returns false if the value has the wrong type.
  virtual bool set_value(std::uint32_t slot, const PropertyValue& v) = 0;

  void mark_present(std::uint32_t slot, bool on) {
    if (present_[slot] != on) {
      present_[slot] = on;
      members_dirty_ = true;
      ++membership_version_;
      ++log_->structure;
    }
  }
  /// The same, made by a resolver (ColumnWriter): logged, not structural.
  void mark_present_by_resolver(std::uint32_t slot, bool on) {
    if (present_[slot] != on) {
      present_[slot] = on;
      members_dirty_ = true;
      ++membership_version_;
      ++log_->by_resolvers;
      if (!logged_) logged_ = true, log_->columns.push_back(id_);
    }
  }
  void refresh_members();

  PropertyId id_;
  MembershipLog* log_;   // the store's
  bool logged_ = false;  // in log_->columns
  std::vector<std::uint8_t> present_;
  std::vector<std::uint32_t> members_;
  bool members_dirty_ = false;
  std::uint64_t version_ = 0;
  std::uint64_t membership_version_ = 0;

  template <class T>
  friend class ColumnWriter;
};

template <class T>
class Column final : public ColumnBase {
 public:
  using ColumnBase::ColumnBase;
  const T& operator[](std::uint32_t slot) const { return values_[slot]; }
  std::span<const T> values() const { return values_; }

  PropertyValue get_value(std::uint32_t slot) const override {
    if constexpr (std::is_same_v<T, std::uint8_t>)
      return PropertyValue(values_[slot] != 0);
    else
      return PropertyValue(values_[slot]);
  }

 private:
  friend class PropertyStore;
  template <class U>
  friend class ColumnWriter;

  void resize(std::size_t slots) override {
    values_.resize(slots);
    present_.resize(slots, 0);
  }
  void reset(std::uint32_t slot) override {
    values_[slot] = T{};
    mark_present(slot, false);
  }
  bool set_value(std::uint32_t slot, const PropertyValue& v) override;

 public:
  std::unique_ptr<ColumnBase> clone() const override {
    auto c = std::make_unique<Column<T>>(id_, nullptr);
    c->values_ = values_;
    c->present_ = present_;
    c->members_ = members_;
    c->members_dirty_ = members_dirty_;
    c->version_ = version_;
    c->membership_version_ = membership_version_;
    return c;
  }
  void encode(std::uint32_t slot, std::string& out) const override;
  /// A column of no store (no log: it is never written), holding `values` and
  /// `present` (one of each per slot; an absent slot's value is T{}), for a
  /// snapshot read back from a save file (runtime/save_file.hpp).
  static std::unique_ptr<ColumnBase> detached(PropertyId id, std::vector<T> values,
                                              std::vector<std::uint8_t> present) {
    auto c = std::make_unique<Column<T>>(id, nullptr);
    c->values_ = std::move(values);
    c->present_ = std::move(present);
    for (std::uint32_t i = 0; i < c->present_.size(); ++i)
      if (c->present_[i]) c->members_.push_back(i);
    return c;
  }
  std::size_t bytes() const override {
    std::size_t n = values_.size() * sizeof(T) + present_.size();
    if constexpr (std::is_same_v<T, std::string>)
      for (const auto& v : values_)
        n += v.size() > 15 ? v.capacity() : 0;  // beyond the inline buffer
    if constexpr (std::is_same_v<T, RefList>)
      for (const auto& v : values_) n += v.capacity() * sizeof(ObjectId);
    return n;
  }

 private:
  void assign(const ColumnBase& from) override {
    const auto& f = static_cast<const Column<T>&>(from);
    values_ = f.values_;
    present_ = f.present_;
    moved();
  }
  void clear(std::size_t slots) override {
    values_.assign(slots, T{});
    present_.assign(slots, 0);
    moved();
  }
  bool reinstate(const ColumnBase& from) override {
    const auto& f = static_cast<const Column<T>&>(from);
    if (present_ != f.present_) {
      assign(from);
      return true;
    }
    bool same;
    if constexpr (std::is_trivially_copyable_v<T>)  // bits: -0.0 is not 0.0, NaN is NaN
      same = values_.size() == f.values_.size() &&
             (values_.empty() ||
              std::memcmp(values_.data(), f.values_.data(), values_.size() * sizeof(T)) == 0);
    else
      same = values_ == f.values_;
    if (same) return false;
    values_ = f.values_;
    ++version_;
    return true;
  }
  void moved() {
    members_dirty_ = true;
    ++version_;
    ++membership_version_;
    ++log_->structure;
  }

  std::vector<T> values_;
};

/// Objects (generational slots) and one column per registered property.
class PropertyStore {
 public:
  explicit PropertyStore(PropertyRegistry& registry) : registry_(registry) {}

  PropertyRegistry& registry() { return registry_; }
  const PropertyRegistry& registry() const { return registry_; }

  // --- objects -------------------------------------------------------------
  ObjectId create();
  void destroy(ObjectId id);
  bool alive(ObjectId id) const {
    return id.index < generations_.size() && generations_[id.index] == id.generation &&
           alive_[id.index];
  }
  /// Throws AccessError naming the object if `id` is stale or null.
  void check_alive(ObjectId id) const {
    if (!alive(id)) [[unlikely]]
      not_alive(id);
  }
  /// The live id in `slot`, or a null id.
  ObjectId id_at(std::uint32_t slot) const;
  std::size_t slot_count() const { return generations_.size(); }
  std::size_t object_count() const { return live_count_; }
  /// Moves when objects are created or destroyed or an edit changes a
  /// membership (not when a resolver does: resolver_membership_version).
  std::uint64_t structure_version() const { return log_.structure; }
  /// Moves when a resolver, through a ColumnWriter, gives an object a
  /// property or takes one away.
  std::uint64_t resolver_membership_version() const { return log_.by_resolvers; }
  /// The columns whose membership resolvers changed since the last call, and
  /// forgets them.
  std::vector<PropertyId> take_resolver_changes();

  // --- names (the "name" convenience property, indexed) ----------------------
  /// Sets the unique scene name; throws InputError on a duplicate.
  void set_name(ObjectId id, const std::string& name);
  ObjectId find(std::string_view name) const;
  /// The object's name, or "#<index>" if it has none (for messages).
  std::string describe(ObjectId id) const;

  // --- columns -------------------------------------------------------------
  /// The column of a property, created on first use. The typed form checks the
  /// requested type against the property's kind and throws AccessError.
  /// Columns are created on first use, so this is logically const.
  ColumnBase& column(PropertyId id) const {
    if (id < columns_.size() && columns_[id]) [[likely]]
      return *columns_[id];
    return make_column(id);
  }
  const ColumnBase* find_column(PropertyId id) const {
    return id < columns_.size() ? columns_[id].get() : nullptr;
  }
  template <class T>
  const Column<T>& typed(PropertyId id) const {
    return typed_mut<T>(id);
  }

  /// Generic edit (scene loading, player edits): type-checked against the
  /// registry, throws InputError naming the property and the expected type.
  void set(ObjectId id, PropertyId prop, const PropertyValue& value);
  /// The value `set` would store (enum names resolved, whole numbers as
  /// integers), or the InputError it would throw; stores nothing.
  PropertyValue checked(ObjectId id, PropertyId prop, const PropertyValue& value) const;
  void remove(ObjectId id, PropertyId prop);
  bool has(ObjectId id, PropertyId prop) const {
    const ColumnBase* c = find_column(prop);
    return c && alive(id) && c->has(id.index);
  }
  PropertyValue get(ObjectId id, PropertyId prop) const;

  /// Rebuilds the member lists of columns whose membership changed. The world
  /// calls this between phases so that views always see sorted, current lists.
  void refresh();

  // --- snapshots (World::snapshot, World::restore) -----------------------------
  /// The object table: what decides which ids are alive and which id the
  /// next create() returns.
  struct Objects {
    std::vector<std::uint32_t> generations;  ///< per slot, the live (or next) generation
    std::vector<std::uint8_t> alive;         ///< per slot
    std::vector<std::uint32_t> free_slots;   ///< in reuse order (create() takes the front)
    std::vector<std::string> names;          ///< per slot, "" for none
  };
  Objects objects() const { return {generations_, alive_, free_slots_, names_}; }
  /// Identifies this store for delta snapshots: change counters are compared
  /// only within one store (they never repeat within it, restores included).
  std::uint64_t lineage() const { return lineage_; }
  /// Replaces every object and value: `objects`, and for each property id the
  /// column clone (ColumnBase::clone) to take its values from, or null to
  /// empty the column. Every column of the registry not listed is emptied. A
  /// structural change: every resolver rebuilds at the next sync. The caller
  /// checks that each clone has its property's kind.
  void restore(const Objects& objects, const std::vector<const ColumnBase*>& columns);
  /// After restore: puts back the values of `columns` (as given to restore)
  /// wherever a stage's rebuild wrote other bits into them. Returns how many
  /// columns it put back.
  std::size_t reinstate(const std::vector<const ColumnBase*>& columns);

 private:
  friend class ResolverAccess;  // the only way to a writable column
  template <class T>
  Column<T>& typed_mut(PropertyId id) const;
  ColumnBase& make_column(PropertyId id) const;
  [[noreturn]] void not_alive(ObjectId id) const;

  PropertyRegistry& registry_;
  mutable std::vector<std::unique_ptr<ColumnBase>> columns_;
  std::vector<std::uint32_t> generations_;
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint32_t> free_slots_;
  std::vector<std::string> names_;
  std::map<std::string, ObjectId, std::less<>> by_name_;
  std::size_t live_count_ = 0;
  mutable MembershipLog log_;           // columns update it (see ColumnBase)
  std::uint64_t refreshed_at_ = ~0ull;  // log_.structure + log_.by_resolvers at the last refresh()
  std::uint64_t lineage_ = next_lineage();

  static std::uint64_t next_lineage();
};

// ---------------------------------------------------------------------------

template <class T>
bool Column<T>::set_value(std::uint32_t slot, const PropertyValue& v) {
  T value{};
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    const bool* b = std::get_if<bool>(&v);
    if (!b) return false;
    value = *b ? 1 : 0;
  } else if constexpr (std::is_same_v<T, double>) {
    if (const double* d = std::get_if<double>(&v))
      value = *d;
    else if (const std::int64_t* i = std::get_if<std::int64_t>(&v))
      value = double(*i);
    else
      return false;
  } else {
    const T* p = std::get_if<T>(&v);
    if (!p) return false;
    value = *p;
  }
  if (!(values_[slot] == value) || !has(slot)) {
    values_[slot] = std::move(value);
    ++version_;
  }
  mark_present(slot, true);
  return true;
}

namespace detail {
template <class V>
inline void append_bits(std::string& out, const V& v) {
  static_assert(std::is_trivially_copyable_v<V>);
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
}  // namespace detail

template <class T>
void Column<T>::encode(std::uint32_t slot, std::string& out) const {
  // Field by field (never the struct's bytes, which may hold padding).
  const T& v = values_[slot];
  if constexpr (std::is_same_v<T, Vec3>) {
    for (double c : {v.x, v.y, v.z}) detail::append_bits(out, c);
  } else if constexpr (std::is_same_v<T, Quat>) {
    for (double c : {v.w, v.x, v.y, v.z}) detail::append_bits(out, c);
  } else if constexpr (std::is_same_v<T, std::string>) {
    detail::append_bits(out, std::uint64_t(v.size()));
    out += v;
  } else if constexpr (std::is_same_v<T, ObjectId>) {
    detail::append_bits(out, v.index);
    detail::append_bits(out, v.generation);
  } else if constexpr (std::is_same_v<T, RefList>) {
    detail::append_bits(out, std::uint64_t(v.size()));
    for (ObjectId id : v) {
      detail::append_bits(out, id.index);
      detail::append_bits(out, id.generation);
    }
  } else if constexpr (std::is_same_v<T, EnumValue>) {
    detail::append_bits(out, v.index);
  } else {
    detail::append_bits(out, v);  // double, int64, uint8 (bool)
  }
}

template <class T>
Column<T>& PropertyStore::typed_mut(PropertyId id) const {
  const PropertyDef& d = registry_.def(id);
  if (d.kind != kind_of<T>())
    throw AccessError("property '" + d.name + "' is " + std::string(to_string(d.kind)) +
                      ", requested as " + std::string(to_string(kind_of<T>())));
  return static_cast<Column<T>&>(column(id));
}

}  // namespace alloy
