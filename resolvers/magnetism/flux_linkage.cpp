#include "resolvers/magnetism/flux_linkage.hpp"

#include <cmath>
#include <numbers>

#include "resolvers/magnetism/solenoid_field.hpp"

namespace alloy::magnetism {

double pole_potential(std::span<const Pole> poles, double softening, Vec3 x,
                      std::uint32_t exclude_body) {
  double sum = 0;
  for (const Pole& p : poles) {
    if (p.body == exclude_body || p.strength == 0) continue;
    const Vec3 r = x - p.position;
    const double s2 = dot(r, r) + softening * softening;
    if (s2 <= 0) continue;  // coincident with no softening: no finite potential
    sum += p.strength / std::sqrt(s2);
  }
  return kMu0Over4Pi * sum;
}

FluxLinkage coil_flux(std::span<const Pole> poles, std::span<const Vec3> pole_velocity,
                      double softening, const CoilGeometry& coil) {
  FluxLinkage out;
  if (coil.linkage == 0) return out;
  const BarPoles ends = bar_poles(coil.centre, coil.axis, coil.separation);
  // The coil's own poles move with its body.
  const Vec3 u_north = coil.velocity + cross(coil.angular_velocity, ends.north - coil.centre);
  const Vec3 u_south = coil.velocity + cross(coil.angular_velocity, ends.south - coil.centre);
  double flux = 0, rate = 0;
  for (std::size_t i = 0; i < poles.size(); ++i) {
    const Pole& p = poles[i];
    if (p.body == coil.body || p.strength == 0) continue;
    const Vec3 up = i < pole_velocity.size() ? pole_velocity[i] : Vec3{};
    // d/dt (1 / s(x - p)) = -K(x - p) . (u_x - u_p), K the force kernel.
    const Vec3 rs = ends.south - p.position, rn = ends.north - p.position;
    const double ss = std::sqrt(dot(rs, rs) + softening * softening);
    const double sn = std::sqrt(dot(rn, rn) + softening * softening);
    if (!(ss > 0) || !(sn > 0)) continue;
    flux += p.strength * (1.0 / ss - 1.0 / sn);
    rate += p.strength * (-dot(softened_kernel(rs, softening), u_south - up) +
                          dot(softened_kernel(rn, softening), u_north - up));
  }
  out.flux = coil.linkage * kMu0Over4Pi * flux;
  out.rate = coil.linkage * kMu0Over4Pi * rate;
  if (!(coil.radius > 0) || coil.sheet_bodies.empty()) return out;
  // The near field as a finite solenoid, per ampere: turns per metre
  // N / d = k N / (pi a^2). Each point moves relative to the coil's frame.
  const Solenoid sheet{coil.centre, coil.axis, coil.separation, coil.radius,
                       coil.linkage / (std::numbers::pi * coil.radius * coil.radius)};
  auto frame_velocity = [&](Vec3 x) {
    return coil.velocity + cross(coil.angular_velocity, x - coil.centre);
  };
  auto applies = [&](std::size_t i) {
    const std::uint32_t b = poles[i].body;
    return b != coil.body && b < coil.sheet_bodies.size() && coil.sheet_bodies[b] != 0 &&
           poles[i].strength != 0;
  };
  auto velocity = [&](std::size_t i) {
    return (i < pole_velocity.size() ? pole_velocity[i] : Vec3{}) -
           frame_velocity(poles[i].position);
  };
  double near_flux = 0, near_rate = 0;
  for (std::size_t i = 0; i < poles.size(); ++i) {
    if (!applies(i)) continue;
    const Pole& p = poles[i];
    const PoleLinkage g = near_correction(sheet, softening, p.position);
    near_flux += p.strength * g.flux;
    near_rate += p.strength * dot(g.gradient, velocity(i));
    if (i + 1 < poles.size() && poles[i + 1].body == p.body && p.strength > 0 &&
        poles[i + 1].strength == -p.strength) {
      const StringLinkage st = string_linkage(sheet, poles[i + 1].position, p.position);
      if (st.overlap == 0) continue;
      near_flux += p.strength * st.flux;
      near_rate +=
          p.strength * (dot(st.grad_north, velocity(i)) + dot(st.grad_south, velocity(i + 1)));
    }
  }
  if (near_flux == 0 && near_rate == 0) return out;  // nothing near: the pair's bits, -0 kept
  out.flux += near_flux;
  out.rate += near_rate;
  return out;
}

double mutual_inductance(const CoilGeometry& a, const CoilGeometry& b, double softening) {
  const BarPoles ends = bar_poles(b.centre, b.axis, b.separation);
  // Any body other than a's: b's poles are never skipped as a's own.
  const std::uint32_t body = a.body == kNoBody - 1 ? kNoBody - 2 : kNoBody - 1;
  const Pole unit[2] = {{ends.north, b.linkage, body}, {ends.south, -b.linkage, body}};
  CoilGeometry still = a;  // the flux, not its rate
  still.velocity = {}, still.angular_velocity = {};
  return coil_flux(unit, {}, softening, still).flux;
}

}  // namespace alloy::magnetism
