// Tests for runtime/property_store.hpp and runtime/access.hpp: typed columns,
// generational ids, change counters, and who may write.
#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>

#include "runtime/world.hpp"

namespace alloy {
namespace {

class PropertyStoreTest : public ::testing::Test {
 protected:
  PropertyStoreTest() : store(registry) {
    mass = registry.add({.name = "mass", .kind = PropertyKind::Number, .unit = "kg", .min = 0.0});
    position = registry.add({.name = "position", .kind = PropertyKind::Vec3, .unit = "m"});
    shape = registry.add({.name = "shape", .kind = PropertyKind::Enum, .enum_values = {"box", "sphere"}});
    count = registry.add({.name = "count", .kind = PropertyKind::Integer});
    link = registry.add({.name = "link", .kind = PropertyKind::Ref});
    name = registry.add({.name = "name", .kind = PropertyKind::String});
  }
  PropertyRegistry registry;
  PropertyStore store;
  PropertyId mass, position, shape, count, link, name;
};

TEST_F(PropertyStoreTest, RegistryFindsByNameAndRejectsConflicts) {
  EXPECT_EQ(registry.id("mass"), mass);
  EXPECT_EQ(registry.add({.name = "mass", .kind = PropertyKind::Number, .unit = "kg", .min = 0.0}), mass);
  EXPECT_THROW(registry.add({.name = "mass", .kind = PropertyKind::Vec3}), InputError);
  try {
    registry.id("mas");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'mass'"), std::string::npos) << e.what();
  }
}

TEST_F(PropertyStoreTest, ColumnsHoldTypedValuesPerObject) {
  const ObjectId a = store.create(), b = store.create();
  store.set(a, mass, 2.0);
  store.set(b, position, Vec3{1, 2, 3});
  store.set(b, shape, std::string("sphere"));
  store.set(b, count, 3.0);  // a whole number from a script is an integer
  EXPECT_TRUE(store.has(a, mass));
  EXPECT_FALSE(store.has(b, mass));
  EXPECT_EQ(std::get<double>(store.get(a, mass)), 2.0);
  EXPECT_EQ(std::get<Vec3>(store.get(b, position)), (Vec3{1, 2, 3}));
  EXPECT_EQ(std::get<EnumValue>(store.get(b, shape)).index, 1);
  EXPECT_EQ(std::get<std::int64_t>(store.get(b, count)), 3);
  store.refresh();
  const auto& col = store.typed<double>(mass);
  ASSERT_EQ(col.members().size(), 1u);
  EXPECT_EQ(col.members()[0], a.index);
}

TEST_F(PropertyStoreTest, BadValuesAreRefusedWithTheObjectName) {
  const ObjectId a = store.create();
  store.set(a, name, std::string("arm"));
  auto message = [&](auto&& fn) {
    try {
      fn();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { store.set(a, mass, -1.0); }).find("object 'arm': 'mass' must not be negative, got -1"),
            std::string::npos);
  EXPECT_NE(message([&] { store.set(a, mass, std::nan("")); }).find("'mass' must be a finite number, got nan"), std::string::npos);
  EXPECT_NE(message([&] { store.set(a, mass, Vec3{}); }).find("expects number, got vec3"), std::string::npos);
  EXPECT_NE(message([&] { store.set(a, shape, std::string("cone")); }).find("one of: box, sphere"),
            std::string::npos);
  EXPECT_NE(message([&] { store.set(a, count, 1.5); }).find("expects integer"), std::string::npos);
  EXPECT_FALSE(store.has(a, mass));  // nothing half-written
}

TEST_F(PropertyStoreTest, StaleIdsFailLoudly) {
  const ObjectId a = store.create();
  store.set(a, mass, 1.0);
  store.destroy(a);
  EXPECT_FALSE(store.alive(a));
  EXPECT_THROW(store.set(a, mass, 1.0), AccessError);
  const ObjectId b = store.create();  // reuses the slot with a new generation
  EXPECT_EQ(b.index, a.index);
  EXPECT_NE(b.generation, a.generation);
  EXPECT_FALSE(store.has(b, mass));  // the old object's values are gone
  try {
    store.get(a, mass);
    FAIL();
  } catch (const AccessError& e) {
    EXPECT_NE(std::string(e.what()).find("was destroyed"), std::string::npos);
  }
  EXPECT_THROW(store.set(b, link, a), InputError);  // a reference to a destroyed object
}

TEST_F(PropertyStoreTest, NamesAreUniqueAndIndexed) {
  const ObjectId a = store.create(), b = store.create();
  store.set(a, name, std::string("bell"));
  EXPECT_EQ(store.find("bell"), a);
  EXPECT_THROW(store.set(b, name, std::string("bell")), InputError);
  store.destroy(a);
  EXPECT_TRUE(store.find("bell").is_null());
  store.set(b, name, std::string("bell"));
  EXPECT_EQ(store.describe(b), "bell");
}

TEST_F(PropertyStoreTest, ChangeCountersMoveOnlyOnRealChanges) {
  const ObjectId a = store.create();
  store.set(a, mass, 1.0);
  const auto& col = store.typed<double>(mass);
  const auto v = col.version(), m = col.membership_version(), s = store.structure_version();
  store.set(a, mass, 1.0);
  EXPECT_EQ(col.version(), v);
  store.set(a, mass, 2.0);
  EXPECT_EQ(col.version(), v + 1);
  EXPECT_EQ(col.membership_version(), m);
  EXPECT_EQ(store.structure_version(), s);
  store.remove(a, mass);
  EXPECT_GT(col.membership_version(), m);
  EXPECT_GT(store.structure_version(), s);
}

TEST_F(PropertyStoreTest, TypedColumnAccessChecksTheKind) {
  EXPECT_THROW(store.typed<Vec3>(mass), AccessError);
  EXPECT_NO_THROW(store.typed<double>(mass));
}

// The write permission is a property of the API: a writer cannot be made from
// a column, only obtained from a ResolverAccess, and a view cannot write.
static_assert(!std::is_constructible_v<ColumnWriter<double>, Column<double>*>);
static_assert(!std::is_assignable_v<decltype(std::declval<ColumnView<double>>()[0]), double>);

TEST_F(PropertyStoreTest, OwnersDeclareBoundsThatEveryEditObeys) {
  const PropertyId e = registry.add({.name = "e", .kind = PropertyKind::Number, .min = 0.0, .max = 1.0});
  const PropertyId r = registry.add({.name = "r", .kind = PropertyKind::Number, .min = 0.0, .min_exclusive = true});
  const PropertyId size = registry.add({.name = "size", .kind = PropertyKind::Vec3, .min = 0.0, .min_exclusive = true});
  const PropertyId axis = registry.add({.name = "axis", .kind = PropertyKind::Vec3, .nonzero = true});
  const ObjectId a = store.create();
  auto message = [&](PropertyId p, const PropertyValue& v) {
    try {
      store.set(a, p, v);
    } catch (const InputError& err) {
      return err.bare();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(e, 1.0), "accepted");
  EXPECT_EQ(message(e, 1.5), "'e' must lie between 0 and 1, got 1.5");
  EXPECT_EQ(message(r, 0.0), "'r' must be greater than 0, got 0");
  EXPECT_EQ(message(size, Vec3{1, 0, 1}), "'size' must be greater than 0 in every direction, got {1, 0, 1}");
  EXPECT_EQ(message(axis, Vec3{}), "'axis' must not be the zero vector");
  EXPECT_EQ(message(axis, Vec3{0, 0, 1}), "accepted");
}

TEST(PropertyRegistryTest, FindsEveryNameAmongManyAndNoOther) {
  // The name index grows as properties are registered (a scene with every
  // plugin has over a hundred): each stays findable, unknown names are not.
  PropertyRegistry r;
  for (int i = 0; i < 300; ++i) {
    const PropertyId id = r.add({.name = "p" + std::to_string(i)});
    for (int j = 0; j <= i; j += 37) EXPECT_EQ(r.find("p" + std::to_string(j)), PropertyId(j));
    EXPECT_EQ(id, PropertyId(i));
  }
  for (int i = 0; i < 300; ++i) EXPECT_EQ(r.id("p" + std::to_string(i)), PropertyId(i));
  EXPECT_FALSE(r.find("p300").has_value());
  EXPECT_FALSE(r.find("").has_value());
  EXPECT_THROW(r.id("p3000"), InputError);
}

}  // namespace
}  // namespace alloy
