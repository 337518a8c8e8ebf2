// Tests for frozen objects (runtime/world.hpp, World::frozen): a resolver that
// writes a non-finite value is refused, the world names the resolver, object
// and property in a "non_finite" event, and the object leaves every stage's
// scope from the next step until World::unfreeze, while the others go on.
// The stages here are small but real: a drift resolver integrating positions,
// a derived set and an interaction that record the objects they see.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "runtime/world.hpp"

namespace alloy {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<std::uint32_t> slots_of(std::span<const std::uint32_t> m) {
  return {m.begin(), m.end()};
}

/// Integrates position += velocity * dt and turns heading += 1 rad/s; on
/// request, writes a bad value into one object's property once.
class Drift : public Resolver {
 public:
  void build(ResolverAccess& a) override {
    ++builds;
    built_with = slots_of(a.column<Vec3>("position").members());
  }
  void advance(ResolverAccess& a, double dt) override {
    auto x = a.writer<Vec3>("position");
    auto heading = a.writer<double>("heading");
    auto turn = a.writer<Quat>("turn");
    const auto v = a.column<Vec3>("velocity");
    members = slots_of(x.members());
    scoped = a.scope() != nullptr;
    for (std::uint32_t s : x.members()) x.set(s, x[s] + v.value_or(s, {}) * dt);
    // With `write_heading_bad`, the poisoned heading is among the step's
    // writes in slot order: one value at a time, or all in one call
    // (ColumnWriter::set over spans).
    std::vector<std::uint32_t> slots(heading.members().begin(), heading.members().end());
    std::vector<double> values;
    for (std::uint32_t s : slots)
      values.push_back(write_heading_bad && s == poison_slot && a.step() == poison_step
                           ? kInf
                           : heading[s] + (s == still_slot ? 0.0 : dt));
    if (bulk)
      heading.set(slots, values);
    else
      for (std::size_t i = 0; i < slots.size(); ++i) heading.set(slots[i], values[i]);
    if (poison_slot != ~0u && a.step() == poison_step && !write_heading_bad) {
      if (poison == "position") x.set(poison_slot, Vec3{1, kNaN, 0});
      if (poison == "heading") heading.set(poison_slot, kInf);
      if (poison == "turn") turn.set(poison_slot, Quat{kNaN, 0, 0, 0});
      if (poison == "position twice") {  // one event per freeze
        x.set(poison_slot, Vec3{kNaN, 0, 0});
        heading.set(poison_slot, kNaN);
      }
    }
  }
  int builds = 0;
  std::vector<std::uint32_t> built_with, members;
  bool scoped = false;
  std::uint32_t poison_slot = ~0u;
  std::uint64_t poison_step = 0;
  std::string poison = "position";
  bool bulk = false;               // write `heading` with the span form of set()
  bool write_heading_bad = false;  // the poison is among the headings' writes
  std::uint32_t still_slot = ~0u;  // an object whose heading is written unchanged
};

/// A derived set: the objects it last saw carry a position.
class Seen : public DerivedSet {
 public:
  void update(const WorldView& w) override {
    members = slots_of(w.column<Vec3>("position").members());
  }
  std::vector<std::uint32_t> members;
};

/// An interaction that records the objects it sees and queues nothing.
class Watch : public Interaction {
 public:
  void apply(const WorldView& w) override {
    members = slots_of(w.column<Vec3>("position").members());
  }
  std::vector<std::uint32_t> members;
};

void register_plugins(PluginRegistry& r) {
  r.add({.info = {.name = "drift",
                  .kind = StageKind::Resolver,
                  .reads = {"position", "velocity", "heading"},
                  .writes = {"position", "heading", "turn"},
                  .needs = {"position"}},
         .properties = {{.name = "position", .kind = PropertyKind::Vec3, .unit = "m"},
                        {.name = "velocity", .kind = PropertyKind::Vec3, .unit = "m/s"},
                        {.name = "heading", .kind = PropertyKind::Number, .unit = "rad"},
                        {.name = "turn", .kind = PropertyKind::Quat}},
         .create = [](PluginContext&) { return std::make_unique<Drift>(); }});
  r.add({.info = {.name = "seen",
                  .kind = StageKind::Derived,
                  .reads = {"position"},
                  .needs = {"position"}},
         .create = [](PluginContext&) { return std::make_unique<Seen>(); }});
  r.add({.info = {.name = "watch",
                  .kind = StageKind::Interaction,
                  .derived = {"seen"},
                  .target = "drift"},
         .create = [](PluginContext&) { return std::make_unique<Watch>(); }});
}

class FrozenTest : public ::testing::Test {
 protected:
  void SetUp() override { register_plugins(registry); }
  ObjectId add(World& w, const std::string& name, Vec3 x, Vec3 v) {
    const ObjectId id = w.create(name);
    w.set(id, "position", x);
    w.set(id, "velocity", v);
    w.set(id, "heading", 0.0);
    return id;
  }
  /// a moving along x, b along z, c along -z, a metre apart.
  std::array<ObjectId, 3> add_abc(World& w) {
    return {add(w, "a", {0, 0, 0}, {1, 0, 0}), add(w, "b", {0, 1, 0}, {0, 0, 1}),
            add(w, "c", {0, 2, 0}, {0, 0, -1})};
  }
  std::vector<Event> events_of(const World& w, const std::string& type) {
    std::vector<Event> out;
    for (const Event& e : w.events())
      if (e.type == type) out.push_back(e);
    return out;
  }
  Vec3 position(const World& w, ObjectId id) { return *w.value<Vec3>(id, "position"); }
  PluginRegistry registry;
};

TEST_F(FrozenTest, ANaNWriteIsRefusedNamedAndFreezesOnlyThatObject) {
  World w(registry);
  const auto [a, b, c] = add_abc(w);
  w.run(3);
  auto& drift = dynamic_cast<Drift&>(*w.stage("drift"));
  auto& seen = dynamic_cast<Seen&>(*w.stage("seen"));
  auto& watch = dynamic_cast<Watch&>(*w.stage("watch"));
  drift.poison_slot = b.index;
  drift.poison_step = w.step_count();
  const Vec3 b_before = position(w, b);
  const int builds_before = drift.builds;
  w.step();

  // The event names the resolver, the object and the property, with the value.
  const auto bad = events_of(w, "non_finite");
  ASSERT_EQ(bad.size(), 1u);
  EXPECT_EQ(bad[0].source, "drift");
  EXPECT_EQ(bad[0].a, b);
  EXPECT_EQ(bad[0].text, "position");
  ASSERT_EQ(bad[0].values.size(), 3u);
  EXPECT_EQ(bad[0].values[0].first, "x");
  EXPECT_EQ(bad[0].values[0].second, 1.0);
  EXPECT_TRUE(std::isnan(bad[0].value("y")));
  EXPECT_EQ(frozen_message(w, bad[0]), "frozen: b: drift wrote position = {1, nan, 0}");
  // The write was refused: the value is the one written earlier in the step (finite).
  const Vec3 b_frozen = position(w, b);
  EXPECT_TRUE(is_finite(b_frozen));
  EXPECT_EQ(b_frozen, (b_before + Vec3{0, 0, 1} * w.dt()));
  EXPECT_TRUE(w.frozen(b));
  EXPECT_FALSE(w.frozen(a));
  EXPECT_EQ(w.frozen_objects(), (std::vector<ObjectId>{b}));

  // From the next step it is in no stage's scope; the resolver was rebuilt without it.
  w.run(5);
  const std::vector<std::uint32_t> others = {a.index, c.index};
  EXPECT_GT(drift.builds, builds_before);
  EXPECT_EQ(drift.built_with, others);
  EXPECT_EQ(drift.members, others);
  EXPECT_EQ(seen.members, others);
  EXPECT_EQ(watch.members, others);
  EXPECT_TRUE(events_of(w, "non_finite").empty());
  // It keeps every property, with its last finite values, and does not move.
  EXPECT_EQ(position(w, b), b_frozen);
  EXPECT_EQ(*w.value<double>(b, "heading"), 4 * w.dt());
  // The others keep stepping with finite values.
  EXPECT_DOUBLE_EQ(position(w, a).x, 9 * w.dt());
  EXPECT_DOUBLE_EQ(position(w, c).z, -9 * w.dt());
  EXPECT_TRUE(is_finite(position(w, a)) && is_finite(position(w, c)));

  // Unfrozen (an edit, after the user fixed it), it rejoins at the next step.
  w.unfreeze(b);
  EXPECT_FALSE(w.frozen(b));
  w.step();
  const std::vector<std::uint32_t> all = {a.index, b.index, c.index};
  EXPECT_EQ(drift.built_with, all);
  EXPECT_EQ(drift.members, all);
  EXPECT_EQ(seen.members, drift.members);
  EXPECT_EQ(position(w, b), (b_frozen + Vec3{0, 0, 1} * w.dt()));
  EXPECT_EQ(*w.value<double>(b, "heading"), 5 * w.dt());
}

TEST_F(FrozenTest, AWriteOfManyValuesChecksAndCountsEachAsSetDoes) {
  // Two worlds, one writing `heading` a value at a time, the other in one
  // call: an infinity among the values is refused and freezes its object
  // alone, the others are written, and the column's change counter moves
  // by the same count (a value written unchanged does not move it).
  std::vector<double> headings[2];
  std::uint64_t versions[2] = {0, 0};
  std::vector<Event> refused[2];
  for (int bulk = 0; bulk < 2; ++bulk) {
    World w(registry);
    const auto [a, b, c] = add_abc(w);
    w.run(2);
    auto& drift = dynamic_cast<Drift&>(*w.stage("drift"));
    drift.bulk = bulk != 0;
    drift.still_slot = c.index;
    drift.write_heading_bad = true;
    drift.poison_slot = b.index;
    drift.poison_step = w.step_count();
    const std::uint64_t before = w.store().column(w.properties().id("heading")).version();
    w.step();
    versions[bulk] = w.store().column(w.properties().id("heading")).version() - before;
    refused[bulk] = events_of(w, "non_finite");
    EXPECT_TRUE(w.frozen(b));
    EXPECT_FALSE(w.frozen(a) || w.frozen(c));
    for (ObjectId id : {a, b, c}) headings[bulk].push_back(*w.value<double>(id, "heading"));
  }
  // a moved, b was refused (keeps 2 dt), c was written unchanged.
  const double dt = WorldDef{}.dt;
  EXPECT_EQ(headings[1], (std::vector<double>{dt + dt + dt, dt + dt, dt + dt}));
  EXPECT_EQ(headings[0], headings[1]);
  EXPECT_EQ(versions[1], 1u);
  EXPECT_EQ(versions[0], versions[1]);
  ASSERT_EQ(refused[1].size(), 1u);
  EXPECT_EQ(refused[1][0].text, "heading");
  EXPECT_EQ(refused[0].size(), refused[1].size());
}

TEST_F(FrozenTest, InfinityInANumberAndNaNInAQuaternionAreCaughtToo) {
  for (const std::string what : {"heading", "turn"}) {
    World w(registry);
    add(w, "a", {}, {1, 0, 0});
    const ObjectId b = add(w, "b", {}, {1, 0, 0});
    w.start();
    auto& drift = dynamic_cast<Drift&>(*w.stage("drift"));
    drift.poison = what;
    drift.poison_slot = b.index;
    drift.poison_step = 0;
    w.step();
    const auto bad = events_of(w, "non_finite");
    ASSERT_EQ(bad.size(), 1u) << what;
    EXPECT_EQ(bad[0].text, what);
    EXPECT_EQ(bad[0].values.size(), what == "turn" ? 4u : 1u);
    EXPECT_TRUE(w.frozen(b));
    if (what == "heading") {
      EXPECT_EQ(*w.value<double>(b, "heading"), w.dt());  // the step's finite write stays
    } else {
      // A first write that is not finite does not give the object the property.
      EXPECT_FALSE(w.value<Quat>(b, "turn").has_value());
    }
  }
}

TEST_F(FrozenTest, OneEventPerFreezeAndTheNarratedLine) {
  World w(registry);
  const ObjectId a = add(w, "ball", {}, {});
  w.start();
  auto& drift = dynamic_cast<Drift&>(*w.stage("drift"));
  drift.poison = "position twice";
  drift.poison_slot = a.index;
  std::vector<Event> seen;
  w.add_observer([&](const Event& e) { seen.push_back(e); });
  w.step();
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].step, 1u);
  EXPECT_EQ(frozen_message(w, seen[0]), "frozen: ball: drift wrote position = {nan, 0, 0}");
  EXPECT_EQ(*w.value<double>(a, "heading"), w.dt());  // the second bad write was refused too
}

