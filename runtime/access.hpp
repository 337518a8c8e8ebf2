// Read-only views and declared writers over property columns.
//
// This is where "only a resolver may write, and only the columns it declared"
// becomes a property of the API rather than a convention: ColumnView has no
// way to change a value; ColumnWriter can only be obtained from a
// ResolverAccess, which the world hands to a resolver's build()/advance() and
// which refuses any column not in the resolver's `writes`.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

#include "runtime/property_store.hpp"
#include "runtime/scope.hpp"

namespace alloy {
class ResolverAccess;

namespace detail {
/// One branch for the whole value: x - x is 0 for every finite x and NaN for
/// NaN and +-Inf, and a sum with a NaN is NaN. Exact IEEE arithmetic (the
/// project builds without -ffast-math); integers, strings and refs are always
/// "finite".
template <class T>
inline bool finite_write(const T& v) {
  if constexpr (std::is_same_v<T, double>)
    return v - v == 0;
  else if constexpr (std::is_same_v<T, Vec3>)
    return (v.x - v.x) + (v.y - v.y) + (v.z - v.z) == 0;
  else if constexpr (std::is_same_v<T, Quat>)
    return (v.w - v.w) + (v.x - v.x) + (v.y - v.y) + (v.z - v.z) == 0;
  else
    return true;
}
/// A resolver wrote a non-finite value: refuse it, record a "non_finite"
/// event naming the resolver, object and property, and freeze the object
/// (World::frozen). `components` are the refused value's numbers. Out of line
/// and cold: it runs only when a simulation has already gone wrong.
void non_finite_write(ResolverAccess* access, std::uint32_t slot, PropertyId property,
                      const double* components, int count);
/// A write outside the writer's scope: silently refused if the object is
/// frozen (a resolver may still hold it through a reference), else AccessError.
void out_of_scope_write(ResolverAccess* access, std::uint32_t slot);
}  // namespace detail

/// Read-only view of one column. Cheap to copy; valid for the world's lifetime.
/// A view handed to a stage of an area sees only the objects in that area.
template <class T>
class ColumnView {
 public:
  ColumnView() = default;
  ColumnView(const Column<T>* column, const PropertyStore* store, const Scope* scope = nullptr)
      : c_(column), store_(store), scope_(scope) {}

  explicit operator bool() const { return c_ != nullptr; }
  PropertyId id() const { return c_->id(); }
  /// Fast path for loops over members(): no liveness check.
  const T& operator[](std::uint32_t slot) const { return (*c_)[slot]; }
  bool has(std::uint32_t slot) const {
    return c_ && c_->has(slot) && (!scope_ || scope_->contains(slot));
  }
  bool has(ObjectId id) const { return store_ && store_->alive(id) && has(id.index); }
  /// Checked access: a stale id or a missing property fails loudly.
  const T& get(ObjectId id) const {
    store_->check_alive(id);
    if (!c_->has(id.index))
      throw AccessError(store_->describe(id) + " does not carry '" +
                        store_->registry().def(c_->id()).name + "'");
    return (*c_)[id.index];
  }
  /// `fallback` if the object does not carry the property.
  T value_or(std::uint32_t slot, T fallback) const {
    return c_ && c_->has(slot) ? (*c_)[slot] : fallback;
  }
  /// The objects carrying the property (in scope), ascending.
  std::span<const std::uint32_t> members() const {
    if (!c_) return {};
    return scope_ ? scope_->members_of(*c_) : c_->members();
  }
  std::uint64_t version() const { return c_ ? c_->version() : 0; }

 private:
  const Column<T>* c_ = nullptr;
  const PropertyStore* store_ = nullptr;
  const Scope* scope_ = nullptr;
};

/// Write access to one column that a resolver declared. Setting a value that
/// differs from the stored one moves the column's change counter. A
/// non-finite number (NaN, +-Inf) is never stored: see detail::non_finite_write.
template <class T>
class ColumnWriter {
 public:
  ColumnWriter() = default;

