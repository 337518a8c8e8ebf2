// Contact data shared by the collisions derived set, the interaction that feeds
// contacts to the rigid body, and the rigid body's published impulses.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"

namespace alloy::rigid {

/// One point of contact between two parts a and b (a < b by ObjectId).
struct ContactPoint {
  Vec3 position;      ///< world frame, m
  /// Unit normal pointing from b towards a: moving a along +normal by `depth`
  /// separates the parts (ODE's convention with a as body 1).
  Vec3 normal;
  double depth = 0;   ///< penetration, m (>= 0)
};

/// The impulse the rigid body applied to a pair of parts over its last advance.
struct PairImpulse {
  ObjectId a, b;             ///< a < b
  Vec3 impulse;              ///< total contact impulse on a (normal and friction), N*s; b got -impulse
  double normal_impulse = 0; ///< its normal part, N*s (>= 0)
};

/// A stage's declaration that it reads contact impulses (ContactPair::impulse,
/// normal_impulse, total_impulse, the impulse of contact_ended). The rigid
/// body computes them (ODE's joint feedback on every contact joint, about 2 %
/// of a pile's step) only while at least one demand is held: a scene pays
/// nothing for impulses nobody reads. Hold it for as long as the stage reads
/// them (a member); it may outlive the rigid body it was taken from.
class ImpulseDemand {
 public:
  ImpulseDemand() = default;
  explicit ImpulseDemand(std::shared_ptr<std::size_t> count) : count_(std::move(count)) {
    if (count_) ++*count_;
  }
  ImpulseDemand(ImpulseDemand&& o) noexcept = default;
  ImpulseDemand& operator=(ImpulseDemand&& o) noexcept {
    if (this != &o) release(), count_ = std::move(o.count_);
    return *this;
  }
  ImpulseDemand(const ImpulseDemand&) = delete;
  ImpulseDemand& operator=(const ImpulseDemand&) = delete;
  ~ImpulseDemand() { release(); }
  /// Whether this holds a demand (a default-constructed one does not).
  explicit operator bool() const { return bool(count_); }

 private:
  void release() {
    if (count_) --*count_, count_.reset();
  }
  std::shared_ptr<std::size_t> count_;
};

/// Orders pairs by (a, b): the deterministic order of every contact list.
constexpr bool pair_less(ObjectId a1, ObjectId b1, ObjectId a2, ObjectId b2) {
  return a1 < a2 || (a1 == a2 && b1 < b2);
}

}  // namespace alloy::rigid
