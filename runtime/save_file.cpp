#include "runtime/save_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

#include "runtime/world.hpp"

namespace alloy {

// Every number is written as its little-endian bits, as in state hashes.
static_assert(std::endian::native == std::endian::little,
              "save files are little endian; a big-endian port must swap bytes here");

namespace {

constexpr char kMagic[8] = {'A', 'L', 'L', 'O', 'Y', 'S', 'A', 'V'};
constexpr std::size_t kPrefix = 48;
// A meta block holds names only: a few hundred KB at most for any real
// registry; far beyond that is a damaged size.
constexpr std::uint64_t kMaxMeta = 64ull << 20;

// --- writing -------------------------------------------------------------------

class Out {
 public:
  template <class T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void str(std::string_view s) {
    put<std::uint64_t>(s.size());
    bytes.append(s);
  }
  void id(ObjectId i) {
    put(i.index);
    put(i.generation);
  }
  void value(const PropertyValue& v) {
    put<std::uint8_t>(std::uint8_t(v.index()));
    std::visit(
        [&](const auto& x) {
          using T = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<T, bool>)
            put<std::uint8_t>(x ? 1 : 0);
          else if constexpr (std::is_same_v<T, Vec3>)
            put(x.x), put(x.y), put(x.z);
          else if constexpr (std::is_same_v<T, Quat>)
            put(x.w), put(x.x), put(x.y), put(x.z);
          else if constexpr (std::is_same_v<T, std::string>)
            str(x);
          else if constexpr (std::is_same_v<T, ObjectId>)
            id(x);
          else if constexpr (std::is_same_v<T, RefList>) {
            put<std::uint64_t>(x.size());
            for (ObjectId i : x) id(i);
          } else if constexpr (std::is_same_v<T, EnumValue>)
            put(x.index);
          else
            put(x);  // double, int64
        },
        v);
  }
  /// A section: tag, size, then what `fill` writes.
  template <class F>
  void section(const char* tag, F&& fill) {
    bytes.append(tag, 4);
    const std::size_t at = bytes.size();
    put<std::uint64_t>(0);
    fill(*this);
    const std::uint64_t size = bytes.size() - at - 8;
    std::memcpy(bytes.data() + at, &size, 8);
  }
  std::string bytes;
};

// --- reading -------------------------------------------------------------------

/// Reads one section's bytes; every failure names the file, the section and
/// the byte offset in the (decompressed) block.
class In {
 public:
  In(const std::string& what, std::string_view block, std::string_view part)
      : what_(what), part_(part), data_(block) {}

  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(what_ + ": " + std::string(part_) +
                     (section_.empty() ? "" : ", section '" + section_ + "'") + " at byte " +
                     std::to_string(base_ + at_) + ": " + why);
  }
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  /// A count of items of at least `min_bytes` each, checked against what is left.
  std::uint64_t count(std::size_t min_bytes, const char* what) {
    const auto n = get<std::uint64_t>();
    if (min_bytes && n > left() / min_bytes)
      fail("a count of " + std::to_string(n) + " " + what + " is more than its " +
           std::to_string(left()) + " bytes can hold");
    if (!min_bytes && n > left() + 1'000'000)  // zero-sized items: still bounded
      fail("an absurd count of " + std::to_string(n) + " " + what);
    return n;
  }
  std::string str() {
    const auto n = get<std::uint64_t>();
    if (n > left()) fail("a string of " + std::to_string(n) + " bytes runs past its end");
    std::string s(data_.substr(at_, std::size_t(n)));
    at_ += std::size_t(n);
    return s;
  }
  ObjectId id() {
    ObjectId i;
    i.index = get<std::uint32_t>();
    i.generation = get<std::uint32_t>();
    return i;
  }
  PropertyValue value() {
    const auto k = get<std::uint8_t>();
    switch (k) {
      case 0:
        return get<double>();
      case 1:
        return get<std::int64_t>();
      case 2:
        return get<std::uint8_t>() != 0;
      case 3: {
        Vec3 v;
        v.x = get<double>(), v.y = get<double>(), v.z = get<double>();
        return v;
      }
      case 4: {
        Quat q;
        q.w = get<double>(), q.x = get<double>(), q.y = get<double>(), q.z = get<double>();
        return q;
      }
      case 5:
        return str();
      case 6:
        return id();
      case 7: {
        RefList l(std::size_t(count(8, "ids")));
        for (ObjectId& i : l) i = id();
        return l;
      }
      case 8:
        return EnumValue{get<std::int32_t>()};
      default:
        fail("a value of unknown type " + std::to_string(k));
    }
  }
  /// Enters the next section, which must be `tag`; returns false (and stays)
  /// if the next section is another one and `optional`.
  bool enter(const char* tag, bool optional = false) {
    section_.clear();
    if (left() < 12) {
      if (optional) return false;
      fail(std::string("the file ends where section '") + tag + "' should start");
    }
    const std::string t(data_.substr(at_, 4));
    if (t != tag) {
      if (optional) return false;
      fail(std::string("expected section '") + tag + "', found '" + printable(t) + "'");
    }
    std::uint64_t size;
    std::memcpy(&size, data_.data() + at_ + 4, 8);
    if (size > left() - 12)
      fail("section '" + std::string(tag) + "' claims " + std::to_string(size) + " bytes, only " +
           std::to_string(left() - 12) + " are left");
    outer_ = data_;
    outer_at_ = at_ + 12 + std::size_t(size);
    base_ += at_ + 12;
    data_ = data_.substr(at_ + 12, std::size_t(size));
    at_ = 0;
    section_ = tag;
    return true;
  }
  /// Leaves the section, which must have been read to its end.
  void leave() {
    if (at_ != data_.size())
      fail(std::to_string(data_.size() - at_) + " bytes left unread at its end");
    base_ -= outer_at_ - data_.size();
    data_ = outer_;
    at_ = outer_at_;
    section_.clear();
  }
  std::size_t left() const { return data_.size() - at_; }
  bool done() const { return at_ == data_.size(); }

