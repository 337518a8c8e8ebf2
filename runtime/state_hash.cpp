#include "runtime/state_hash.hpp"

#include <xxhash.h>

#include <algorithm>
#include <bit>
#include <cstdio>

#include "runtime/world.hpp"

namespace alloy {

namespace {

// Little-endian bytes of a plain value (alloy builds only for little-endian
// hosts; the static_assert keeps a big-endian port from hashing differently
// without notice).
static_assert(std::endian::native == std::endian::little,
              "state hashes assume a little-endian host");

template <class V>
void put(std::string& out, const V& v) {
  detail::append_bits(out, v);
}
void put_string(std::string& out, std::string_view s) {
  put(out, std::uint64_t(s.size()));
  out += s;
}
void put_id(std::string& out, ObjectId id) {
  put(out, id.index);
  put(out, id.generation);
}

std::uint64_t digest(const std::string& bytes) {
  return XXH3_64bits(bytes.data(), bytes.size());
}

void put_value(std::string& out, const PropertyValue& v) {
  put(out, std::uint8_t(v.index()));
  std::visit(
      [&](const auto& x) {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, Vec3>) {
          for (double c : {x.x, x.y, x.z}) put(out, c);
        } else if constexpr (std::is_same_v<T, Quat>) {
          for (double c : {x.w, x.x, x.y, x.z}) put(out, c);
        } else if constexpr (std::is_same_v<T, std::string>) {
          put_string(out, x);
        } else if constexpr (std::is_same_v<T, ObjectId>) {
          put_id(out, x);
        } else if constexpr (std::is_same_v<T, RefList>) {
          put(out, std::uint64_t(x.size()));
          for (ObjectId id : x) put_id(out, id);
        } else if constexpr (std::is_same_v<T, EnumValue>) {
          put(out, x.index);
        } else if constexpr (std::is_same_v<T, bool>) {
          put(out, std::uint8_t(x ? 1 : 0));
        } else {
          put(out, x);  // double, int64
        }
      },
      v);
}

void put_list(std::string& out, const std::vector<std::string>& list) {
  put(out, std::uint64_t(list.size()));
  for (const auto& s : list) put_string(out, s);
}

}  // namespace

StateHash hash_state(const Snapshot& s) {
  StateHash h;
  std::string b;

  // Columns, in name order (the snapshot keeps them so; sorted again here so
  // that the definition does not rest on it).
  std::vector<const Snapshot::Column*> columns;
  for (const auto& c : s.columns) columns.push_back(&c);
  std::sort(columns.begin(), columns.end(),
            [](const auto* x, const auto* y) { return x->property < y->property; });
  for (const Snapshot::Column* c : columns) {
    const auto present = c->values->presence();
    std::uint64_t members = 0;
    for (std::uint8_t p : present) members += p ? 1 : 0;
    if (members == 0) continue;
    b.clear();
    put_string(b, c->property);
    put(b, std::uint8_t(c->kind));
    put(b, members);
    for (std::uint32_t slot = 0; slot < present.size(); ++slot) {
      if (!present[slot]) continue;
      put(b, slot);
      c->values->encode(slot, b);
    }
    h.columns.emplace_back(c->property, digest(b));
  }

  b.clear();
  const auto& o = s.objects;
  put(b, std::uint64_t(o.generations.size()));
  for (std::size_t i = 0; i < o.generations.size(); ++i) {
    put(b, o.generations[i]);
    put(b, i < o.alive.size() ? o.alive[i] : std::uint8_t(0));
    put_string(b, i < o.names.size() ? o.names[i] : std::string());
  }
  put(b, std::uint64_t(o.free_slots.size()));
  for (std::uint32_t f : o.free_slots) put(b, f);
  h.objects = digest(b);

  b.clear();
  put(b, s.step);
  put(b, s.time);
  put(b, s.dt);
  put(b, std::uint8_t(s.started ? 1 : 0));
  put(b, std::uint8_t(s.resync ? 1 : 0));
  put(b, std::uint64_t(s.inputs.size()));
  for (const auto& in : s.inputs) {
    put(b, in.time);
    put_id(b, in.id);
    put_string(b, in.property);
    put_value(b, in.value);
  }
  put(b, std::uint64_t(s.swaps.size()));
  for (const auto& sw : s.swaps) {
    put(b, sw.time);
    put_string(b, sw.area);
    put_string(b, sw.from);
    put_string(b, sw.to);
  }
  h.schedule = digest(b);

  b.clear();
  put_list(b, s.stages);
  put(b, std::uint64_t(s.area_plugins.size()));
  for (const auto& a : s.area_plugins) put_list(b, a);
  put_list(b, s.disabled);
  put_list(b, s.enabled);
  put(b, std::uint64_t(s.use.size()));
  for (const auto& [what, plugin] : s.use) {
    put_string(b, what);
    put_string(b, plugin);
  }
  put(b, std::uint64_t(s.frozen.size()));
  for (ObjectId id : s.frozen) put_id(b, id);
  put(b, std::uint64_t(s.area_of_slot.size()));
  for (int a : s.area_of_slot) put(b, std::int32_t(a));
  put(b, std::uint64_t(s.stage_states.size()));
  for (const auto& st : s.stage_states) {
    put_string(b, st.stage);
    put(b, std::uint64_t(st.bytes.size()));
    b.append(reinterpret_cast<const char*>(st.bytes.data()), st.bytes.size());
    h.stage_states.emplace_back(st.stage, XXH3_64bits(st.bytes.data(), st.bytes.size()));
  }
  h.stages = digest(b);

  // The mods' state tables: a desync in a mod's state alone is a desync.
  for (const auto& m : s.mod_states) {
    b.clear();
    put_string(b, m.mod);
    put_string(b, m.version);
    put(b, std::uint64_t(m.bytes.size()));
    b.append(reinterpret_cast<const char*>(m.bytes.data()), m.bytes.size());
    h.mod_states.emplace_back(m.mod, digest(b));
  }

  b.clear();
  b += "alloy-state-1";
  put(b, h.objects);
  put(b, h.schedule);
  put(b, h.stages);
  put(b, std::uint64_t(h.columns.size()));
  for (const auto& [name, hash] : h.columns) {
    put_string(b, name);
    put(b, hash);
  }
  // Only when a mod saved a state, so that a world without mod state keeps
  // the hash it had before mod states were hashed.
  if (!h.mod_states.empty()) {
    b += "mods";
    put(b, std::uint64_t(h.mod_states.size()));
    for (const auto& [mod, hash] : h.mod_states) {
      put_string(b, mod);
      put(b, hash);
    }
  }
  h.world = digest(b);
  return h;
}

