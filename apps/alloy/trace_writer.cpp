#include "apps/alloy/trace_writer.hpp"

#include <charconv>
#include <cstdio>
#include <filesystem>

namespace alloy::app {

namespace {

void put_number(std::ofstream& out, double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
  out.write(buf, r.ptr - buf);
}

std::string csv_quoted(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

TraceWriter::TraceWriter(const std::string& path, const World& world,
                         const std::vector<std::string>& properties)
    : path_(path), temp_(path + ".tmp") {
  for (const auto& p : properties) props_.push_back(world.properties().id(p));
  out_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError("cannot write trace file '" + path + "'");
  out_ << "step,time,object,property,value\n";
}

TraceWriter::~TraceWriter() {
  if (!closed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void TraceWriter::sample(const World& world) {
  const PropertyStore& store = world.store();
  char head[64];
  const int n = std::snprintf(head, sizeof head, "%llu,", (unsigned long long)world.step_count());
  for (std::uint32_t slot = 0; slot < store.slot_count(); ++slot) {
    const ObjectId id = store.id_at(slot);
    if (id.is_null()) continue;
    const std::string object = csv_quoted(store.describe(id));
    for (PropertyId p : props_) {
      const ColumnBase* col = store.find_column(p);
      if (!col || !col->has(slot)) continue;
      const PropertyDef& def = world.properties().def(p);
      auto row = [&](const std::string& prop, auto&& write_value) {
        out_.write(head, n);
        put_number(out_, world.time());
        out_ << ',' << object << ',' << prop << ',';
        write_value();
        out_ << '\n';
      };
      auto number = [&](const std::string& prop, double v) { row(prop, [&] { put_number(out_, v); }); };
      const PropertyValue value = col->get_value(slot);
      std::visit(
          [&](const auto& v) {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, double>) number(def.name, v);
            else if constexpr (std::is_same_v<T, std::int64_t>) row(def.name, [&] { out_ << v; });
            else if constexpr (std::is_same_v<T, bool>) row(def.name, [&] { out_ << (v ? 1 : 0); });
            else if constexpr (std::is_same_v<T, Vec3>) {
              number(def.name + ".x", v.x);
              number(def.name + ".y", v.y);
              number(def.name + ".z", v.z);
            } else if constexpr (std::is_same_v<T, Quat>) {
              number(def.name + ".w", v.w);
              number(def.name + ".x", v.x);
              number(def.name + ".y", v.y);
              number(def.name + ".z", v.z);
              number(def.name + ".angle", angle_z(v));  // the play-area angle, for 2D scenes
            } else if constexpr (std::is_same_v<T, std::string>) row(def.name, [&] { out_ << csv_quoted(v); });
            else if constexpr (std::is_same_v<T, ObjectId>) {
              row(def.name, [&] { out_ << csv_quoted(v.is_null() ? "" : store.describe(v)); });
            } else if constexpr (std::is_same_v<T, RefList>) {
              std::string names;
              for (ObjectId r : v) names += (names.empty() ? "" : ";") + store.describe(r);
              row(def.name, [&] { out_ << csv_quoted(names); });
            } else if constexpr (std::is_same_v<T, EnumValue>) {
              row(def.name, [&] { out_ << def.enum_values.at(std::size_t(v.index)); });
            }
          },
          value);
    }
  }
}

void TraceWriter::close() {
  out_.flush();
  if (!out_) throw std::runtime_error("writing trace file '" + path_ + "' failed");
  out_.close();
  std::filesystem::rename(temp_, path_);
  closed_ = true;
}

}  // namespace alloy::app