  static std::string printable(const std::string& s) {
    std::string o;
    for (unsigned char c : s) o += (c >= 32 && c < 127) ? char(c) : '?';
    return o;
  }

 private:
  void need(std::size_t n) {
    if (n > left())
      fail("needs " + std::to_string(n) + " more bytes, " + std::to_string(left()) + " left");
  }
  const std::string& what_;
  std::string_view part_;
  std::string_view data_, outer_;
  std::size_t at_ = 0, outer_at_ = 0, base_ = 0;
  std::string section_;
};

PropertyKind read_kind(In& in) {
  const auto k = in.get<std::uint8_t>();
  if (k > std::uint8_t(PropertyKind::Enum)) in.fail("unknown property kind " + std::to_string(k));
  return PropertyKind(k);
}

// --- the meta block ----------------------------------------------------------------

std::string encode_meta(const SaveMeta& m) {
  Out o;
  o.section("PROG", [&](Out& s) {
    s.str(m.program);
    s.str(m.program_version);
    s.str(m.kind);
  });
  o.section("SCEN", [&](Out& s) {
    s.str(m.scene);
    s.str(m.scene_name);
  });
  o.section("PROP", [&](Out& s) {
    s.put<std::uint64_t>(m.properties.size());
    for (const auto& p : m.properties) {
      s.str(p.name);
      s.put<std::uint8_t>(std::uint8_t(p.kind));
      s.put<std::uint64_t>(p.enum_values.size());
      for (const auto& e : p.enum_values) s.str(e);
    }
  });
  o.section("PLUG", [&](Out& s) {
    s.put<std::uint64_t>(m.plugins.size());
    for (const auto& p : m.plugins) s.str(p.name), s.str(p.kind);
  });
  o.section("MODS", [&](Out& s) {
    s.put<std::uint64_t>(m.mods.size());
    for (const auto& p : m.mods) s.str(p.name), s.str(p.version);
  });
  return o.bytes;
}

SaveMeta decode_meta(const std::string& what, const std::string& block) {
  In in(what, block, "meta block");
  SaveMeta m;
  in.enter("PROG");
  m.program = in.str();
  if (m.program != kSaveProgram)
    in.fail("this is a save of the program '" + In::printable(m.program) + "', not of alloy");
  m.program_version = in.str();
  m.kind = in.str();
  if (m.kind != "save" && m.kind != "replay")
    in.fail("unknown kind of file '" + In::printable(m.kind) + "'");
  in.leave();
  in.enter("SCEN");
  m.scene = in.str();
  m.scene_name = in.str();
  in.leave();
  in.enter("PROP");
  std::set<std::string> seen;
  m.properties.resize(std::size_t(in.count(17, "properties")));
  for (auto& p : m.properties) {
    p.name = in.str();
    if (!seen.insert(p.name).second) in.fail("property '" + p.name + "' is listed twice");
    p.kind = read_kind(in);
    p.enum_values.resize(std::size_t(in.count(8, "enum values")));
    for (auto& e : p.enum_values) e = in.str();
  }
  in.leave();
  in.enter("PLUG");
  m.plugins.resize(std::size_t(in.count(16, "plugins")));
  for (auto& p : m.plugins) p.name = in.str(), p.kind = in.str();
  in.leave();
  in.enter("MODS");
  m.mods.resize(std::size_t(in.count(16, "mods")));
  for (auto& p : m.mods) p.name = in.str(), p.version = in.str();
  in.leave();
  if (!in.done()) in.fail("unexpected bytes after section 'MODS'");
  return m;
}

// --- the snapshot's sections -------------------------------------------------------
//
// One entry per part of a Snapshot, in file order. A new Snapshot field is a
// new entry here (with a new tag, and kSaveFormat moved on).

struct Decoding {
  const SaveMeta& meta;
  Snapshot& s;
};

