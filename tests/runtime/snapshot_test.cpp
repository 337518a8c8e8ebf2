// Tests for runtime/snapshot.hpp and runtime/state_hash.hpp: the state hash
// sees every part of the world's state and names the part that differs;
// World::snapshot and World::restore continue a run bit for bit (ids with
// generations, pending inputs, queued commands, a stage's own state through
// Stage::save_state / restore_state); a snapshot that does not fit is refused
// before anything changes; a delta snapshot shares what did not change.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/state_hash.hpp"
#include "runtime/world.hpp"

namespace alloy {
namespace {

/// A resolver with state outside properties, as a coil has its current and a
/// noisy source its random generator: each oscillator (x, v) is pulled by a
/// hidden current that lags x, plus a small pseudo-random jolt. It performs
/// the pushes that interactions queued, at the start of its advance.
class Coil : public Resolver {
 public:
  explicit Coil(bool saves) : saves_(saves) {}
  void push(std::uint32_t slot, double dv) { queue_.push_back({slot, dv}); }

  void build(ResolverAccess& a) override {
    // Keeps what it has: the current of an object lives on across rebuilds.
    if (current_.size() < a.store().slot_count()) current_.resize(a.store().slot_count(), 0.0);
  }
  void advance(ResolverAccess& a, double dt) override {
    auto x = a.writer<double>("x");
    auto v = a.writer<double>("v");
    for (const auto& [slot, dv] : queue_)
      if (v.has(slot)) v.set(slot, v[slot] + dv);
    queue_.clear();
    for (std::uint32_t s : x.members()) {
      current_[s] += (x[s] - current_[s]) * 3.0 * dt;
      rng_ ^= rng_ << 13, rng_ ^= rng_ >> 7, rng_ ^= rng_ << 17;  // xorshift64
      const double jolt = double(rng_ >> 11) * 0x1p-53 * 1e-3;
      v.set(s, v[s] - (x[s] + 0.5 * current_[s]) * dt + jolt);
      x.set(s, x[s] + v[s] * dt);
    }
  }
  bool save_state(StateWriter& out) const override {
    if (!saves_) return false;
    out.put(rng_);
    out.put_vector(current_);
    return true;
  }
  void restore_state(StateReader& in) override {
    rng_ = in.get<std::uint64_t>();
    current_ = in.get_vector<double>();
  }

 private:
  bool saves_;
  std::uint64_t rng_ = 0x9e3779b97f4a7c15ull;
  std::vector<double> current_;  // by slot
  std::vector<std::pair<std::uint32_t, double>> queue_;
};

/// A derived set: the mean of x.
class Centroid : public DerivedSet {
 public:
  void update(const WorldView& w) override {
    auto x = w.column<double>("x");
    double sum = 0;
    for (std::uint32_t s : x.members()) sum += x[s];
    mean = x.members().empty() ? 0 : sum / double(x.members().size());
  }
  double mean = 0;
};

/// An interaction: pushes every oscillator back towards the centre.
class Centring : public Interaction {
 public:
  Centring(Coil& coil, Centroid& centroid) : coil_(coil), centroid_(centroid) {}
  void apply(const WorldView& w) override {
    for (std::uint32_t s : w.column<double>("x").members()) coil_.push(s, -0.05 * centroid_.mean);
  }

