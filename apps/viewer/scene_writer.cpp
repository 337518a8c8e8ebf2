#include "apps/viewer/scene_writer.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace alloy::viewer {

namespace fs = std::filesystem;

namespace {

/// The shortest decimal that reads back as exactly `v`.
std::string number(double v) {
  char buf[40];
  for (int precision : {15, 16, 17}) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\0':
        out += "\\0";
        break;
      default:
        out += c;
    }
  }
  return out + "\"";
}

bool is_identifier(const std::string& s) {
  static const std::set<std::string> keywords = {
      "and",      "break",  "do",   "else", "elseif", "end",  "false", "for",
      "function", "goto",   "if",   "in",   "local",  "nil",  "not",   "or",
      "repeat",   "return", "then", "true", "until",  "while"};
  if (s.empty() || keywords.count(s)) return false;
  if (!(std::isalpha((unsigned char)s[0]) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return std::isalnum((unsigned char)c) || c == '_'; });
}

std::string key(const std::string& k) {
  return is_identifier(k) ? k : "[" + quoted(k) + "]";
}

std::string vec(Vec3 v) {
  return "{ " + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + " }";
}

}  // namespace

std::string write_scene(const World& world, const SceneMeta& meta) {
  const PropertyStore& store = world.store();
  const PropertyRegistry& reg = world.properties();
  const PropertyId name_id = reg.id("name");

  // Names to write: an object's own, or one made up when another refers to it.
  std::map<std::uint32_t, std::string> names;
  std::set<std::string> taken;
  for (std::uint32_t s = 0; s < store.slot_count(); ++s)
    if (ObjectId id = store.id_at(s); id && store.has(id, name_id)) {
      names[s] = std::get<std::string>(store.get(id, name_id));
      taken.insert(names[s]);
    }
  auto name_of = [&](ObjectId ref) -> std::string {
    auto it = names.find(ref.index);
    if (it != names.end()) return it->second;
    std::string n = "_" + std::to_string(ref.index);
    while (taken.count(n)) n += "_";
    taken.insert(n);
    return names[ref.index] = n;
  };

  // Properties in name order, so that a file diffs well across saves.
  std::vector<PropertyId> props;
  for (PropertyId p = 0; p < reg.size(); ++p)
    if (p != name_id) props.push_back(p);
  std::sort(props.begin(), props.end(),
            [&](PropertyId a, PropertyId b) { return reg.def(a).name < reg.def(b).name; });

  // First pass: name every object another one refers to.
  for (std::uint32_t s = 0; s < store.slot_count(); ++s) {
    const ObjectId id = store.id_at(s);
    if (!id) continue;
    for (PropertyId p : props) {
      if (!store.has(id, p)) continue;
      const PropertyValue v = store.get(id, p);
      if (const ObjectId* r = std::get_if<ObjectId>(&v); r && store.alive(*r)) name_of(*r);
      if (const RefList* l = std::get_if<RefList>(&v))
        for (ObjectId r : *l)
          if (store.alive(r)) name_of(r);
    }
  }

  std::ostringstream objects;
  for (std::uint32_t s = 0; s < store.slot_count(); ++s) {
    const ObjectId id = store.id_at(s);
    if (!id) continue;
    objects << "object {\n";
    if (auto it = names.find(s); it != names.end())
      objects << "  name = " << quoted(it->second) << ",\n";
    for (PropertyId p : props) {
      if (!store.has(id, p)) continue;
      const PropertyDef& def = reg.def(p);
      const PropertyValue v = store.get(id, p);
      std::string text;
      switch (def.kind) {
        case PropertyKind::Number: {
          const double d = std::get<double>(v);
          if (!std::isfinite(d)) continue;  // never in a world: the store refuses them
          text = number(d);
          break;
        }
        case PropertyKind::Integer:
          text = std::to_string(std::get<std::int64_t>(v));
          break;
        case PropertyKind::Bool:
          text = std::get<bool>(v) ? "true" : "false";
          break;
        case PropertyKind::Vec3:
          text = vec(std::get<Vec3>(v));
          break;
        case PropertyKind::Quat: {
          const Quat q = std::get<Quat>(v);
          text = "{ " + number(q.w) + ", " + number(q.x) + ", " + number(q.y) + ", " + number(q.z) +
                 " }";
          break;
        }
        case PropertyKind::String:
          text = quoted(std::get<std::string>(v));
          break;
        case PropertyKind::Ref: {
          const ObjectId r = std::get<ObjectId>(v);
          if (!store.alive(r)) continue;  // null: absent means the play area
          text = quoted(name_of(r));
          break;
        }
        case PropertyKind::RefList: {
          text = "{";
          for (ObjectId r : std::get<RefList>(v))
            if (store.alive(r)) text += " " + quoted(name_of(r)) + ",";
          text += " }";
          break;
        }
        case PropertyKind::Enum: {
          const auto e = std::get<EnumValue>(v).index;
          if (e < 0 || std::size_t(e) >= def.enum_values.size()) continue;
          text = quoted(def.enum_values[std::size_t(e)]);
          break;
        }
      }
      objects << "  " << key(def.name) << " = " << text << ",\n";
    }
    objects << "}\n";
  }
  const std::string body = objects.str();

  const WorldDef& def = world.def();
  std::ostringstream out;
  out << kSavedHeader << (meta.origin.empty() ? "" : " from " + meta.origin)
      << " at t = " << number(world.time()) << " s (step " << world.step_count() << ").\n"
      << "-- Every object is written property by property, as it was at that moment.\n\n";
  out << "world {\n";
  if (!meta.name.empty()) out << "  name = " << quoted(meta.name) << ",\n";
  if (!meta.description.empty()) out << "  description = " << quoted(meta.description) << ",\n";
  out << "  dt = " << number(def.dt) << ",\n";
  if (meta.seconds > 0) out << "  seconds = " << number(meta.seconds) << ",\n";
  if (!def.plugins.empty()) {
    out << "  plugins = {";
    for (const auto& p : def.plugins) out << " " << quoted(p) << ",";
    out << " },\n";
  }
  auto settings_table = [](const std::map<std::string, PluginSettings, std::less<>>& all,
                           const std::string& indent) {
    std::string t = "{\n";
    for (const auto& [plugin, settings] : all) {
      t += indent + "  [" + quoted(plugin) + "] = {";
      for (const auto& [k, v] : settings.values()) {
        std::string text;
        if (const double* d = std::get_if<double>(&v))
          text = number(*d);
        else if (const std::int64_t* i = std::get_if<std::int64_t>(&v))
          text = std::to_string(*i);
        else if (const bool* b = std::get_if<bool>(&v))
          text = *b ? "true" : "false";
        else if (const Vec3* p = std::get_if<Vec3>(&v))
          text = vec(*p);
        else if (const std::string* s = std::get_if<std::string>(&v))
          text = quoted(*s);
        else
          continue;
        t += " " + key(k) + " = " + text + ",";
      }
      t += " },\n";
    }
    return t + indent + "}";
  };
  if (!def.settings.empty()) out << "  settings = " << settings_table(def.settings, "  ") << ",\n";
  if (!def.use.empty()) {
    out << "  use = {";
    for (const auto& [what, plugin] : def.use)
      out << " " << key(what) << " = " << quoted(plugin) << ",";
    out << " },\n";
  }
  if (!def.areas.empty()) {
    out << "  areas = {\n";
    for (const AreaDef& a : def.areas) {
      out << "    { name = " << quoted(a.name);
      if (a.radius > 0)
        out << ", center = " << vec(a.center) << ", radius = " << number(a.radius);
      else if (!(a.half_extents == Vec3{}))
        out << ", center = " << vec(a.center) << ", half_extents = " << vec(a.half_extents);
      if (!a.plugins.empty()) {
        out << ", plugins = {";
        for (const auto& p : a.plugins) out << " " << quoted(p) << ",";
        out << " }";
      }
      if (!a.settings.empty())
        out << ",\n      settings = " << settings_table(a.settings, "      ");
      out << " },\n";
    }
    out << "  },\n";
  }
  if (!def.every.empty()) {
    out << "  every = {";
    for (const auto& [plugin, n] : def.every) out << " [" << quoted(plugin) << "] = " << n << ",";
    out << " },\n";
  }
  out << "}\n\n" << body;
  return out.str();
}

void write_file_whole(const fs::path& path, const std::string& data) {
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw std::runtime_error("cannot write '" + path.string() + "': no folder '" + dir.string() +
                             "'");
  const fs::path tmp = dir / ("." + path.filename().string() + ".tmp" + std::to_string(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error("cannot write '" + tmp.string() + "': " + std::strerror(errno));
    out.write(data.data(), std::streamsize(data.size()));
    out.flush();
    if (!out) {
      fs::remove(tmp, ec);
      throw std::runtime_error("cannot write '" + tmp.string() + "': " + std::strerror(errno));
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot replace '" + path.string() + "': " + ec.message());
  }
}

void save_scene(const World& world, const SceneMeta& meta, const fs::path& path) {
  write_file_whole(path, write_scene(world, meta));
}

}  // namespace alloy::viewer