template <class T>
void put_plain_vector(Out& o, const std::vector<T>& v) {
  o.put<std::uint64_t>(v.size());
  for (const T& x : v) o.put(x);
}
template <class T>
std::vector<T> get_plain_vector(In& in, const char* what) {
  std::vector<T> v(std::size_t(in.count(sizeof(T), what)));
  for (T& x : v) x = in.get<T>();
  return v;
}
void put_strings(Out& o, const std::vector<std::string>& v) {
  o.put<std::uint64_t>(v.size());
  for (const auto& x : v) o.str(x);
}
std::vector<std::string> get_strings(In& in, const char* what) {
  std::vector<std::string> v(std::size_t(in.count(8, what)));
  for (auto& x : v) x = in.str();
  return v;
}

template <class T>
std::unique_ptr<ColumnBase> read_column(In& in, const SaveMeta::Property& p,
                                        std::vector<std::uint8_t> present) {
  std::vector<T> values(present.size());
  for (std::size_t i = 0; i < present.size(); ++i) {
    if (!present[i]) continue;
    T& v = values[i];
    if constexpr (std::is_same_v<T, Vec3>) {
      v.x = in.get<double>(), v.y = in.get<double>(), v.z = in.get<double>();
    } else if constexpr (std::is_same_v<T, Quat>) {
      v.w = in.get<double>(), v.x = in.get<double>(), v.y = in.get<double>(),
      v.z = in.get<double>();
    } else if constexpr (std::is_same_v<T, std::string>) {
      v = in.str();
    } else if constexpr (std::is_same_v<T, ObjectId>) {
      v = in.id();
    } else if constexpr (std::is_same_v<T, RefList>) {
      v.resize(std::size_t(in.count(8, "ids")));
      for (ObjectId& i : v) i = in.id();
    } else if constexpr (std::is_same_v<T, EnumValue>) {
      v.index = in.get<std::int32_t>();
      if (v.index < 0 || std::size_t(v.index) >= p.enum_values.size())
        in.fail("property '" + p.name + "' of slot " + std::to_string(i) + " has enum index " +
                std::to_string(v.index) + ", it has " + std::to_string(p.enum_values.size()) +
                " values");
    } else if constexpr (std::is_same_v<T, std::uint8_t>) {
      v = in.get<std::uint8_t>();
      if (v > 1) in.fail("property '" + p.name + "' holds a boolean that is neither 0 nor 1");
    } else {
      v = in.get<T>();
    }
  }
  return Column<T>::detached(0, std::move(values), std::move(present));
}

std::unique_ptr<ColumnBase> read_column(In& in, const SaveMeta::Property& p,
                                        std::vector<std::uint8_t> present) {
  switch (p.kind) {
    case PropertyKind::Number:
      return read_column<double>(in, p, std::move(present));
    case PropertyKind::Integer:
      return read_column<std::int64_t>(in, p, std::move(present));
    case PropertyKind::Bool:
      return read_column<std::uint8_t>(in, p, std::move(present));
    case PropertyKind::Vec3:
      return read_column<Vec3>(in, p, std::move(present));
    case PropertyKind::Quat:
      return read_column<Quat>(in, p, std::move(present));
    case PropertyKind::String:
      return read_column<std::string>(in, p, std::move(present));
    case PropertyKind::Ref:
      return read_column<ObjectId>(in, p, std::move(present));
    case PropertyKind::RefList:
      return read_column<RefList>(in, p, std::move(present));
    case PropertyKind::Enum:
      return read_column<EnumValue>(in, p, std::move(present));
  }
  in.fail("unknown property kind");
}

struct SectionCodec {
  const char* tag;
  void (*write)(Out&, const Snapshot&);
  void (*read)(In&, Decoding&);
};

