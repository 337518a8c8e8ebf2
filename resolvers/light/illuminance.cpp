#include "resolvers/light/illuminance.hpp"

#include <algorithm>
#include <cmath>

namespace alloy::light {

double point_illuminance(double flux, Vec3 source, Vec3 receiver, Vec3 normal) {
  const Vec3 d = source - receiver;
  const double r = length(d);
  if (!(flux > 0) || !std::isfinite(r)) return 0.0;
  // A lamp at the receiver's own place lights it head on (no direction to
  // take a cosine of); closer than a bulb's size, it is a bulb's size away.
  const double cos_theta = r > 0 ? dot(normal, d) / r : 1.0;
  if (!(cos_theta > 0)) return 0.0;  // the lamp is behind the face, or beside it
  const double rr = std::max(r, kMinDistance);
  return flux * cos_theta / (4 * kPi * rr * rr);
}

void IlluminanceSet::update(const WorldView& world) {
  receivers_.clear();
  shares_.clear();
  const PropertyStore& store = world.store();
  const auto position = position_.column<Vec3>(world);
  const auto orientation = orientation_.column<Quat>(world);
  const auto flux = flux_.column<double>(world);
  const auto receiver = receiver_.column<std::uint8_t>(world);
  for (std::uint32_t r : receiver.members()) {
    if (!receiver[r]) continue;
    Receiver out{store.id_at(r), ambient_};
    if (position.has(r)) {
      const Vec3 at = position[r];
      // The face looks along the part's +y axis (the kit lays parts along x).
      Vec3 normal = rotate(orientation.value_or(r, Quat{}), {0, 1, 0});
      const double n = length(normal);
      if (n > 0) normal = normal / n;
      for (std::uint32_t l : flux.members()) {
        if (l == r || !position.has(l)) continue;
        const double e = point_illuminance(flux[l], position[l], at, normal);
        if (e > 0 && std::isfinite(e)) {
          shares_.push_back({out.id, store.id_at(l), e});
          out.illuminance += e;
        }
      }
    }
    receivers_.push_back(out);
  }
}

double IlluminanceSet::illuminance(ObjectId id) const {
  for (const Receiver& r : receivers_)
    if (r.id == id) return r.illuminance;
  return 0.0;
}

double IlluminanceSet::share(ObjectId receiver, ObjectId lamp) const {
  for (const Share& s : shares_)
    if (s.receiver == receiver && s.lamp == lamp) return s.illuminance;
  return 0.0;
}

}  // namespace alloy::light
