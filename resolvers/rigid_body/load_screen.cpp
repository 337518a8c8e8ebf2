#include "resolvers/rigid_body/load_screen.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "resolvers/rigid_body/properties.hpp"

namespace alloy::rigid {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
std::string vector_text(Vec3 v) {
  return "{" + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + "}";
}

void SourceMarks::mark(std::size_t at, const std::string* stage) {
  marks_.push_back({at, stage, stage ? *stage : std::string()});
}

const std::string& SourceMarks::name_of(std::size_t i) const {
  static const std::string none;
  auto it = std::upper_bound(marks_.begin(), marks_.end(), i,
                             [](std::size_t x, const Mark& m) { return x < m.from; });
  return it == marks_.begin() ? none : std::prev(it)->name;
}

void LoadScreen::begin(std::size_t bodies) {
  dv_.assign(bodies, 0.0);
  dw_.assign(bodies, 0.0);
  worst_.assign(bodies, -1.0);
  culprit_.assign(bodies, npos);
}

void LoadScreen::add(std::uint32_t b, double dv, double dw, std::size_t index) {
  dv_[b] += dv, dw_[b] += dw;
  const double score = std::max(dv / limits::speed, dw / limits::angular_speed);
  if (!(score <= worst_[b])) worst_[b] = score, culprit_[b] = index;  // NaN counts as the worst
}

bool LoadScreen::breaks(std::uint32_t b) const {
  return !(dv_[b] <= limits::speed && dw_[b] <= limits::angular_speed);
}

std::size_t LoadScreen::culprit(std::uint32_t b) const {
  return culprit_[b];
}

std::size_t LoadScreen::pusher(std::uint32_t b) const {
  return worst_[b] < 0.01 ? npos : culprit_[b];
}

std::string LoadScreen::refusal(std::uint32_t b, const std::string& what, double dt) const {
  const bool linear = !(dv_[b] <= limits::speed);
  const std::string change = linear ? "its speed by " + number(dv_[b]) + " m/s (the limit is " +
                                          number(limits::speed) + " m/s)"
                                    : "its angular speed by " + number(dw_[b]) +
                                          " rad/s (the limit is " + number(limits::angular_speed) +
                                          " rad/s)";
  return "queued " + what + " on it: its loads would change " + change + " in one step of " +
         number(dt) + " s; they were refused";
}

std::string LoadScreen::describe(const RigidBodyEngine::LoadCommand& c) {
  using Load = RigidBodyEngine::Load;
  static constexpr const char* kName[] = {"add_force", "add_force_at", "add_torque"};
  std::string what = std::string(kName[int(c.kind)]) + " " + vector_text(c.value) +
                     (c.kind == Load::Torque ? " N m" : " N");
  if (c.kind == Load::ForceAtPoint) what += " at " + vector_text(c.point) + " m";
  return what;
}

std::string LoadScreen::describe_rated(Vec3 force, Vec3 torque) {
  return "add_load " + vector_text(force) + " N, " + vector_text(torque) + " N m";
}

std::vector<std::pair<std::string, double>> LoadScreen::components(Vec3 v) {
  return {{"x", v.x}, {"y", v.y}, {"z", v.z}};
}

bool LoadScreen::point_within_extent(Vec3 p) {
  return std::abs(p.x) <= limits::extent && std::abs(p.y) <= limits::extent &&
         std::abs(p.z) <= limits::extent;
}

}  // namespace alloy::rigid
