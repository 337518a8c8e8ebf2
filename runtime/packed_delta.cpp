#include "runtime/packed_delta.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "runtime/error.hpp"

namespace alloy {
namespace {

/// The column's values as 8-byte words, or null if its kind is not one of them.
template <class T>
const std::uint64_t* words_of(const ColumnBase& c, std::size_t& n) {
  if (const auto* t = dynamic_cast<const Column<T>*>(&c)) {
    n = t->values().size() * (sizeof(T) / 8);
    return reinterpret_cast<const std::uint64_t*>(t->values().data());
  }
  return nullptr;
}
const std::uint64_t* words(const ColumnBase& c, std::size_t& n) {
  static_assert(sizeof(Vec3) == 24 && sizeof(Quat) == 32);
  if (auto* w = words_of<double>(c, n)) return w;
  if (auto* w = words_of<Vec3>(c, n)) return w;
  if (auto* w = words_of<Quat>(c, n)) return w;
  if (auto* w = words_of<std::int64_t>(c, n)) return w;
  return nullptr;
}

void pack(const std::uint64_t* now, const std::uint64_t* then, std::size_t n,
          std::vector<std::byte>& out) {
  // Counts first (two a byte), then the kept low bytes of each word's XOR.
  out.assign((n + 1) / 2 + n * 8, std::byte{0});
  auto* counts = reinterpret_cast<std::uint8_t*>(out.data());
  auto* at = reinterpret_cast<std::uint8_t*>(out.data()) + (n + 1) / 2;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t x = now[i] ^ then[i];
    const unsigned keep = x ? 8 - unsigned(std::countl_zero(x)) / 8 : 0;
    counts[i / 2] |= std::uint8_t(keep << (4 * (i % 2)));
    std::memcpy(at, &x, 8);  // little endian: the low bytes first; the rest overwritten next
    at += keep;
  }
  out.resize(std::size_t(at - reinterpret_cast<std::uint8_t*>(out.data())));
}

void unpack(const std::vector<std::byte>& in, const std::uint64_t* then, std::uint64_t* now,
            std::size_t n) {
  const std::size_t head = (n + 1) / 2;
  if (in.size() < head) throw InputError("a packed delta column is cut short");
  const auto* counts = reinterpret_cast<const std::uint8_t*>(in.data());
  const auto* at = counts + head;
  const auto* end = counts + in.size();
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned keep = (counts[i / 2] >> (4 * (i % 2))) & 0xf;
    if (keep > 8 || std::size_t(end - at) < keep)
      throw InputError("a packed delta column is damaged");
    std::uint64_t x = 0;
    std::memcpy(&x, at, keep);
    at += keep;
    now[i] = then[i] ^ x;
  }
  if (at != end) throw InputError("a packed delta column has bytes left over");
}

}  // namespace

std::size_t PackedDelta::bytes(const Snapshot& base) const {
  std::size_t n = sizeof(PackedDelta);
  for (const auto& c : rest.columns) {  // as Snapshot::size counts: shared columns are the base's
    const Snapshot::Column* b = base.column(c.property);
    if (c.values && b && b->values == c.values) continue;
    n += sizeof(Snapshot::Column) + c.property.size() + (c.values ? c.values->bytes() : 0);
  }
  for (const auto& p : packed) n += p.size();
  n += rest.objects.generations.size() * (sizeof(std::uint32_t) + 1 + sizeof(std::string));
  n += rest.objects.free_slots.size() * sizeof(std::uint32_t) +
       rest.area_of_slot.size() * sizeof(int);
  n += rest.frozen.size() * sizeof(ObjectId) + rest.inputs.size() * sizeof(Snapshot::Input) +
       rest.swaps.size() * sizeof(Snapshot::Swap);
  for (const auto& st : rest.stage_states) n += st.bytes.size() + st.stage.size();
  return n;
}

PackedDelta pack_delta(const Snapshot& base, const Snapshot& s) {
  PackedDelta d;
  d.rest.step = s.step, d.rest.time = s.time, d.rest.dt = s.dt, d.rest.started = s.started;
  d.rest.resync = s.resync;
  d.same_objects =
      s.objects.generations == base.objects.generations && s.objects.alive == base.objects.alive &&
      s.objects.free_slots == base.objects.free_slots && s.objects.names == base.objects.names;
  if (!d.same_objects) d.rest.objects = s.objects;
  d.same_areas = s.area_of_slot == base.area_of_slot;
  if (!d.same_areas) d.rest.area_of_slot = s.area_of_slot;
  d.rest.frozen = s.frozen;
  d.rest.area_plugins = s.area_plugins;
  d.rest.disabled = s.disabled;
  d.rest.enabled = s.enabled;
  d.rest.use = s.use;
  d.rest.stages = s.stages;
  d.rest.stage_states = s.stage_states;
  d.rest.inputs = s.inputs;
  d.rest.swaps = s.swaps;
  d.rest.lineage = s.lineage;
  d.rest.columns.reserve(s.columns.size());
  for (const Snapshot::Column& c : s.columns) {
    Snapshot::Column out = c;
    const Snapshot::Column* b = base.column(c.property);
    std::size_t n = 0, nb = 0;
    const std::uint64_t *now = nullptr, *then = nullptr;
    if (b && b->values != c.values && b->kind == c.kind &&
        std::ranges::equal(b->values->presence(), c.values->presence()) &&
        (now = words(*c.values, n)) && (then = words(*b->values, nb)) && n == nb) {
      d.packed.emplace_back();
      pack(now, then, n, d.packed.back());
      out.values = nullptr;
    }
    d.rest.columns.push_back(std::move(out));
  }
  return d;
}

Snapshot unpack_delta(const Snapshot& base, const PackedDelta& d) {
  Snapshot s = d.rest;
  if (d.same_objects) s.objects = base.objects;
  if (d.same_areas) s.area_of_slot = base.area_of_slot;
  std::size_t k = 0;
  for (Snapshot::Column& c : s.columns) {
    if (c.values) continue;
    const Snapshot::Column* b = base.column(c.property);
    if (!b || k >= d.packed.size())
      throw InputError("a packed delta's column '" + c.property + "' is not in its base");
    std::unique_ptr<ColumnBase> col = b->values->clone();  // ours alone until shared below
    std::size_t n = 0, nb = 0;
    const std::uint64_t* then = words(*b->values, nb);
    const std::uint64_t* mine = words(*col, n);
    if (!then || !mine || n != nb)
      throw InputError("a packed delta's column '" + c.property + "' does not fit its base");
    // The clone is not const: writing its values through the span is writing our own object.
    unpack(d.packed[k++], then, const_cast<std::uint64_t*>(mine), n);
    c.values = std::move(col);
  }
  if (k != d.packed.size()) throw InputError("a packed delta has columns left over");
  return s;
}

}  // namespace alloy
