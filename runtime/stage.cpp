#include "runtime/stage.hpp"

namespace alloy {

std::string_view to_string(StageKind kind) {
  switch (kind) {
    case StageKind::Resolver: return "resolver";
    case StageKind::Derived: return "derived";
    case StageKind::Interaction: return "interaction";
  }
  return "?";
}

namespace {
template <class T>
const T* find_as(const std::map<std::string, PropertyValue, std::less<>>& m, std::string_view key) {
  auto it = m.find(key);
  return it == m.end() ? nullptr : std::get_if<T>(&it->second);
}

[[noreturn]] void wrong_type(const ErrorLocation& where, std::string_view key, const char* expected) {
  throw InputError(where, "setting '" + std::string(key) + "' must be " + expected);
}
}  // namespace

double PluginSettings::number(std::string_view key, double fallback) const {
  if (!has(key)) return fallback;
  if (const double* d = find_as<double>(values_, key)) return *d;
  if (const std::int64_t* i = find_as<std::int64_t>(values_, key)) return double(*i);
  wrong_type(where, key, "a number");
}

std::int64_t PluginSettings::integer(std::string_view key, std::int64_t fallback) const {
  if (!has(key)) return fallback;
  if (const std::int64_t* i = find_as<std::int64_t>(values_, key)) return *i;
  if (const double* d = find_as<double>(values_, key); d && double(std::int64_t(*d)) == *d)
    return std::int64_t(*d);
  wrong_type(where, key, "an integer");
}

bool PluginSettings::boolean(std::string_view key, bool fallback) const {
  if (!has(key)) return fallback;
  if (const bool* b = find_as<bool>(values_, key)) return *b;
  wrong_type(where, key, "true or false");
}

Vec3 PluginSettings::vec3(std::string_view key, Vec3 fallback) const {
  if (!has(key)) return fallback;
  if (const Vec3* v = find_as<Vec3>(values_, key)) return *v;
  wrong_type(where, key, "a vector {x, y, z}");
}

std::string PluginSettings::string(std::string_view key, std::string fallback) const {
  if (!has(key)) return fallback;
  if (const std::string* s = find_as<std::string>(values_, key)) return *s;
  wrong_type(where, key, "a string");
}

void PluginSettings::check_known(std::string_view plugin, const std::vector<std::string>& known) const {
  for (const auto& [key, value] : values_) {
    bool ok = false;
    for (const auto& k : known) ok = ok || k == key;
    if (!ok) {
      std::string msg = "plugin '" + std::string(plugin) + "' has no setting '" + key + "'";
      if (auto near = closest_name(key, known); !near.empty()) msg += " (did you mean '" + near + "'?)";
      throw InputError(where, msg);
    }
  }
}

}  // namespace alloy