const SectionCodec kSnapshotSections[] = {
    {"STEP",
     [](Out& o, const Snapshot& s) {
       o.put(s.step), o.put(s.time), o.put(s.dt), o.put<std::uint8_t>(s.started);
       o.put<std::uint8_t>(s.resync);
     },
     [](In& in, Decoding& d) {
       d.s.step = in.get<std::uint64_t>();
       d.s.time = in.get<double>();
       d.s.dt = in.get<double>();
       d.s.started = in.get<std::uint8_t>() != 0;
       d.s.resync = in.get<std::uint8_t>() != 0;
       if (!std::isfinite(d.s.time) || !(d.s.dt > 0) || !std::isfinite(d.s.dt))
         in.fail("the time or the step is not a finite number");
     }},
    {"OBJS",
     [](Out& o, const Snapshot& s) {
       put_plain_vector(o, s.objects.generations);
       put_plain_vector(o, s.objects.alive);
       put_plain_vector(o, s.objects.free_slots);
       put_strings(o, s.objects.names);
     },
     [](In& in, Decoding& d) {
       auto& ob = d.s.objects;
       ob.generations = get_plain_vector<std::uint32_t>(in, "slots");
       ob.alive = get_plain_vector<std::uint8_t>(in, "alive flags");
       ob.free_slots = get_plain_vector<std::uint32_t>(in, "free slots");
       ob.names = get_strings(in, "names");
       const std::size_t n = ob.generations.size();
       if (ob.alive.size() != n || ob.names.size() != n)
         in.fail("the object table has " + std::to_string(n) + " slots but " +
                 std::to_string(ob.alive.size()) + " alive flags and " +
                 std::to_string(ob.names.size()) + " names");
       for (std::uint32_t f : ob.free_slots)
         if (f >= n) in.fail("free slot " + std::to_string(f) + " does not exist");
     }},
    {"COLS",
     [](Out& o, const Snapshot& s) {
       o.put<std::uint64_t>(s.columns.size());
       std::string value;
       for (const auto& c : s.columns) {
         o.str(c.property);
         o.put<std::uint8_t>(std::uint8_t(c.kind));
         const auto present = c.values->presence();
         o.put<std::uint64_t>(present.size());
         o.bytes.append(reinterpret_cast<const char*>(present.data()), present.size());
         for (std::uint32_t i = 0; i < present.size(); ++i)
           if (present[i]) c.values->encode(i, o.bytes);
       }
     },
     [](In& in, Decoding& d) {
       const std::size_t slots = d.s.objects.generations.size();
       const auto n = in.count(17, "columns");
       for (std::uint64_t k = 0; k < n; ++k) {
         Snapshot::Column c;
         c.property = in.str();
         c.kind = read_kind(in);
         const auto* p = [&]() -> const SaveMeta::Property* {
           for (const auto& q : d.meta.properties)
             if (q.name == c.property) return &q;
           return nullptr;
         }();
         if (!p) in.fail("column '" + c.property + "' is not in the meta block's properties");
         if (p->kind != c.kind)
           in.fail("column '" + c.property + "' has another kind than its property");
         // In name order, each once: Snapshot::column() searches them.
         if (!d.s.columns.empty() && !(d.s.columns.back().property < c.property))
           in.fail("column '" + c.property + "' is out of name order or listed twice");
         const auto count = in.count(1, "slots");
         if (count != slots)
           in.fail("column '" + c.property + "' covers " + std::to_string(count) +
                   " slots, the object table " + std::to_string(slots));
         std::vector<std::uint8_t> present(slots);
         for (auto& b : present) {
           b = in.get<std::uint8_t>();
           if (b > 1) in.fail("column '" + c.property + "' has a presence flag that is not 0 or 1");
         }
         c.values = read_column(in, *p, std::move(present));
         d.s.columns.push_back(std::move(c));
       }
     }},
    {"FRZN", [](Out& o, const Snapshot& s) { put_plain_vector(o, s.frozen); },
     [](In& in, Decoding& d) { d.s.frozen = get_plain_vector<ObjectId>(in, "frozen objects"); }},
    {"AREA",
     [](Out& o, const Snapshot& s) {
       put_plain_vector(o, s.area_of_slot);
       o.put<std::uint64_t>(s.area_plugins.size());
       for (const auto& a : s.area_plugins) put_strings(o, a);
     },
     [](In& in, Decoding& d) {
       d.s.area_of_slot = get_plain_vector<int>(in, "area indices");
       d.s.area_plugins.resize(std::size_t(in.count(8, "areas")));
       for (auto& a : d.s.area_plugins) a = get_strings(in, "plugins");
     }},
    {"STGS",
     [](Out& o, const Snapshot& s) {
       put_strings(o, s.disabled);
       put_strings(o, s.enabled);
       o.put<std::uint64_t>(s.use.size());
       for (const auto& [k, v] : s.use) o.str(k), o.str(v);
       put_strings(o, s.stages);
     },
     [](In& in, Decoding& d) {
       d.s.disabled = get_strings(in, "plugins");
       d.s.enabled = get_strings(in, "plugins");
       const auto n = in.count(16, "providers");
       for (std::uint64_t i = 0; i < n; ++i) {
         std::string k = in.str();
         d.s.use[k] = in.str();
       }
       d.s.stages = get_strings(in, "stages");
     }},
    {"SSTA",
     [](Out& o, const Snapshot& s) {
       o.put<std::uint64_t>(s.stage_states.size());
       for (const auto& st : s.stage_states) {
         o.str(st.stage);
         o.put<std::uint64_t>(st.bytes.size());
         o.bytes.append(reinterpret_cast<const char*>(st.bytes.data()), st.bytes.size());
       }
     },
     [](In& in, Decoding& d) {
       d.s.stage_states.resize(std::size_t(in.count(16, "stage states")));
       for (auto& st : d.s.stage_states) {
         st.stage = in.str();
         const std::string b = in.str();
         st.bytes.resize(b.size());
         if (!b.empty()) std::memcpy(st.bytes.data(), b.data(), b.size());
       }
     }},
    {"MSTA",
     [](Out& o, const Snapshot& s) {
       o.put<std::uint64_t>(s.mod_states.size());
       for (const auto& m : s.mod_states) {
         o.str(m.mod);
         o.str(m.version);
         o.put<std::uint64_t>(m.bytes.size());
         o.bytes.append(reinterpret_cast<const char*>(m.bytes.data()), m.bytes.size());
       }
     },
     [](In& in, Decoding& d) {
       // The state bytes are checked by the mod's runtime when the world is
       // restored (lua/state_codec.hpp), before anything changes.
       d.s.mod_states.resize(std::size_t(in.count(24, "mod states")));
       for (auto& m : d.s.mod_states) {
         m.mod = in.str();
         m.version = in.str();
         const std::string b = in.str();
         m.bytes.resize(b.size());
         if (!b.empty()) std::memcpy(m.bytes.data(), b.data(), b.size());
       }
     }},
    {"INPT",
     [](Out& o, const Snapshot& s) {
       o.put<std::uint64_t>(s.inputs.size());
       for (const auto& i : s.inputs)
         o.put(i.time), o.id(i.id), o.str(i.property), o.value(i.value);
     },
     [](In& in, Decoding& d) {
       d.s.inputs.resize(std::size_t(in.count(26, "inputs")));
       for (auto& i : d.s.inputs) {
         i.time = in.get<double>();
         i.id = in.id();
         i.property = in.str();
         i.value = in.value();
       }
     }},
    {"SWAP",
     [](Out& o, const Snapshot& s) {
       o.put<std::uint64_t>(s.swaps.size());
       for (const auto& w : s.swaps) o.put(w.time), o.str(w.area), o.str(w.from), o.str(w.to);
     },
     [](In& in, Decoding& d) {
       d.s.swaps.resize(std::size_t(in.count(32, "swaps")));
       for (auto& w : d.s.swaps) {
         w.time = in.get<double>();
         w.area = in.str(), w.from = in.str(), w.to = in.str();
       }
     }},
};