 private:
  Coil& coil_;
  Centroid& centroid_;
};

/// `saves`: whether the coil saves its state (false shows why it must).
void register_toy(PluginRegistry& r, bool saves = true) {
  r.add({.info = {.name = "coil",
                  .kind = StageKind::Resolver,
                  .reads = {"x", "v"},
                  .writes = {"x", "v"},
                  .needs = {"x"}},
         .properties = {{.name = "x", .kind = PropertyKind::Number, .unit = "m"},
                        {.name = "v", .kind = PropertyKind::Number, .unit = "m/s"},
                        {.name = "label", .kind = PropertyKind::String},
                        {.name = "links", .kind = PropertyKind::RefList}},
         .create = [saves](PluginContext&) { return std::make_unique<Coil>(saves); }});
  r.add({.info = {.name = "centroid", .kind = StageKind::Derived, .reads = {"x"}, .needs = {"x"}},
         .create = [](PluginContext&) { return std::make_unique<Centroid>(); }});
  r.add({.info = {.name = "centring",
                  .kind = StageKind::Interaction,
                  .derived = {"centroid"},
                  .target = "coil"},
         .create = [](PluginContext& c) {
           return std::make_unique<Centring>(c.target<Coil>(), c.dependency<Centroid>("centroid"));
         }});
}

/// The same little scene in any world: three oscillators, one destroyed
/// (so that the free list and a generation matter), a timeline input at
/// t = 0.1 s and a string and a reference list that never change.
void build_scene(World& w) {
  const ObjectId a = w.create("a");
  w.set(a, "x", 1.0);
  w.set(a, "v", 0.0);
  w.set(a, "label", std::string("first"));
  const ObjectId gone = w.create("gone");
  w.set(gone, "x", 5.0);
  const ObjectId b = w.create("b");
  w.set(b, "x", -0.5);
  w.set(b, "v", 0.25);
  w.set(b, "links", RefList{a});
  w.destroy(gone);
  w.schedule(0.1, b, w.properties().id("v"), 1.5);
}

struct Toy {
  explicit Toy(bool saves = true) {
    register_toy(registry, saves);
    world = std::make_unique<World>(registry, WorldDef{.dt = 0.01});
    build_scene(*world);
  }
  PluginRegistry registry;
  std::unique_ptr<World> world;
};

/// The state hash after each of `n` steps.
struct HashRun {
  std::vector<StateHash> steps;
  /// The first step that differs from `other` and the parts that differ, or "".
  std::string differs_from(const HashRun& other) const {
    for (std::size_t i = 0; i < std::max(steps.size(), other.steps.size()); ++i) {
      if (i >= steps.size() || i >= other.steps.size()) return "lengths differ";
      if (steps[i].world == other.steps[i].world) continue;
      std::string parts;
      for (const auto& d : hash_differences(other.steps[i], steps[i])) parts += " [" + d + "]";
      return "step " + std::to_string(i + 1) + " of the run differs in" + parts;
    }
    return "";
  }
  friend bool operator==(const HashRun& a, const HashRun& b) { return a.differs_from(b).empty(); }
  friend std::ostream& operator<<(std::ostream& o, const HashRun& r) {
    return o << r.steps.size() << " steps";
  }
};
HashRun hashes(World& w, int n) {
  HashRun out;
  for (int i = 0; i < n; ++i) {
    w.step();
    out.steps.push_back(hash_state(w));
  }
  return out;
}
#define EXPECT_SAME_RUN(a, b) EXPECT_EQ((a).differs_from(b), "")

TEST(StateHash, TwoRunsOfTheSameSceneHashAlikeAtEveryStep) {
  Toy one, two;
  EXPECT_EQ(hash_state(*one.world).world, hash_state(*two.world).world);
  EXPECT_SAME_RUN(hashes(*one.world, 30), hashes(*two.world, 30));
}

TEST(StateHash, OneBitOfOneValueChangesTheHashAndNamesTheColumn) {
  Toy one, two;
  one.world->run(5);
  two.world->run(5);
  const ObjectId a = two.world->find("a");
  const double x = *two.world->value<double>(a, "x");
  two.world->set(a, "x", std::nextafter(x, 2.0));  // one ulp
  const StateHash h1 = hash_state(*one.world), h2 = hash_state(*two.world);
  EXPECT_NE(h1.world, h2.world);
  EXPECT_EQ(hash_differences(h1, h2), (std::vector<std::string>{"column 'x'"}));
  EXPECT_NE(hash_object(*one.world, a), hash_object(*two.world, a));
  EXPECT_EQ(hash_object(*one.world, one.world->find("b")),
            hash_object(*two.world, two.world->find("b")));
}

TEST(StateHash, SeesGenerationsNamesPendingInputsAndStageState) {
  Toy base;
  const StateHash h = hash_state(*base.world);
  {  // the same objects and values, but a slot freed and taken again: other generations
    Toy t;
    const ObjectId extra = t.world->create();
    t.world->destroy(extra);
    EXPECT_EQ(hash_differences(h, hash_state(*t.world)),
              (std::vector<std::string>{"objects (ids, generations, names, free list)"}));
  }
  {  // one pending input more
    Toy t;
    t.world->schedule(0.5, t.world->find("a"), t.world->properties().id("x"), 0.0);
    EXPECT_EQ(hash_differences(h, hash_state(*t.world)),
              (std::vector<std::string>{"schedule (step, time, dt, pending inputs and swaps)"}));
  }
  {  // a stage's own state: the coil's hidden current
    Toy a, b;
    a.world->run(3);
    b.world->run(3);
    Snapshot s = b.world->snapshot();
    ASSERT_EQ(s.stage_states.size(), 1u);
    s.stage_states[0].bytes.back() = std::byte(std::uint8_t(s.stage_states[0].bytes.back()) ^ 1);
    EXPECT_EQ(hash_differences(hash_state(*a.world), hash_state(s)),
              (std::vector<std::string>{"state of stage 'coil'"}));
  }
}

TEST(Snapshot, RestoreContinuesBitForBitAtEveryStep) {
  for (int k : {0, 1, 7, 10, 11}) {  // before, at and after the input at t = 0.1 s
    SCOPED_TRACE("snapshot at step " + std::to_string(k));
    Toy t;
    World& w = *t.world;
    w.run(std::uint64_t(k));
    const Snapshot s = w.snapshot();
    const HashRun first = hashes(w, 25);
    // Edits after the snapshot that the restore must undo.
    const ObjectId late = w.create("late");
    w.set(late, "x", 3.0);
    w.destroy(w.find("a"));
    w.run(2);
    w.restore(s);
    EXPECT_EQ(w.step_count(), std::uint64_t(k));
    EXPECT_EQ(hash_state(w).world, hash_state(s).world);
    EXPECT_SAME_RUN(hashes(w, 25), first);
  }
}

TEST(Snapshot, RestoreIntoAnotherWorldOfTheSameScene) {
  Toy one, two;
  one.world->run(12);
  const Snapshot s = one.world->snapshot();
  const HashRun expected = hashes(*one.world, 20);
  two.world->run(3);
  two.world->restore(s);
  EXPECT_SAME_RUN(hashes(*two.world, 20), expected);
}

TEST(Snapshot, ASnapshotTakenBeforeStartRestoresUnstarted) {
  Toy t;
  const Snapshot s = t.world->snapshot();
  EXPECT_FALSE(s.started);
  const HashRun expected = hashes(*t.world, 10);
  t.world->restore(s);
  EXPECT_TRUE(t.world->active_stages().empty());
  EXPECT_SAME_RUN(hashes(*t.world, 10), expected);
}

TEST(Snapshot, WithoutItsSavedStateTheCoilDiverges) {
  // The same resolver declaring no state: the restore rebuilds it from the
  // properties, its current starts again at zero, and the run differs. This
  // is what the hook is for, and what a resolver that forgets it looks like.
  Toy t(/*saves=*/false);
  t.world->run(8);
  const Snapshot s = t.world->snapshot();
  const HashRun first = hashes(*t.world, 5);
  t.world->restore(s);
  EXPECT_NE(hashes(*t.world, 5).differs_from(first), "");
}

TEST(Snapshot, IdsKeepTheirGenerations) {
  Toy t;
  World& w = *t.world;
  w.run(2);
  const ObjectId a = w.find("a");
  const Snapshot s = w.snapshot();
  w.destroy(a);
  const ObjectId reused = w.create("reused");  // the oldest free slot: the one "gone" left
  EXPECT_FALSE(w.store().alive(a));
  w.restore(s);
  EXPECT_TRUE(w.store().alive(a));  // the id held before the snapshot is valid again
  EXPECT_EQ(w.find("a"), a);
  EXPECT_FALSE(w.store().alive(reused));  // made after it: stale
  EXPECT_EQ(w.find("reused"), ObjectId{});
  // The next id is the one the uninterrupted run would have handed out.
  Toy u;
  u.world->run(2);
  EXPECT_EQ(w.create(), u.world->create());
}

TEST(Snapshot, ASnapshotThatDoesNotFitIsRefusedBeforeAnythingChanges) {
  Toy t;
  World& w = *t.world;
  w.run(4);
  const Snapshot good = w.snapshot();
  w.run(2);
  const std::uint64_t before = hash_state(w).world;
  auto refused = [&](Snapshot s, const std::string& words) {
    try {
      w.restore(s);
      ADD_FAILURE() << "restored a snapshot that should be refused: " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
    EXPECT_EQ(hash_state(w).world, before) << words;
  };
  {
    Snapshot s = good;
    for (auto& c : s.columns)
      if (c.property == "label") c.property = "lable";
    refused(s, "property 'lable', which this world does not know");
  }
  {
    Snapshot s = good;
    for (auto& c : s.columns)
      if (c.property == "x") c.kind = PropertyKind::Integer;
    refused(s, "property 'x' is integer in it and number in this world");
  }
  {
    Snapshot s = good;
    s.objects.alive.pop_back();
    refused(s, "object table is inconsistent");
  }
  {
    Snapshot s = good;
    s.objects.free_slots.push_back(0);  // a live slot
    refused(s, "free list names slot 0");
  }
  {
    Snapshot s = good;
    s.area_plugins.push_back({});
    refused(s, "it has 1 areas, this world 0");
  }
  {
    Snapshot s = good;
    s.frozen.push_back(ObjectId{1, 1});  // the destroyed object's old id
    refused(s, "a frozen object (#1) is not alive in it");
  }
  {
    Snapshot s = good;
    s.inputs.push_back({1.0, w.find("a"), "nope", 1.0});
    refused(s, "pending input sets property 'nope'");
  }
  // What a forged save file (its checksum recomputed) can hold: each would
  // reach the stages or an engine as a live object with no values, a value
  // on a slot with no object, or a number no edit could set.
  {
    Snapshot s = good;
    s.objects.alive[0] = 0;  // 'a', not put on the free list
    refused(s, "slot 0 holds no object but is not on its free list");
  }
  {
    Snapshot s = good;
    s.objects.alive[0] = 0;
    s.objects.free_slots.push_back(0);  // on the list, but its values are still there
    refused(s, "of slot 0, which holds no object");
  }
  {
    Snapshot s = good;
    s.objects.free_slots.push_back(s.objects.free_slots.front());
    refused(s, "names slot 1 twice");
  }
  // A column as a save file's reader makes it (Column::detached), with one
  // value changed.
  auto with_value = [&]<class T>(const char* property, std::uint32_t slot, T v) {
    Snapshot s = good;
    for (auto& c : s.columns)
      if (c.property == property) {
        const auto& from = dynamic_cast<const Column<T>&>(*c.values);
        std::vector<T> values(from.values().begin(), from.values().end());
        std::vector<std::uint8_t> present(from.presence().begin(), from.presence().end());
        values.at(slot) = v;
        c.values =
            Column<T>::detached(w.properties().id(property), std::move(values), std::move(present));
      }
    return s;
  };
  refused(with_value("x", 0, std::nan("")), "'x' of slot 0 is not a finite number");
  refused(with_value("x", 0, double(HUGE_VAL)), "'x' of slot 0 is not a finite number");
  refused(with_value("links", 2, RefList{ObjectId{1, 1}}),
          "'links' of slot 2 refers to an object that is not alive in it");
}

TEST(Snapshot, DamagedStageStateIsAnErrorNamingTheStage) {
  Toy t;
  t.world->run(3);
  Snapshot s = t.world->snapshot();
  s.stage_states[0].bytes.resize(s.stage_states[0].bytes.size() - 3);  // truncated
  try {
    t.world->restore(s);
    FAIL() << "a truncated stage state was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stage 'coil'"), std::string::npos) << e.what();
  }
  s = t.world->snapshot();
  s.stage_states[0].bytes.push_back(std::byte{0});  // one byte too many
  EXPECT_THROW(t.world->restore(s), InputError);
}

TEST(Snapshot, ADeltaSharesTheColumnsThatDidNotChange) {
  Toy t;
  World& w = *t.world;
  w.run(3);
  const Snapshot base = w.snapshot();
  w.run(2);
  const Snapshot delta = w.snapshot(&base);
  EXPECT_EQ(delta.column("label")->values, base.column("label")->values);  // never changes
  EXPECT_EQ(delta.column("links")->values, base.column("links")->values);
  EXPECT_NE(delta.column("x")->values, base.column("x")->values);  // moves every step
  const Snapshot::Size size = delta.size(&base);
  EXPECT_EQ(size.shared_columns, 3u);  // label, links, name
  EXPECT_LT(size.own_bytes(), size.bytes);
  // A delta restores like a full snapshot.
  const HashRun expected = hashes(w, 10);
  w.restore(delta);
  EXPECT_SAME_RUN(hashes(w, 10), expected);
  // After a restore, nothing is shared with a snapshot taken before it: the
  // columns' counters moved, though their values are the base's again.
  w.restore(base);
  EXPECT_EQ(w.snapshot(&base).size(&base).shared_columns, 0u);
  // A base from another world shares nothing.
  Toy other;
  other.world->run(3);
  EXPECT_EQ(other.world->snapshot(&base).size(&base).shared_columns, 0u);
}

}  // namespace
}  // namespace alloy
