#include "runtime/property_types.hpp"

#include <algorithm>
#include <bit>

#include "runtime/error.hpp"

namespace alloy {

namespace {
constexpr std::pair<PropertyKind, std::string_view> kKindNames[] = {
    {PropertyKind::Number, "number"}, {PropertyKind::Integer, "integer"},
    {PropertyKind::Bool, "bool"},     {PropertyKind::Vec3, "vec3"},
    {PropertyKind::Quat, "quat"},     {PropertyKind::String, "string"},
    {PropertyKind::Ref, "ref"},       {PropertyKind::RefList, "reflist"},
    {PropertyKind::Enum, "enum"},
};

bool same_definition(const PropertyDef& a, const PropertyDef& b) {
  return a.kind == b.kind && a.enum_values == b.enum_values && a.unit == b.unit && a.min == b.min &&
         a.min_exclusive == b.min_exclusive && a.max == b.max && a.nonzero == b.nonzero;
}
}  // namespace

std::string_view to_string(PropertyKind kind) {
  for (auto [k, n] : kKindNames)
    if (k == kind) return n;
  return "?";
}

std::optional<PropertyKind> kind_from_string(std::string_view name) {
  for (auto [k, n] : kKindNames)
    if (n == name) return k;
  return std::nullopt;
}

PropertyId PropertyRegistry::add(PropertyDef def) {
  if (def.name.empty()) throw InputError("a property type needs a name");
  if (def.kind == PropertyKind::Enum && def.enum_values.empty())
    throw InputError("enum property '" + def.name + "' needs at least one value");
  if (auto it = by_name_.find(def.name); it != by_name_.end()) {
    PropertyDef& old = defs_[it->second];
    if (!same_definition(old, def))
      throw InputError("property '" + def.name + "' is already defined as " +
                       std::string(to_string(old.kind)) + " by '" + old.owner +
                       "'; it cannot be redefined as " + std::string(to_string(def.kind)));
    if (old.doc.empty()) old.doc = def.doc;
    return it->second;
  }
  const auto id = PropertyId(defs_.size());
  by_name_.emplace(def.name, id);
  defs_.push_back(std::move(def));
  index(id);
  return id;
}

void PropertyRegistry::index(PropertyId id) {
  if (2 * (defs_.size()) > table_.size()) {  // grow: rehash everything
    table_.assign(std::bit_ceil(std::max<std::size_t>(64, 4 * defs_.size())), kNoProperty);
    for (PropertyId p = 0; p < defs_.size(); ++p) {
      std::size_t i = hash(defs_[p].name) & (table_.size() - 1);
      while (table_[i] != kNoProperty) i = (i + 1) & (table_.size() - 1);
      table_[i] = p;
    }
    return;
  }
  std::size_t i = hash(defs_[id].name) & (table_.size() - 1);
  while (table_[i] != kNoProperty) i = (i + 1) & (table_.size() - 1);
  table_[i] = id;
}

void PropertyRegistry::unknown(std::string_view name) const {
  std::string msg = "unknown property '" + std::string(name) + "'";
  if (auto near = closest_name(name, names()); !near.empty()) msg += " (did you mean '" + near + "'?)";
  throw InputError(msg);
}

std::optional<EnumValue> PropertyRegistry::enum_value(PropertyId id, std::string_view value) const {
  const auto& values = defs_.at(id).enum_values;
  auto it = std::find(values.begin(), values.end(), value);
  if (it == values.end()) return std::nullopt;
  return EnumValue{std::int32_t(it - values.begin())};
}

std::string owner_text(const PropertyDef& def) {
  if (def.owner_is_mod) return "mod '" + def.owner + "'";
  if (def.owner == "runtime" || def.owner.empty()) return "the runtime";
  return "the native plugin '" + def.owner + "'";
}

std::vector<std::string> PropertyRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(by_name_.size());
  for (const auto& [name, id] : by_name_) out.push_back(name);
  return out;
}

std::string closest_name(std::string_view name, const std::vector<std::string>& candidates) {
  // Levenshtein distance; suggest only close matches so the hint helps.
  auto distance = [](std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diag = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    return row[b.size()];
  };
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, name.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = distance(name, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

}  // namespace alloy