/// A snapshot's sections, as one string (a Restore input's snapshot).
std::string encode_snapshot(const Snapshot& snap) {
  Out o;
  for (const SectionCodec& sc : kSnapshotSections)
    o.section(sc.tag, [&](Out& out) { sc.write(out, snap); });
  return std::move(o.bytes);
}

void write_log(Out& o, const std::vector<ReplayInput>& log) {
  o.put<std::uint64_t>(log.size());
  for (const auto& r : log) {
    o.put(r.step);
    o.put<std::uint8_t>(std::uint8_t(r.kind));
    o.id(r.id);
    o.str(r.property);
    o.value(r.value);
    o.str(r.area), o.str(r.from), o.str(r.to), o.str(r.text);
    if (r.kind == ReplayInput::Kind::Restore) o.str(r.snapshot ? encode_snapshot(*r.snapshot) : "");
    // Only these kinds carry a time: the log of a file without them is
    // byte for byte what it was before they were added.
    if (r.kind == ReplayInput::Kind::Schedule || r.kind == ReplayInput::Kind::ScheduleSwap)
      o.put(r.time);
  }
}

void read_log(In& in, const std::string& what, const SaveMeta& meta,
              std::vector<ReplayInput>& log) {
  log.resize(std::size_t(in.count(59, "inputs")));
  std::uint64_t last = 0;
  for (auto& r : log) {
    r.step = in.get<std::uint64_t>();
    if (r.step < last) in.fail("the inputs are not in step order");
    last = r.step;
    const auto k = in.get<std::uint8_t>();
    if (k > std::uint8_t(ReplayInput::Kind::DemandImpulses))
      in.fail("an input of unknown kind " + std::to_string(k));
    r.kind = ReplayInput::Kind(k);
    r.id = in.id();
    r.property = in.str();
    r.value = in.value();
    r.area = in.str(), r.from = in.str(), r.to = in.str(), r.text = in.str();
    if (r.kind == ReplayInput::Kind::Restore) {
      const std::string bytes = in.str();
      auto snap = std::make_shared<Snapshot>();
      const std::string inner =
          what + " (the snapshot restored before step " + std::to_string(r.step + 1) + ")";
      In sub(inner, bytes, "input");
      Decoding dec{meta, *snap};
      for (const SectionCodec& sc : kSnapshotSections) {
        sub.enter(sc.tag);
        sc.read(sub, dec);
        sub.leave();
      }
      if (!sub.done()) sub.fail("bytes after its last section");
      r.snapshot = std::move(snap);
    }
    if (r.kind == ReplayInput::Kind::Schedule || r.kind == ReplayInput::Kind::ScheduleSwap) {
      r.time = in.get<double>();
      if (!std::isfinite(r.time) || r.time < 0)
        in.fail("an input scheduled at " + std::to_string(r.time) + " s");
    }
  }
}

// Names in the hash records are indices into one table of strings, written
// first, so that a step's record is numbers only.
void write_hashes(Out& o, const std::vector<StepHashes>& hashes) {
  std::vector<std::string> names;
  std::map<std::string, std::uint32_t> index;
  auto name = [&](const std::string& n) {
    auto [it, fresh] = index.emplace(n, std::uint32_t(names.size()));
    if (fresh) names.push_back(n);
    return it->second;
  };
  Out body;
  body.put<std::uint64_t>(hashes.size());
  for (const auto& h : hashes) {
    body.put(h.step), body.put(h.world);
    body.put<std::uint64_t>(h.stages.size());
    for (const auto& [n, v] : h.stages) body.put(name(n)), body.put(v);
    body.put<std::uint64_t>(h.columns.size());
    for (const auto& [n, v] : h.columns) body.put(name(n)), body.put(v);
    body.put<std::uint64_t>(h.objects.size());
    for (const auto& [id, v] : h.objects) body.id(id), body.put(v);
  }
  put_strings(o, names);
  o.bytes += body.bytes;
}