StateHash hash_state(const World& world) {
  return hash_state(world.snapshot());
}

std::uint64_t hash_object(const World& world, ObjectId id) {
  std::string b;
  put_id(b, id);
  const PropertyStore& store = world.store();
  put_string(b, store.alive(id) ? store.objects().names[id.index] : std::string());
  if (store.alive(id)) {
    for (const std::string& name : world.properties().names()) {
      const ColumnBase* c = store.find_column(*world.properties().find(name));
      if (!c || !c->has(id.index)) continue;
      put_string(b, name);
      c->encode(id.index, b);
    }
  }
  return digest(b);
}

std::vector<std::string> hash_differences(const StateHash& a, const StateHash& b) {
  std::vector<std::string> out;
  if (a.world == b.world) return out;
  if (a.objects != b.objects) out.push_back("objects (ids, generations, names, free list)");
  if (a.schedule != b.schedule)
    out.push_back("schedule (step, time, dt, pending inputs and swaps)");
  // Columns: a merge of two name-ordered lists.
  std::size_t i = 0, j = 0;
  while (i < a.columns.size() || j < b.columns.size()) {
    if (j == b.columns.size() ||
        (i < a.columns.size() && a.columns[i].first < b.columns[j].first)) {
      out.push_back("column '" + a.columns[i++].first + "' only in the first");
    } else if (i == a.columns.size() || b.columns[j].first < a.columns[i].first) {
      out.push_back("column '" + b.columns[j++].first + "' only in the second");
    } else {
      if (a.columns[i].second != b.columns[j].second)
        out.push_back("column '" + a.columns[i].first + "'");
      ++i, ++j;
    }
  }
  if (a.stages != b.stages) {
    bool named = false;
    for (const auto& [stage, hash] : a.stage_states) {
      auto it = std::find_if(b.stage_states.begin(), b.stage_states.end(),
                             [&](const auto& x) { return x.first == stage; });
      if (it == b.stage_states.end() || it->second != hash)
        out.push_back("state of stage '" + stage + "'"), named = true;
    }
    for (const auto& [stage, hash] : b.stage_states)
      if (std::none_of(a.stage_states.begin(), a.stage_states.end(),
                       [&](const auto& x) { return x.first == stage; }))
        out.push_back("state of stage '" + stage + "' only in the second"), named = true;
    if (!named) out.push_back("stages (stage set, areas, frozen objects)");
  }
  for (const auto& [mod, hash] : a.mod_states) {
    auto it = std::find_if(b.mod_states.begin(), b.mod_states.end(),
                           [&](const auto& x) { return x.first == mod; });
    if (it == b.mod_states.end())
      out.push_back("state of mod '" + mod + "' only in the first");
    else if (it->second != hash)
      out.push_back("state of mod '" + mod + "'");
  }
  for (const auto& [mod, hash] : b.mod_states)
    if (std::none_of(a.mod_states.begin(), a.mod_states.end(),
                     [&](const auto& x) { return x.first == mod; }))
      out.push_back("state of mod '" + mod + "' only in the second");
  if (out.empty()) out.push_back("world (the combined hash only)");
  return out;
}

std::string hex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

}  // namespace alloy
