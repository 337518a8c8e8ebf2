#include "runtime/replay.hpp"

#include <xxhash.h>

#include <algorithm>
#include <map>
#include <set>

#include "runtime/stage.hpp"
#include "runtime/state_hash.hpp"
#include "runtime/world.hpp"

namespace alloy {

namespace {

template <class T>
void put(std::string& b, const T& v) {
  b.append(reinterpret_cast<const char*>(&v), sizeof v);
}
void put_string(std::string& b, std::string_view s) {
  put(b, std::uint64_t(s.size()));
  b.append(s);
}

/// The mod a "mod_reloaded" event names ("mod 'NAME' reloaded: ...").
std::string reloaded_mod(const std::string& text) {
  const auto a = text.find('\''), b = text.find('\'', a + 1);
  if (a == std::string::npos || b == std::string::npos) return {};
  return text.substr(a + 1, b - a - 1);
}

}  // namespace

std::uint64_t stage_hash(World& world, const std::string& stage) {
  const PropertyStore& store = world.store();
  const PropertyRegistry& reg = world.properties();
  XXH3_state_t* st = XXH3_createState();
  if (!st) throw std::bad_alloc();
  XXH3_64bits_reset(st);
  std::string b;
  for (const std::string& name : reg.names()) {
    const PropertyId id = *reg.find(name);
    const ColumnBase* c = store.find_column(id);
    if (!c) continue;
    const auto present = c->presence();  // members() may lag within a step
    b.clear();
    put_string(b, name);
    put(b, std::uint8_t(reg.def(id).kind));
    bool any = false;
    for (std::uint32_t i = 0; i < present.size(); ++i) {
      if (!present[i]) continue;
      any = true;
      put(b, i);
      c->encode(i, b);
    }
    if (any) XXH3_64bits_update(st, b.data(), b.size());
  }
  if (Stage* s = world.stage(stage)) {
    StateWriter w;
    if (s->save_state(w)) {
      b.clear();
      put_string(b, "state of " + stage);
      XXH3_64bits_update(st, b.data(), b.size());
      XXH3_64bits_update(st, w.bytes().data(), w.bytes().size());
    }
  }
  const std::uint64_t h = XXH3_64bits_digest(st);
  XXH3_freeState(st);
  return h;
}

std::vector<std::pair<ObjectId, std::uint64_t>> object_hashes(const World& world) {
  const PropertyStore& store = world.store();
  const PropertyRegistry& reg = world.properties();
  const PropertyStore::Objects objects = store.objects();
  const std::size_t slots = objects.generations.size();
  std::vector<std::string> buf(slots);
  for (std::size_t i = 0; i < slots; ++i)
    if (objects.alive[i]) put_string(buf[i], objects.names[i]);
  for (const std::string& name : reg.names()) {
    const ColumnBase* c = store.find_column(*reg.find(name));
    if (!c) continue;
    const auto present = c->presence();
    for (std::uint32_t i = 0; i < present.size() && i < slots; ++i) {
      if (!present[i] || !objects.alive[i]) continue;
      put_string(buf[i], name);
      c->encode(i, buf[i]);
    }
  }
  std::vector<std::pair<ObjectId, std::uint64_t>> out;
  for (std::uint32_t i = 0; i < slots; ++i)
    if (objects.alive[i])
      out.emplace_back(ObjectId{i, objects.generations[i]},
                       XXH3_64bits(buf[i].data(), buf[i].size()));
  return out;
}

// --- recording ---------------------------------------------------------------------

struct Recorder::State {
  SaveData data;
  std::vector<std::pair<std::string, std::uint64_t>> stages;            // of the step running
  std::map<std::string, std::uint64_t> columns;                         // as of the last step
  std::map<std::uint32_t, std::pair<ObjectId, std::uint64_t>> objects;  // by slot

  /// The recording's clock: the initial step plus the steps recorded. It
  /// is the world's step count unless an input restored another moment (the
  /// viewer's undo): inputs are placed by it, so the log stays in order.
  std::uint64_t clock() const { return data.snapshot.step + data.hashes.size(); }