TEST_F(FrozenTest, AFrozenObjectLeavesItsAreaAndADestroyedOneIsForgotten) {
  WorldDef def;
  def.plugins = {"seen"};  // drift runs only inside the box area
  def.areas = {AreaDef{.name = "box", .half_extents = {10, 10, 10}, .plugins = {"drift"}}};
  World w(registry, def);
  const ObjectId a = add(w, "a", {0, 0, 0}, {1, 0, 0});
  const ObjectId b = add(w, "b", {0, 1, 0}, {1, 0, 0});
  w.start();
  ASSERT_TRUE(w.has_stage("drift@box"));
  auto& drift = dynamic_cast<Drift&>(*w.stage("drift@box"));
  drift.poison_slot = b.index;
  w.step();
  ASSERT_EQ(events_of(w, "non_finite").size(), 1u);
  EXPECT_EQ(events_of(w, "non_finite")[0].source, "drift@box");
  w.step();
  EXPECT_EQ(drift.members, (std::vector<std::uint32_t>{a.index}));
  EXPECT_EQ(w.area_of(b), "box");  // geometrically still there: only the stages let go
  EXPECT_EQ(dynamic_cast<Seen&>(*w.stage("seen")).members, (std::vector<std::uint32_t>{a.index}));
  w.destroy(b);
  EXPECT_TRUE(w.frozen_objects().empty());
  w.step();
  EXPECT_EQ(drift.members, (std::vector<std::uint32_t>{a.index}));
}

TEST_F(FrozenTest, AWorldWithoutFrozenObjectsGivesGlobalStagesNoScope) {
  // The check must cost nothing when nothing goes wrong: no scope filtering.
  World w(registry);
  const ObjectId a = add(w, "a", {}, {1, 0, 0});
  w.run(2);
  auto& drift = dynamic_cast<Drift&>(*w.stage("drift"));
  EXPECT_FALSE(drift.scoped);
  drift.poison_slot = a.index;
  drift.poison_step = w.step_count();
  w.step();
  w.step();
  EXPECT_TRUE(drift.scoped);
  EXPECT_TRUE(drift.members.empty());
  w.unfreeze(a);
  w.step();
  EXPECT_FALSE(drift.scoped);
  EXPECT_EQ(drift.members, (std::vector<std::uint32_t>{a.index}));
  EXPECT_TRUE(w.frozen_objects().empty());
}

}  // namespace
}  // namespace alloy
