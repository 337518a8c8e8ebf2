#include "lua/native_bindings.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>

#include "lua/stage_abi.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

// The prelude writes load records in place as abi::LoadRecord, into queues
// of the runtime's LoadRecord: the same bytes. The id packs slot and
// generation in that order (little-endian).
static_assert(sizeof(alloy::LoadRecord) == sizeof(abi::LoadRecord) &&
              offsetof(alloy::LoadRecord, slot) == 0 &&
              offsetof(alloy::LoadRecord, generation) == 4 &&
              offsetof(alloy::LoadRecord, value) == offsetof(abi::LoadRecord, vx) &&
              offsetof(alloy::LoadRecord, point) == offsetof(abi::LoadRecord, px) &&
              offsetof(alloy::LoadRecord, kind) == offsetof(abi::LoadRecord, kind));
static_assert(std::endian::native == std::endian::little);

namespace {

bool has_native_calls(const PluginDef& def) {
  return def.info.kind == StageKind::Resolver && !def.functions.empty() &&
         std::all_of(def.functions.begin(), def.functions.end(),
                     [](const InteractionFunction& f) { return bool(f.call); });
}

// Every declared resolver is bound by this one class: the calls go through
// the declaration's callables, with the target's own stage.
class DeclaredTarget final : public NativeTarget {
 public:
  DeclaredTarget(Stage& stage, const PluginDef& def)
      : stage_(stage),
        name_(def.info.name),
        fns_(def.functions),
        records_(def.records),
        decls_(declarations(def.functions)) {
    for (const auto& f : fns_) widths_.push_back(width(f.decl.args));
  }
  const std::vector<FunctionDecl>& functions() const override { return decls_; }

  void* open_records(std::size_t n) override {
    if (!records_) return nullptr;
    open_ = records_.open(stage_, n);
    return open_.data();
  }
  std::string close_records(std::size_t used, const PropertyStore& store,
                            bool ids_checked) override {
    if (!records_) return "";
    used = std::min(used, open_.size());
    if (!ids_checked)
      for (std::size_t r = 0; r < used; ++r) {
        const LoadRecord& c = open_[r];
        const ObjectId id = store.id_at(c.slot);
        if (!id || id.generation != c.generation) {
          records_.close(stage_, 0);
          open_ = {};
          return "'" + name_of_kind(c.kind) + "' on the object in slot " + std::to_string(c.slot) +
                 ", which was destroyed";
        }
      }
    records_.close(stage_, used);
    open_ = {};
    return "";
  }
  int record_kind(std::int32_t fn) const override {
    if (!records_ || fn < 0 || std::size_t(fn) >= fns_.size()) return -1;
    return fns_[std::size_t(fn)].record_kind;
  }
  void call(std::int32_t fn, ObjectId object, const double* a) override {
    function(fn).call(stage_, object, a);
  }
  std::string perform(const double* b, std::size_t n, const PropertyStore& store,
                      bool alive_checked) override {
    for (std::size_t o = 0; o < n;) {
      const auto fn = std::int32_t(b[o]);
      if (fn < 0 || std::size_t(fn) >= fns_.size())
        return "a command of an unknown interaction function";
      const InteractionFunction& f = fns_[std::size_t(fn)];
      const std::size_t stride = 2 + std::size_t(widths_[std::size_t(fn)]);
      if (o + stride > n) return "a truncated command";
      const auto slot = std::uint32_t(b[o + 1]);
      const double* args = b + o + 2;
      o += stride;
      if (!alive_checked && !store.id_at(slot))
        return "'" + f.decl.name + "' on the object in slot " + std::to_string(slot) +
               ", which was destroyed";
      // Object arguments arrive as slots: each must hold an object still. A
      // double is converted only once it is known to be a slot (a value out
      // of uint32's range is undefined behaviour to convert).
      for (std::size_t a = 0, at = 0; a < f.decl.args.size();
           at += std::size_t(width(f.decl.args[a])), ++a)
        if (f.decl.args[a] == ArgKind::Object) {
          const double s = args[at];
          if (!(s >= 0 && s < double(store.slot_count())) || !store.id_at(std::uint32_t(s)))
            return "'" + f.decl.name + "': no object in slot " + std::to_string(s);
        }
      // The slot is alive: the fast form, as a native stage's loop over a
      // column uses it, where the resolver has one.
      if (f.call_live)
        f.call_live(stage_, slot, args);
      else
        f.call(stage_, store.id_at(slot), args);
    }
    return "";
  }
  void perform_each(std::int32_t fn, std::span<const std::uint32_t> members,
                    const std::uint8_t* present, const double* v, int width,
                    const PropertyStore& store) override {
    const InteractionFunction& f = function(fn);
    if (width != widths_[std::size_t(fn)] || f.decl.args.size() != 1)
      throw AccessError("'" + f.decl.name + "' of " + name_ + " takes " + signature(f.decl) +
                        ": no bulk form of width " + std::to_string(width));
    if (f.each) {
      f.each(stage_, members, present, v, store);
      return;
    }
    // The members are live (a column's, in this phase).
    for (std::uint32_t s : members) {
      if (present[s] != 1) continue;
      const double* args = v + std::size_t(width) * s;
      if (f.call_live)
        f.call_live(stage_, s, args);
      else
        f.call(stage_, store.id_at(s), args);
    }
  }

 private:
  const InteractionFunction& function(std::int32_t fn) const {
    if (fn < 0 || std::size_t(fn) >= fns_.size())
      throw AccessError(name_ + " has no interaction function #" + std::to_string(fn));
    return fns_[std::size_t(fn)];
  }
  std::string name_of_kind(std::uint8_t kind) const {
    for (const auto& f : fns_)
      if (f.record_kind == int(kind)) return f.decl.name;
    return "a load";
  }

  Stage& stage_;
  std::string name_;
  // Copies: the registry's definition may be replaced (hot reload of a
  // plugin of that name) while this binding lives.
  std::vector<InteractionFunction> fns_;
  RecordQueue records_;
  std::vector<FunctionDecl> decls_;
  std::vector<int> widths_;
  std::span<LoadRecord> open_;  // the room of the current call
};

std::string names_where(const PluginRegistry& registry, bool (*pred)(const PluginDef&)) {
  std::string out;
  for (const auto& n : registry.order())
    if (const PluginDef* d = registry.find(n); d && pred(*d)) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

bool is_contact_set(const PluginDef& d) {
  return d.info.kind == StageKind::Derived && d.contacts;
}

}  // namespace

const PluginDef* native_resolver(const PluginRegistry& registry, std::string_view name) {
  const PluginDef* d = registry.find(name);
  return d && has_native_calls(*d) ? d : nullptr;
}

std::unique_ptr<NativeTarget> bind_native_target(PluginContext& ctx) {
  auto [stage, def] = ctx.target_stage();
  if (!has_native_calls(def))
    throw InputError("Lua interactions cannot queue on the native resolver '" + def.info.name +
                     "': it declares no interaction functions (Lua can reach: " +
                     native_resolver_names(ctx.world().plugins()) + ")");
  return std::make_unique<DeclaredTarget>(stage, def);
}

bool native_derived_readable(const PluginRegistry& registry, std::string_view set) {
  const PluginDef* d = registry.find(set);
  return d && is_contact_set(*d);
}

std::string native_resolver_names(const PluginRegistry& registry) {
  return names_where(registry, has_native_calls);
}

std::string native_contact_set_names(const PluginRegistry& registry) {
  return names_where(registry, is_contact_set);
}

}  // namespace alloy::lua