void read_hashes(In& in, std::vector<StepHashes>& hashes) {
  const auto names = get_strings(in, "names");
  auto name = [&]() -> const std::string& {
    const auto i = in.get<std::uint32_t>();
    if (i >= names.size()) in.fail("a name index " + std::to_string(i) + " past the table");
    return names[i];
  };
  hashes.resize(std::size_t(in.count(40, "steps")));
  for (auto& h : hashes) {
    h.step = in.get<std::uint64_t>();
    h.world = in.get<std::uint64_t>();
    h.stages.resize(std::size_t(in.count(12, "stage hashes")));
    for (auto& [n, v] : h.stages) n = name(), v = in.get<std::uint64_t>();
    h.columns.resize(std::size_t(in.count(12, "column hashes")));
    for (auto& [n, v] : h.columns) n = name(), v = in.get<std::uint64_t>();
    h.objects.resize(std::size_t(in.count(16, "object hashes")));
    for (auto& [id, v] : h.objects) id = in.id(), v = in.get<std::uint64_t>();
  }
}

std::uint64_t checksum(const std::string& prefix40, std::string_view meta, std::string_view body) {
  XXH3_state_t* st = XXH3_createState();
  if (!st) throw std::bad_alloc();
  XXH3_64bits_reset(st);
  XXH3_64bits_update(st, prefix40.data(), 40);
  XXH3_64bits_update(st, meta.data(), meta.size());
  XXH3_64bits_update(st, body.data(), body.size());
  const std::uint64_t h = XXH3_64bits_digest(st);
  XXH3_freeState(st);
  return h;
}

std::string errno_text() {
  return std::strerror(errno);
}

}  // namespace

SaveMeta describe_world(const World& world) {
  SaveMeta m;
  m.program_version = ALLOY_VERSION;
  const PropertyRegistry& reg = world.properties();
  for (const std::string& name : reg.names()) {
    const PropertyDef& d = reg.def(*reg.find(name));
    m.properties.push_back({d.name, d.kind, d.enum_values});
  }
  // World::plugins() has no const overload; nothing here changes the registry.
  auto& plugins = const_cast<World&>(world).plugins();
  for (const std::string& name : plugins.order())
    if (const PluginDef* d = plugins.find(name))
      m.plugins.push_back({name, std::string(to_string(d->info.kind))});
  return m;
}

namespace {
// zstd's level for save bodies, and one compression context per thread, kept
// between saves (a fresh context allocates and clears its tables each time).
// Level 3 (zstd's default), not 9: on 1,000 falling boxes (225 KB before
// zstd) level 9 spent most of the encode compressing, at about 7 MB/s, for a
// file 2 % smaller than level 3's (docs/saves.md, "Cost").
constexpr int kZstdLevel = 3;
ZSTD_CCtx* compression_context() {
  struct Holder {
    ZSTD_CCtx* ctx = ZSTD_createCCtx();
    ~Holder() { ZSTD_freeCCtx(ctx); }
  };
  thread_local Holder holder;
  return holder.ctx;
}
}  // namespace

std::string pack_save(const SaveContainer& c) {
  // Compressed into a buffer that is not cleared first (the output is
  // written over it), and the body is not copied: at 1,000 boxes those two
  // cost more CPU than zstd at level 3 did.
  std::unique_ptr<char[]> z;
  std::size_t zn = 0;
  if (!c.body.empty()) {
    const std::size_t bound = ZSTD_compressBound(c.body.size());
    z.reset(new char[bound]);
    ZSTD_CCtx* ctx = compression_context();
    const std::size_t n =
        ctx ? ZSTD_compressCCtx(ctx, z.get(), bound, c.body.data(), c.body.size(), kZstdLevel)
            : ZSTD_compress(z.get(), bound, c.body.data(), c.body.size(), kZstdLevel);
    if (!ZSTD_isError(n) && n < c.body.size()) zn = n;  // only if it pays
  }
  const std::string_view body = zn > 0 ? std::string_view(z.get(), zn) : std::string_view(c.body);
  const std::uint32_t flags = zn > 0 ? 1 : 0;
  Out o;
  o.bytes.reserve(kPrefix + c.meta.size() + body.size());
  o.bytes.append(kMagic, 8);
  o.put(c.format);
  o.put(flags);
  o.put<std::uint64_t>(c.meta.size());
  o.put<std::uint64_t>(body.size());
  o.put<std::uint64_t>(c.body.size());
  o.put(checksum(o.bytes, c.meta, body));
  o.bytes += c.meta;
  o.bytes += body;
  return std::move(o.bytes);
}