  void input(World& world, const WorldInput& in);
  void after_step(World& world);
};

void Recorder::State::input(World& world, const WorldInput& in) {
  using K = WorldInput::Kind;
  if (in.kind == K::Stepped) return after_step(world);
  ReplayInput r;
  r.step = clock();
  r.id = in.id;
  r.property = in.property;
  r.value = in.value;
  switch (in.kind) {
    case K::Set:
      r.kind = ReplayInput::Kind::Set;
      break;
    case K::Remove:
      r.kind = ReplayInput::Kind::Remove;
      break;
    case K::Create:
      r.kind = ReplayInput::Kind::Create;
      r.text = in.name;
      break;
    case K::Destroy:
      r.kind = ReplayInput::Kind::Destroy;
      break;
    case K::Unfreeze:
      r.kind = ReplayInput::Kind::Unfreeze;
      break;
    case K::Swap:
      r.kind = ReplayInput::Kind::Swap;
      r.area = in.area, r.from = in.from, r.to = in.to;
      break;
    case K::PluginChanged:
      r.kind = ReplayInput::Kind::PluginChanged;
      r.text = in.name;
      break;
    case K::Restore:
      r.kind = ReplayInput::Kind::Restore;
      // A copy shares the snapshot's columns (they are immutable): cheap.
      r.snapshot = std::make_shared<const Snapshot>(*in.snapshot);
      break;
    case K::Sync:
      r.kind = ReplayInput::Kind::Sync;
      break;
    case K::Schedule:
      r.kind = ReplayInput::Kind::Schedule;
      r.time = in.time;
      break;
    case K::ScheduleSwap:
      r.kind = ReplayInput::Kind::ScheduleSwap;
      r.area = in.area, r.from = in.from, r.to = in.to;
      r.time = in.time;
      break;
    case K::DemandImpulses:
      r.kind = ReplayInput::Kind::DemandImpulses;
      break;
    case K::Stepped:
      return;
  }
  data.inputs.push_back(std::move(r));
}

Recorder::Recorder(World& world, SaveMeta meta) : world_(world), state_(std::make_shared<State>()) {
  meta.kind = "replay";
  state_->data.meta = std::move(meta);
  state_->data.snapshot = world.snapshot();
  // Not in the snapshot: a demand held when recording begins is its first input.
  if (world.impulses_demanded())
    state_->data.inputs.push_back(
        {.step = state_->clock(), .kind = ReplayInput::Kind::DemandImpulses, .value = true});
  std::weak_ptr<State> weak = state_;
  world.set_stage_hook([weak, &world](const std::string& stage) {
    if (auto s = weak.lock()) s->stages.emplace_back(stage, stage_hash(world, stage));
  });
  // Observers cannot be removed: these hold the state weakly and go quiet
  // once the recorder is gone.
  world.add_input_observer([weak, &world](const WorldInput& in) {
    if (auto s = weak.lock()) s->input(world, in);
  });
  world.add_observer([weak](const Event& e) {
    auto s = weak.lock();
    if (!s) return;
    ReplayInput r;
    r.step = s->clock();  // the step being published (or, a reload's, the one before)
    if (e.type == "input" && e.source == "schedule") {
      r.kind = ReplayInput::Kind::Timeline;
      r.id = e.a;
      r.text = e.text;
    } else if (e.type == "resolver_swapped") {
      // A swap from outside is logged already (as Swap).
      for (const auto& in : s->data.inputs)
        if (in.kind == ReplayInput::Kind::Swap && in.step == r.step) return;
      r.kind = ReplayInput::Kind::Swapped;
      r.text = e.text;
    } else if (e.type == "mod_reloaded") {
      r.kind = ReplayInput::Kind::Reload;
      r.text = reloaded_mod(e.text);
      for (const auto& in : s->data.inputs)
        if (in.kind == ReplayInput::Kind::Reload && in.step == r.step && in.text == r.text)
          return;  // logged by reloaded()
    } else {
      return;
    }
    s->data.inputs.push_back(std::move(r));
  });
}

Recorder::~Recorder() {
  world_.set_stage_hook({});
}

void Recorder::reloaded(const std::string& mod) {
  ReplayInput r;
  r.step = state_->clock();
  r.kind = ReplayInput::Kind::Reload;
  r.text = mod;
  state_->data.inputs.push_back(std::move(r));
}

std::size_t Recorder::steps() const {
  return state_->data.hashes.size();
}

void Recorder::State::after_step(World& world) {
  State& s = *this;
  StepHashes h;
  h.step = world.step_count();
  const StateHash sh = hash_state(world);
  h.world = sh.world;
  h.stages = std::move(s.stages);
  s.stages.clear();
  for (const auto& [name, v] : sh.columns) {
    auto [it, fresh] = s.columns.emplace(name, v);
    if (fresh || it->second != v) h.columns.emplace_back(name, v), it->second = v;
  }
  // A column that lost its last member: recorded as gone (hash 0).
  for (auto& [name, v] : s.columns) {
    const bool still = std::any_of(sh.columns.begin(), sh.columns.end(),
                                   [&](const auto& c) { return c.first == name; });
    if (!still && v != 0) h.columns.emplace_back(name, 0), v = 0;
  }
  std::map<std::uint32_t, std::pair<ObjectId, std::uint64_t>> now;
  for (const auto& [id, v] : object_hashes(world)) {
    now[id.index] = {id, v};
    const auto it = s.objects.find(id.index);
    if (it == s.objects.end() || it->second != std::pair{id, v}) h.objects.emplace_back(id, v);
  }
  for (const auto& [slot, was] : s.objects)
    if (!now.contains(slot)) h.objects.emplace_back(ObjectId{slot, 0}, 0);  // died
  s.objects = std::move(now);
  s.data.hashes.push_back(std::move(h));
}

const SaveData& Recorder::data() const {
  return state_->data;
}

void Recorder::write(const std::string& path) const {
  write_save_file(path, state_->data);
}

// --- replaying -----------------------------------------------------------------------

std::string ReplayResult::message() const {
  if (identical) return "identical through step " + std::to_string(last_step);
  std::string m = "differs at step " + std::to_string(step);
  m += stage.empty() ? ", before or outside the stages (no stage's hash differs)"
                     : ", first after stage '" + stage + "'";
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s.empty() ? std::string("none") : s;
  };
  m += "\n  properties that differ: " + list(properties);
  m += "\n  objects that differ: " + list(objects);
  return m;
}

