// ODE set-up and conversions shared by the rigid body resolver and the
// collisions set (private to resolvers/rigid_body/).
#pragma once

#include <ode/ode.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "runtime/math.hpp"

namespace alloy::rigid {

/// dInitODE2 once per process, and ODE's per-thread data for the calling
/// thread (a world may be stepped on another thread than the one that made it).
/// The first call also routes ODE's errors and failed assertions to OdeError
/// and its messages to ode_messages().
void ensure_ode();

/// An error or a failed assertion inside ODE (dError, dDebug: its dIASSERT and
/// dUASSERT, which the Debian build keeps). ODE's own handlers print and abort
/// the process; ours throw this instead, through ODE's frames (libode is C++
/// built with exceptions: it has unwind tables and except tables). What ODE
/// was doing is left half done, so whoever catches it throws the ODE object
/// away (the rigid body rebuilds its world from properties).
class OdeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// ODE's messages (dMessage: warnings such as "LCP internal error") since the
/// process started, and the last one. Counted, not printed: a mod must not be
/// able to flood the output through ODE.
std::uint64_t ode_message_count();
std::string last_ode_message();

inline Vec3 to_vec3(const dReal* v) { return {v[0], v[1], v[2]}; }
inline Quat to_quat(const dReal* q) { return {q[0], q[1], q[2], q[3]}; }
inline void to_ode(Quat q, dQuaternion out) {
  out[0] = q.w, out[1] = q.x, out[2] = q.y, out[3] = q.z;
}

inline Quat conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }
/// The unit quaternion of q, or the identity for a zero or non-finite q.
/// A q whose squared norm overflows or underflows (components of 1e300 or
/// 1e-300) is scaled by its largest component first, so that any finite q
/// normalises (a zero result would make ODE's dNormalize4 assert); any other
/// q is divided by its norm as it is, so that a rebuild from properties
/// keeps every bit.
inline Quat normalized(Quat q) {
  double n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!(n2 >= 1e-300 && n2 <= 1e300)) {
    const double s = std::max({std::abs(q.w), std::abs(q.x), std::abs(q.y), std::abs(q.z)});
    if (!(s > 0) || !std::isfinite(s)) return {};
    q = {q.w / s, q.x / s, q.y / s, q.z / s};
    n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  }
  const double n = std::sqrt(n2);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
/// The unit vector along v, or the zero vector for a zero or non-finite v
/// (scaled first when its squared length is out of range, as normalized()).
inline Vec3 unit(Vec3 v) {
  double n2 = v.x * v.x + v.y * v.y + v.z * v.z;
  if (!(n2 >= 1e-300 && n2 <= 1e300)) {
    const double s = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (!(s > 0) || !std::isfinite(s)) return {};
    v = v / s;
    n2 = v.x * v.x + v.y * v.y + v.z * v.z;
  }
  return v / std::sqrt(n2);
}

/// Rotation of a capsule's ODE axis (local z) onto the part's x axis, so that a
/// capsule bar lies in the play area: +90 degrees about y.
inline Quat capsule_axis_rotation() { return Quat::from_axis_angle({0, 1, 0}, 1.5707963267948966); }

}  // namespace alloy::rigid
