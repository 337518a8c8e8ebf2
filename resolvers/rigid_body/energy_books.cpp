#include "resolvers/rigid_body/energy_books.hpp"

#include <string_view>

namespace alloy::rigid {

std::uint32_t EnergyBooks::account(const std::string& stage) {
  std::string name = stage.substr(0, stage.find('@'));
  static constexpr std::string_view prefix = "rigid_body_from_";
  if (name.starts_with(prefix)) name.erase(0, prefix.size());
  if (name.empty()) name = "loads from outside the stages";
  for (std::size_t i = 0; i < work.size(); ++i)
    if (work[i].first == name) return std::uint32_t(i);
  // The coils' loads are paid by the circuits' EMF over a trapezoidal step
  // with its mean current, I-bar dPhi; the kick of semi-implicit Euler at
  // t_n, with the current of that instant, gives the kinetic energy
  // h F.(v + v')/2: summed over the steps, the kicks' work along the mean
  // velocity is the circuits' work but for the first and the last half
  // step (docs/energy.md "Magnetism"), where along the displacement it
  // differs by half the sum of dI dPhi, first order in the step.
  along_mean.push_back(name == "magnetism");
  work.emplace_back(name, 0.0);
  return std::uint32_t(work.size() - 1);
}

double EnergyBooks::book_load(const Applied& a, double along_step, double h, Vec3 v1, Vec3 w1) {
  const Vec3 torque = a.torque + cross(a.arm, a.force);
  const double mean = 0.5 * h * (dot(a.force, v0[a.body] + v1) + dot(torque, w0[a.body] + w1));
  if (along_mean[a.source]) {
    work[a.source].second += mean;
  } else {
    work[a.source].second += along_step;
    integration += along_step - mean;
  }
  return mean;
}

void EnergyBooks::report(double kinetic, EnergyReport& out) {
  out.store("kinetic energy", kinetic);
  out.sink("viscous drag (linear_damping, angular_damping)", std::exchange(drag, 0.0));
  out.sink("restitution (collision impulses)", std::exchange(restitution, 0.0));
  out.sink("integration and position corrections", std::exchange(integration, 0.0));
  out.sink("contacts and joints (residue of the kinetic energy)", std::exchange(contacts, 0.0));
  for (auto& [name, joules] : work) out.transfer(name, std::exchange(joules, 0.0));
}

}  // namespace alloy::rigid