SaveContainer unpack_save(const std::string& bytes, const std::string& what) {
  auto fail = [&](const std::string& why) -> InputError { return InputError(what + ": " + why); };
  if (bytes.empty()) throw fail("the file is empty: not a save file");
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw fail("not an alloy save file (it does not start with \"ALLOYSAV\")");
  if (bytes.size() < kPrefix)
    throw fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the " +
               std::to_string(kPrefix) + "-byte header");
  auto u32 = [&](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  auto u64 = [&](std::size_t at) {
    std::uint64_t v;
    std::memcpy(&v, bytes.data() + at, 8);
    return v;
  };
  SaveContainer c;
  c.format = u32(8);
  if (c.format > kSaveFormat)
    throw fail("save format version " + std::to_string(c.format) +
               " is newer than this alloy reads (" + std::to_string(kSaveFormat) +
               "): use a newer alloy");
  if (c.format == 0) throw fail("save format version 0 does not exist");
  const std::uint32_t flags = u32(12);
  if (flags & ~1u) throw fail("unknown flags " + std::to_string(flags) + " in the header");
  const std::uint64_t meta = u64(16), stored = u64(24), raw = u64(32);
  if (meta > kMaxMeta)
    throw fail("the header claims a meta block of " + std::to_string(meta) + " bytes");
  if (raw > kMaxBody)
    throw fail("the header claims a body of " + std::to_string(raw) + " bytes, more than the " +
               std::to_string(kMaxBody) + " a save may hold");
  if (!(flags & 1) && stored != raw) throw fail("the header's body sizes disagree");
  const std::uint64_t want = kPrefix + meta + stored;
  if (stored > kMaxBody || bytes.size() != want)
    throw fail(bytes.size() < want
                   ? "truncated: " + std::to_string(bytes.size()) + " bytes, the header says " +
                         std::to_string(want)
                   : std::to_string(bytes.size() - want) + " bytes after the end the header gives");
  const std::string_view m(bytes.data() + kPrefix, meta), b(bytes.data() + kPrefix + meta, stored);
  if (checksum(bytes.substr(0, 40), m, b) != u64(40))
    throw fail("the checksum does not match: the file is damaged");
  c.meta = std::string(m);
  if (flags & 1) {
    const unsigned long long size = ZSTD_getFrameContentSize(b.data(), b.size());
    if (size != raw) throw fail("the compressed body does not hold the size the header gives");
    c.body.resize(raw);
    const std::size_t n = ZSTD_decompress(c.body.data(), c.body.size(), b.data(), b.size());
    if (ZSTD_isError(n) || n != raw)
      throw fail(std::string("the compressed body is damaged (") +
                 (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short") + ")");
  } else {
    c.body = std::string(b);
  }
  return c;
}

std::string encode_save(const SaveData& d) {
  SaveContainer c;
  c.meta = encode_meta(d.meta);
  Out o;
  for (const SectionCodec& s : kSnapshotSections)
    o.section(s.tag, [&](Out& out) { s.write(out, d.snapshot); });
  if (d.meta.kind == "replay") {
    o.section("RLOG", [&](Out& out) { write_log(out, d.inputs); });
    o.section("RHSH", [&](Out& out) { write_hashes(out, d.hashes); });
  }
  o.section("END ", [](Out&) {});
  c.body = std::move(o.bytes);
  return pack_save(c);
}

SaveData decode_save(const std::string& bytes, const std::string& what) {
  const SaveContainer c = unpack_save(bytes, what);
  SaveData d;
  d.meta = decode_meta(what, c.meta);
  In in(what, c.body, "body");
  Decoding dec{d.meta, d.snapshot};
  for (const SectionCodec& s : kSnapshotSections) {
    in.enter(s.tag);
    s.read(in, dec);
    in.leave();
  }
  if (d.meta.kind == "replay") {
    in.enter("RLOG");
    read_log(in, what, d.meta, d.inputs);
    in.leave();
    in.enter("RHSH");
    read_hashes(in, d.hashes);
    in.leave();
  }
  in.enter("END ");
  in.leave();
  if (!in.done()) in.fail("bytes after the section 'END '");
  // What the world's restore checks again, checked here so that `alloy
  // check` says it without a world.
  const Snapshot& s = d.snapshot;
  const std::size_t slots = s.objects.generations.size();
  if (s.area_of_slot.size() > slots)
    throw InputError(what + ": section 'AREA' gives areas to slots that do not exist");
  for (int a : s.area_of_slot)
    if (a < -1 || a >= int(s.area_plugins.size()))
      throw InputError(what + ": section 'AREA' puts an object in area " + std::to_string(a) +
                       ", which does not exist");
  for (ObjectId id : s.frozen)
    if (id.index >= slots || !s.objects.alive[id.index] ||
        s.objects.generations[id.index] != id.generation)
      throw InputError(what + ": section 'FRZN': frozen object #" + std::to_string(id.index) +
                       " is not alive");
  return d;
}

bool is_save_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".alloysave" || ext == ".alloyrec") return true;  // even empty or damaged
  std::ifstream f(path, std::ios::binary);
  char magic[8] = {};
  return f.read(magic, 8) && std::memcmp(magic, kMagic, 8) == 0;
}

