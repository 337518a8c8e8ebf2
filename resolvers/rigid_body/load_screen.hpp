// The screen of queued loads, shared by every engine that provides
// `rigid_body` (ODE's RigidBodyResolver, Box2D's Box2DEngine): before a
// window's step, the loads queued on each body must not change its velocity
// by more than limits::speed nor its angular velocity by more than
// limits::angular_speed (properties.hpp). A body whose loads would is
// refused (frozen, an "out_of_bounds" event naming the stage, and through
// it the mod, that queued the load doing the most), so that a mod's 1e9 N
// push is caught before the engine integrates it, on either engine, with
// the same words (docs/security.md).
//
// Magnitudes are summed, not vectors, so that neither the order of the sum
// nor +-huge loads that cancel can overflow an engine's accumulators. The
// engine measures each load's share (it knows its bodies' masses, inertias
// and, for a planar engine, which components it applies); the screen sums,
// blames and words the refusal.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "resolvers/rigid_body/engine.hpp"
#include "runtime/math.hpp"

namespace alloy::rigid {

/// A number in a refusal's text, as printf's %g writes it.
std::string number(double v);
/// A vector in a refusal's text: "{x, y, z}".
std::string vector_text(Vec3 v);

/// Which stage queued which loads: marks where the stage running at queue
/// time (World::running_stage) changed, so that a refused load names the
/// stage (and through it the mod) that gave it. One pointer compare a load.
class SourceMarks {
 public:
  void note(std::size_t at, const std::string* stage) {
    if (marks_.empty() || marks_.back().stage != stage) mark(at, stage);
  }
  /// The name of the stage that queued load `i`, or "" (outside any stage).
  const std::string& name_of(std::size_t i) const;
  void clear() { marks_.clear(); }

 private:
  struct Mark {
    std::size_t from;
    const std::string* stage;  // compared, never read: `name` keeps the name
    std::string name;
  };
  void mark(std::size_t at, const std::string* stage);
  std::vector<Mark> marks_;
};

/// One window's sums per body (see the header comment).
class LoadScreen {
 public:
  static constexpr std::size_t npos = ~std::size_t(0);

  /// Starts a window over `bodies` bodies, with no load.
  void begin(std::size_t bodies);
  /// Load `index` (the engine's numbering, used only to name the culprit)
  /// changes body `body`'s speed by at most `dv` m/s and its angular speed
  /// by at most `dw` rad/s in the window (|F| dt / m, |torque| dt / I_min).
  /// NaN counts as the largest change.
  void add(std::uint32_t body, double dv, double dw, std::size_t index);
  /// Whether the body's loads break the limits (true for NaN).
  bool breaks(std::uint32_t body) const;
  /// The load that does the most to the body, or npos if it has none.
  std::size_t culprit(std::uint32_t body) const;
  /// The culprit if it alone changes the speed by 1 % of the limit in a step
  /// (1 km/s: gravity's 0.04 m/s does not), else npos: the stage named when a
  /// run of loads within the bounds pushes a body past them.
  std::size_t pusher(std::uint32_t body) const;
  /// The refusal's text: "queued <what> on it: its loads would change its
  /// speed by ... in one step of <dt> s; they were refused".
  std::string refusal(std::uint32_t body, const std::string& what, double dt) const;

  /// How a queued load is named in a refusal ("add_force {1e+09, 0, 0} N").
  static std::string describe(const RigidBodyEngine::LoadCommand& c);
  /// How add_load's load is named ("add_load {..} N, {..} N m").
  static std::string describe_rated(Vec3 force, Vec3 torque);
  /// A load's numbers for the event (x, y, z).
  static std::vector<std::pair<std::string, double>> components(Vec3 v);
  /// Whether a force's point of application lies within the world's extent
  /// (limits::extent; false if not finite). A load at a point beyond it is
  /// refused whatever the force: an engine in single precision makes inf of
  /// the point, and NaN of a zero force's torque about it.
  static bool point_within_extent(Vec3 point);

 private:
  std::vector<double> dv_, dw_, worst_;
  std::vector<std::size_t> culprit_;
};

}  // namespace alloy::rigid