namespace {

/// Applies the log's inputs due before the next step: those logged at the
/// recording's clock `clock` (the initial step plus the steps replayed).
void apply_inputs(World& w, const SaveData& data, std::size_t& next, const ReplayOptions& o,
                  std::uint64_t clock) {
  const auto& log = data.inputs;
  while (next < log.size() && log[next].step <= clock) {
    const ReplayInput& r = log[next++];
    switch (r.kind) {
      case ReplayInput::Kind::Set:
        w.set(r.id, r.property, r.value);
        break;
      case ReplayInput::Kind::Swap:
        w.swap(r.area, r.from, r.to);
        break;
      case ReplayInput::Kind::Reload:
        if (!o.reload)
          throw InputError("the recording reloads mod '" + r.text + "' before step " +
                           std::to_string(r.step + 1) + ", and this replay cannot reload mods");
        o.reload(w, r.text);
        break;
      case ReplayInput::Kind::Remove:
        w.remove(r.id, r.property);
        break;
      case ReplayInput::Kind::Create:
        if (const ObjectId made = w.create(r.text); made != r.id)
          throw InputError("the replay's create before step " + std::to_string(r.step + 1) +
                           " made object #" + std::to_string(made.index) +
                           " where the recording made #" + std::to_string(r.id.index) +
                           ": the object tables have parted");
        break;
      case ReplayInput::Kind::Destroy:
        w.destroy(r.id);
        break;
      case ReplayInput::Kind::Unfreeze:
        w.unfreeze(r.id);
        break;
      case ReplayInput::Kind::PluginChanged:
        w.plugin_changed(r.text);
        break;
      case ReplayInput::Kind::Restore:
        if (!r.snapshot)
          throw InputError("the recording restores a snapshot before step " +
                           std::to_string(r.step + 1) + " that it does not hold");
        w.restore(*r.snapshot);
        break;
      case ReplayInput::Kind::Sync:
        w.sync();
        break;
      case ReplayInput::Kind::Schedule:
        w.schedule(r.time, r.id, w.properties().id(r.property), r.value);
        break;
      case ReplayInput::Kind::ScheduleSwap:
        w.schedule_swap(r.time, r.area, r.from, r.to);
        break;
      case ReplayInput::Kind::DemandImpulses: {
        const bool* on = std::get_if<bool>(&r.value);
        if (!on)
          throw InputError("the recording's impulse demand before step " +
                           std::to_string(r.step + 1) + " is not true or false");
        w.demand_impulses(*on);
        break;
      }
      case ReplayInput::Kind::Timeline:
      case ReplayInput::Kind::Swapped:
        break;  // the world makes them from its snapshot
    }
  }
}

}  // namespace

