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

#include "runtime/property_store.hpp"
#include "runtime/scope.hpp"

namespace alloy {
class ResolverAccess;
}

namespace alloy {

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
  bool has(std::uint32_t slot) const { return c_ && c_->has(slot) && (!scope_ || scope_->contains(slot)); }
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
  T value_or(std::uint32_t slot, T fallback) const { return c_ && c_->has(slot) ? (*c_)[slot] : fallback; }
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
/// differs from the stored one moves the column's change counter.
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
    if (scope_ && !scope_->contains(slot)) out_of_scope(slot);
    if (!c_->has(slot)) {
      c_->values_[slot] = value;
      c_->mark_present(slot, true);
      ++c_->version_;
    } else if (!(c_->values_[slot] == value)) {
      c_->values_[slot] = value;
      ++c_->version_;
    }
  }
  /// The object in `slot` stops carrying the property (a structural change).
  void erase(std::uint32_t slot) {
    if (!c_->has(slot)) return;
    if (scope_ && !scope_->contains(slot)) out_of_scope(slot);
    c_->values_[slot] = T{};
    c_->mark_present(slot, false);
    ++c_->version_;
  }
  /// The objects carrying the property (in scope), ascending.
  std::span<const std::uint32_t> members() const {
    return scope_ ? scope_->members_of(*c_) : c_->members();
  }
  std::uint64_t version() const { return c_->version(); }

 private:
  friend class ResolverAccess;
  ColumnWriter(Column<T>* column, const Scope* scope) : c_(column), scope_(scope) {}
  [[noreturn]] void out_of_scope(std::uint32_t slot) const {
    throw AccessError("a resolver of an area wrote object #" + std::to_string(slot) +
                      ", which is outside its area");
  }
  Column<T>* c_ = nullptr;
  const Scope* scope_ = nullptr;
};

}  // namespace alloy
