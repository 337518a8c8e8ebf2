// The property-type registry (paper 3.1): every property is known by name and
// has one representation, chosen here once. Properties are dumb data; the
// registry only says what a name means, never what to do with it.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"

namespace alloy {

enum class PropertyKind : std::uint8_t {
  Number,   ///< double
  Integer,  ///< int64
  Bool,     ///< stored as uint8 (no vector<bool>)
  Vec3,     ///< alloy::Vec3
  Quat,     ///< alloy::Quat
  String,   ///< std::string
  Ref,      ///< ObjectId of another object (or null)
  RefList,  ///< std::vector<ObjectId>
  Enum,     ///< index into the property's list of named values
};

std::string_view to_string(PropertyKind kind);
std::optional<PropertyKind> kind_from_string(std::string_view name);

/// Value of an enum property: the index into PropertyDef::enum_values.
struct EnumValue {
  std::int32_t index = 0;
  friend constexpr bool operator==(EnumValue, EnumValue) = default;
};

using RefList = std::vector<ObjectId>;

/// Storage type of each kind.
template <PropertyKind K> struct StorageOf;
template <> struct StorageOf<PropertyKind::Number> { using type = double; };
template <> struct StorageOf<PropertyKind::Integer> { using type = std::int64_t; };
template <> struct StorageOf<PropertyKind::Bool> { using type = std::uint8_t; };
template <> struct StorageOf<PropertyKind::Vec3> { using type = Vec3; };
template <> struct StorageOf<PropertyKind::Quat> { using type = Quat; };
template <> struct StorageOf<PropertyKind::String> { using type = std::string; };
template <> struct StorageOf<PropertyKind::Ref> { using type = ObjectId; };
template <> struct StorageOf<PropertyKind::RefList> { using type = RefList; };
template <> struct StorageOf<PropertyKind::Enum> { using type = EnumValue; };

/// The kind whose storage is T (used to check a typed column request).
template <class T> constexpr PropertyKind kind_of();
template <> constexpr PropertyKind kind_of<double>() { return PropertyKind::Number; }
template <> constexpr PropertyKind kind_of<std::int64_t>() { return PropertyKind::Integer; }
template <> constexpr PropertyKind kind_of<std::uint8_t>() { return PropertyKind::Bool; }
template <> constexpr PropertyKind kind_of<Vec3>() { return PropertyKind::Vec3; }
template <> constexpr PropertyKind kind_of<Quat>() { return PropertyKind::Quat; }
template <> constexpr PropertyKind kind_of<std::string>() { return PropertyKind::String; }
template <> constexpr PropertyKind kind_of<ObjectId>() { return PropertyKind::Ref; }
template <> constexpr PropertyKind kind_of<RefList>() { return PropertyKind::RefList; }
template <> constexpr PropertyKind kind_of<EnumValue>() { return PropertyKind::Enum; }

/// Any property value, for editing, scene loading and traces (never in a hot loop).
using PropertyValue = std::variant<double, std::int64_t, bool, Vec3, Quat, std::string, ObjectId,
                                   RefList, EnumValue>;

/// Dense index of a registered property; also the index of its column.
using PropertyId = std::uint32_t;
inline constexpr PropertyId kNoProperty = 0xffffffffu;

/// Definition of a property type. Create with sane defaults, register once.
struct PropertyDef {
  std::string name;                      ///< unique, e.g. "position"
  PropertyKind kind = PropertyKind::Number;
  std::string unit;                      ///< SI unit for docs and traces, e.g. "m/s"
  std::string doc;                       ///< one line: what the value means
  std::vector<std::string> enum_values;  ///< the names of an Enum's values, in order
  std::string owner;                     ///< who registered it (plugin or mod), for unloading
  /// `owner` names a Lua mod (else a native plugin, or "runtime"). A mod may
  /// be called like a native plugin: the flag, not the name, tells them apart.
  /// Only a property's owner may write it from Lua without a scene's grant.
  bool owner_is_mod = false;
  /// Bounds, checked on every edit (scene, player, timeline): numbers and
  /// integers, and each component of a vec3 (a box's size).
  std::optional<double> min;
  bool min_exclusive = false;  ///< the value must be > min, not >= min
  std::optional<double> max;
  bool nonzero = false;  ///< vec3 / quat: must not be all zeros (an axis, a rotation)
};

/// Name -> definition. Registration is idempotent when the definition is the
/// same; a conflicting redefinition is an InputError.
class PropertyRegistry {
 public:
  PropertyId add(PropertyDef def);
  /// Inline and hashed: stages look properties up by name in their steps.
  std::optional<PropertyId> find(std::string_view name) const;
  /// Throws InputError("unknown property 'x'") if missing.
  PropertyId id(std::string_view name) const {
    if (const auto found = find(name)) return *found;
    unknown(name);
  }
  const PropertyDef& def(PropertyId id) const { return defs_.at(id); }
  std::size_t size() const { return defs_.size(); }
  /// Index of an enum value by name, or nullopt.
  std::optional<EnumValue> enum_value(PropertyId id, std::string_view value) const;
  /// Names sorted, for messages ("did you mean") and docs.
  std::vector<std::string> names() const;

 private:
  [[noreturn]] void unknown(std::string_view name) const;
  static std::size_t hash(std::string_view s) {  // FNV-1a: names are short
    std::size_t h = 1469598103934665603ull;
    for (char c : s) h = (h ^ std::uint8_t(c)) * 1099511628211ull;
    return h;
  }
  void index(PropertyId id);

  std::vector<PropertyDef> defs_;
  std::map<std::string, PropertyId, std::less<>> by_name_;  // sorted, for names()
  /// Open addressing on hash(name), at most half full; kNoProperty: empty.
  std::vector<PropertyId> table_;
};

inline std::optional<PropertyId> PropertyRegistry::find(std::string_view name) const {
  if (table_.empty()) return std::nullopt;
  const std::size_t mask = table_.size() - 1;
  for (std::size_t i = hash(name) & mask;; i = (i + 1) & mask) {
    const PropertyId id = table_[i];
    if (id == kNoProperty) return std::nullopt;
    if (defs_[id].name == name) return id;
  }
}

/// Who a property belongs to, for messages: "mod 'magic'", "the native
/// plugin 'rigid_body'", "the runtime".
std::string owner_text(const PropertyDef& def);
/// Whether `def` belongs to the Lua mod called `mod`.
inline bool owned_by_mod(const PropertyDef& def, std::string_view mod) {
  return def.owner_is_mod && def.owner == mod;
}

/// Closest registered name to `name` by edit distance (for "did you mean"), or "".
std::string closest_name(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace alloy
