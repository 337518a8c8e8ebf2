// ODE set-up and conversions shared by the rigid body resolver and the
// collisions set (private to resolvers/rigid_body/).
#pragma once

#include <ode/ode.h>

#include "runtime/math.hpp"

namespace alloy::rigid {

/// dInitODE2 once per process, and ODE's per-thread data for the calling
/// thread (a world may be stepped on another thread than the one that made it).
void ensure_ode();

inline Vec3 to_vec3(const dReal* v) { return {v[0], v[1], v[2]}; }
inline Quat to_quat(const dReal* q) { return {q[0], q[1], q[2], q[3]}; }
inline void to_ode(Quat q, dQuaternion out) {
  out[0] = q.w, out[1] = q.x, out[2] = q.y, out[3] = q.z;
}

inline Quat conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }
inline Quat normalized(Quat q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 0)) return {};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

/// Rotation of a capsule's ODE axis (local z) onto the part's x axis, so that a
/// capsule bar lies in the play area: +90 degrees about y.
inline Quat capsule_axis_rotation() { return Quat::from_axis_angle({0, 1, 0}, 1.5707963267948966); }

}  // namespace alloy::rigid