namespace {
/// Removes the temporary files ("NAME.tmp.PID", next to `target`) of writers
/// of `target` that died before their rename (killed, out of power): their
/// process is gone. A live writer's file (another process saving to the same
/// path now) is left alone. Errors are ignored: a file we cannot remove is
/// only clutter, and must not stop the save.
void remove_dead_writers_files(const std::filesystem::path& dir,
                               const std::filesystem::path& target) {
  namespace fs = std::filesystem;
  const std::string prefix = target.filename().string() + ".tmp.";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = pid_t(std::stol(digits));
    if (pid <= 0 || pid == ::getpid()) continue;  // ours is overwritten (O_TRUNC)
    if (::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove(it->path(), ignored);
    }
  }
}
}  // namespace

void write_file_atomic(const std::string& path, const std::string& bytes, const WriteHooks& hooks) {
  namespace fs = std::filesystem;
  auto fail = [&](const std::string& why) {
    return InputError("cannot write save file '" + path + "': " + why);
  };
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw fail("it is a folder");
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(dir, ec)) throw fail("no folder '" + dir.string() + "'");
  remove_dead_writers_files(dir, target);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw fail(errno_text());
  auto abandon = [&](const std::string& why) {
    ::close(fd);
    ::unlink(tmp.c_str());
    return fail(why);
  };
  const std::size_t chunk = std::max<std::size_t>(hooks.chunk, 1);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const std::size_t n = std::min(chunk, bytes.size() - done);
    std::size_t put = 0;
    while (put < n) {
      const ssize_t w = ::write(fd, bytes.data() + done + put, n - put);
      if (w < 0) {
        if (errno == EINTR) continue;
        throw abandon(errno_text());
      }
      put += std::size_t(w);
    }
    done += n;
    if (hooks.after_chunk) hooks.after_chunk(done);
  }
  if (::fsync(fd) != 0) throw abandon("fsync: " + errno_text());
  if (::close(fd) != 0) {
    ::unlink(tmp.c_str());
    throw fail(errno_text());
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = errno_text();
    ::unlink(tmp.c_str());
    throw fail(why);
  }
  // The rename itself is durable once the folder is on disk.
  if (const int d = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); d >= 0) {
    ::fsync(d);
    ::close(d);
  }
}

SaveData read_save_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw InputError(path + ": no such save file");
  if (fs::is_directory(st)) throw InputError(path + ": is a folder, not a save file");
  if (!fs::is_regular_file(st)) throw InputError(path + ": not a regular file");
  const auto size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read: " + ec.message());
  if (size > kMaxBody + kMaxMeta + kPrefix)
    throw InputError(path + ": " + std::to_string(size) + " bytes, larger than any save file");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": cannot open: " + errno_text());
  std::string bytes(std::size_t(size), '\0');
  if (!f.read(bytes.data(), std::streamsize(size)))
    throw InputError(path + ": cannot read it whole");
  return decode_save(bytes, path);
}

void write_save_file(const std::string& path, const SaveData& data, const WriteHooks& hooks) {
  write_file_atomic(path, encode_save(data), hooks);
}

void check_save_fits(SaveData& data, const std::string& what, const World& world,
                     const std::vector<SaveMeta::Mod>& mods, std::vector<std::string>* notes) {
  for (const SaveMeta::Mod& m : data.meta.mods) {
    const auto it = std::find_if(mods.begin(), mods.end(),
                                 [&](const SaveMeta::Mod& x) { return x.name == m.name; });
    if (it == mods.end())
      throw InputError(what + ": the save needs mod '" + m.name + "' (version " + m.version +
                       "), which the scene did not load: is it on the mod path (ALLOY_MODS)?");
    if (it->version != m.version && notes)
      notes->push_back("mod '" + m.name + "' is version " + it->version + " here, " + m.version +
                       " in the save");
  }
  const PropertyRegistry& reg = world.properties();
  for (const SaveMeta::Property& p : data.meta.properties) {
    const auto id = reg.find(p.name);
    // A property the save's registry had but nobody carries is harmless;
    // one with values is not.
    const Snapshot::Column* c = data.snapshot.column(p.name);
    const bool used = c && c->values && !c->values->members().empty();
    if (!id) {
      if (used)
        throw InputError(what + ": the save holds values of property '" + p.name + "' (" +
                         std::string(to_string(p.kind)) +
                         "), which no loaded plugin or mod registers");
      std::erase_if(data.snapshot.columns,
                    [&](const Snapshot::Column& col) { return col.property == p.name; });
      continue;
    }
    const PropertyDef& def = reg.def(*id);
    if (def.kind != p.kind)
      throw InputError(what + ": property '" + p.name + "' is " + std::string(to_string(p.kind)) +
                       " in the save and " + std::string(to_string(def.kind)) + " now (" +
                       owner_text(def) + " changed its kind)");
    if (def.kind == PropertyKind::Enum && def.enum_values != p.enum_values)
      throw InputError(what + ": the values of enum property '" + p.name + "' changed (" +
                       owner_text(def) + ")");
  }
}

}  // namespace alloy