  explicit operator bool() const { return c_ != nullptr; }
  const T& operator[](std::uint32_t slot) const { return (*c_)[slot]; }
  bool has(std::uint32_t slot) const { return c_->has(slot); }
  /// Writes `value` for the object in `slot`; the object starts carrying the
  /// property if it did not.
  void set(std::uint32_t slot, const T& value) {
    if (scope_ && !scope_->contains(slot)) [[unlikely]] {
      detail::out_of_scope_write(access_, slot);
      return;
    }
    if (!detail::finite_write(value)) [[unlikely]] {
      refuse(slot, value);
      return;
    }
    if (!c_->has(slot)) {
      c_->values_[slot] = value;
      c_->mark_present_by_resolver(slot, true);
      ++c_->version_;
    } else if (!(c_->values_[slot] == value)) {
      c_->values_[slot] = value;
      ++c_->version_;
    }
  }
  /// Writes `values[i]` for the object in `slots[i]`, for every i in order:
  /// the same as set() on each pair (the same scope and finiteness checks,
  /// the change counter moved once per value that differs), in one call, for
  /// a resolver that publishes a column for thousands of objects a step.
  /// The common case (in scope, already carrying the property, finite) is
  /// one tight loop; any other pair goes through set() itself. AccessError
  /// if the spans differ in length.
  void set(std::span<const std::uint32_t> slots, std::span<const T> values) {
    if (slots.size() != values.size())
      throw AccessError("ColumnWriter::set: " + std::to_string(slots.size()) + " slots but " +
                        std::to_string(values.size()) + " values");
    // Held in locals, the arrays are not reloaded after every store; the
    // slow path (set() on one pair, which may refuse and freeze the object)
    // takes them afresh after it, so that nothing it does can leave them
    // pointing at storage it moved.
    T* stored = c_->values_.data();
    const std::uint8_t* present = c_->present_.data();
    std::size_t size = c_->present_.size();
    std::uint64_t changed = 0;
    for (std::size_t i = 0; i < slots.size(); ++i) {
      const std::uint32_t slot = slots[i];
      const T& value = values[i];
      if (slot >= size || !present[slot] || (scope_ && !scope_->contains(slot)) ||
          !detail::finite_write(value)) [[unlikely]] {
        c_->version_ += std::exchange(changed, 0);  // in order with what set() moves
        set(slot, value);
        stored = c_->values_.data(), present = c_->present_.data(), size = c_->present_.size();
        continue;
      }
      if (!(stored[slot] == value)) stored[slot] = value, ++changed;
    }
    c_->version_ += changed;
  }
  /// The object in `slot` stops carrying the property (a structural change).
  void erase(std::uint32_t slot) {
    if (!c_->has(slot)) return;
    if (scope_ && !scope_->contains(slot)) [[unlikely]] {
      detail::out_of_scope_write(access_, slot);
      return;
    }
    c_->values_[slot] = T{};
    c_->mark_present_by_resolver(slot, false);
    ++c_->version_;
  }
  /// The objects carrying the property (in scope), ascending.
  std::span<const std::uint32_t> members() const {
    return scope_ ? scope_->members_of(*c_) : c_->members();
  }
  std::uint64_t version() const { return c_->version(); }

 private:
  friend class ResolverAccess;
  ColumnWriter(Column<T>* column, const Scope* scope, ResolverAccess* access)
      : c_(column), scope_(scope), access_(access) {}
  [[gnu::noinline, gnu::cold]] void refuse(std::uint32_t slot, const T& value) const {
    if constexpr (std::is_same_v<T, double>) {
      detail::non_finite_write(access_, slot, c_->id(), &value, 1);
    } else if constexpr (std::is_same_v<T, Vec3>) {
      const double c[3] = {value.x, value.y, value.z};
      detail::non_finite_write(access_, slot, c_->id(), c, 3);
    } else if constexpr (std::is_same_v<T, Quat>) {
      const double c[4] = {value.w, value.x, value.y, value.z};
      detail::non_finite_write(access_, slot, c_->id(), c, 4);
    }
  }
  Column<T>* c_ = nullptr;
  const Scope* scope_ = nullptr;
  ResolverAccess* access_ = nullptr;
};

}  // namespace alloy