ReplayResult replay(const SaveData& data, const std::function<World&()>& rebuild,
                    const ReplayOptions& options) {
  if (data.meta.kind != "replay")
    throw InputError("the file is a save, not a recording: continue it with `alloy run FILE`");
  ReplayResult result;
  std::size_t diverged = data.hashes.size();
  {
    World& w = rebuild();
    w.restore(data.snapshot);
    result.last_step = w.step_count();
    if (options.tamper)
      w.set_stage_hook(
          [&](const std::string& stage) { options.tamper(w, w.step_count() + 1, stage); });
    std::size_t next = 0;
    std::map<std::string, std::uint64_t> columns;
    std::map<std::uint32_t, std::pair<ObjectId, std::uint64_t>> objects;
    for (std::size_t i = 0; i < data.hashes.size(); ++i) {
      const StepHashes& h = data.hashes[i];
      for (const auto& [n, v] : h.columns) columns[n] = v;
      for (const auto& [id, v] : h.objects)
        if (id.generation == 0 && v == 0)
          objects.erase(id.index);
        else
          objects[id.index] = {id, v};
      apply_inputs(w, data, next, options, data.snapshot.step + i);
      w.step();
      if (w.step_count() != h.step)
        throw InputError("the recording's steps do not follow: step " +
                         std::to_string(w.step_count()) + " ran where it has step " +
                         std::to_string(h.step));
      const StateHash now = hash_state(w);
      if (now.world == h.world) {
        ++result.steps;
        result.last_step = h.step;
        continue;
      }
      diverged = i;
      result.identical = false;
      result.step = h.step;
      for (const auto& [n, v] : now.columns) {
        const auto it = columns.find(n);
        if (it == columns.end() || it->second != v) result.properties.push_back(n);
      }
      for (const auto& [n, v] : columns)
        if (v != 0 && std::none_of(now.columns.begin(), now.columns.end(),
                                   [&](const auto& c) { return c.first == n; }))
          result.properties.push_back(n);
      std::set<std::uint32_t> seen;
      for (const auto& [id, v] : object_hashes(w)) {
        seen.insert(id.index);
        const auto it = objects.find(id.index);
        if (it == objects.end() || it->second != std::pair{id, v})
          result.objects.push_back(w.describe(id));
      }
      for (const auto& [slot, rec] : objects)
        if (!seen.contains(slot))
          result.objects.push_back("#" + std::to_string(slot) + " (alive in the recording)");
      w.set_stage_hook({});
      break;
    }
    if (result.identical) {
      w.set_stage_hook({});
      return result;
    }
  }
  // Run again to the step that differs, hashing after each of its stages.
  World& w = rebuild();
  w.restore(data.snapshot);
  const StepHashes& h = data.hashes[diverged];
  std::vector<std::pair<std::string, std::uint64_t>> stages;
  bool hashing = false;
  w.set_stage_hook([&](const std::string& stage) {
    if (options.tamper) options.tamper(w, w.step_count() + 1, stage);
    if (hashing) stages.emplace_back(stage, stage_hash(w, stage));
  });
  std::size_t next = 0;
  for (std::size_t i = 0; i <= diverged; ++i) {
    apply_inputs(w, data, next, options, data.snapshot.step + i);
    hashing = i == diverged;
    w.step();
  }
  w.set_stage_hook({});
  for (std::size_t j = 0; j < std::max(stages.size(), h.stages.size()); ++j) {
    if (j < stages.size() && j < h.stages.size() && stages[j] == h.stages[j]) continue;
    result.stage = j < h.stages.size() ? h.stages[j].first : stages[j].first;
    break;
  }
  return result;
}

}  // namespace alloy
