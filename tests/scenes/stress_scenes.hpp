// Stress scenes for numerical stability (issue 6, item 3), built through the
// world's editing API like rigid_scenes.hpp, and the checks run on them: a scan
// of every numeric property for NaN / Inf, and the mechanical energy of the
// rigid bodies. tests/stress runs them shortened, bench/stress.cpp in full.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/world.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes::stress {

// --- checks ------------------------------------------------------------------------------

/// Non-finite values in every number, vec3 and quat column of the store (only
/// values an object carries). `first`, if given, gets "object.property" of the
/// first one found.
std::size_t count_non_finite(const World& w, std::string* first = nullptr);

/// Mechanical energy of the movable rigid bodies (mass, not static): kinetic,
/// translational and rotational (boxes and spheres; other shapes translational
/// only), and potential in each body's own `gravity` (J).
struct Energy {
  double kinetic = 0, potential = 0;
  double total() const { return kinetic + potential; }
};
Energy mechanical_energy(const World& w);

/// Largest speed of any movable body (m/s): a bounded-energy check where no
/// potential is known (magnets).
double max_speed(const World& w);

/// What a run found: call observe() after every step.
struct Monitor {
  /// Starts the world (so that every resolver has written its outputs, such
  /// as each body's `gravity`) and takes the starting energy.
  explicit Monitor(World& w);
  void observe(const World& w);
  std::uint64_t steps = 0;
  std::uint64_t non_finite = 0;                     ///< values found, summed over steps
  std::string first_non_finite;                     ///< "object.property at step n"
  double e0 = 0, e_max = 0, e_min = 0, e_last = 0;  ///< total mechanical energy, J
  double ke_max = 0;                                ///< kinetic energy, J
  double speed_max = 0;                             ///< m/s
  /// Energy gained above the start (J, >= 0 when it never rose).
  double gain() const { return e_max - e0; }
  double drift() const { return e_last - e0; }
};

/// True if rigid_body accepts the setting `key` (substeps, auto_disable are
/// being added while this is written: use them where they exist).
bool rigid_body_has_setting(const std::string& key);

// --- scenes --------------------------------------------------------------------------------

/// Largest distance any of `ids` moved from `start` (m).
double max_displacement(const World& w, const std::vector<ObjectId>& ids,
                        const std::vector<Vec3>& start);
std::vector<Vec3> positions(const World& w, const std::vector<ObjectId>& ids);

/// A 2D pyramid of cubes in the x-y plane on a floor: `base` in the bottom row,
/// one fewer in each row above (base = 20: 210 boxes).
struct Pyramid {
  std::vector<ObjectId> boxes;
};
Pyramid build_pyramid(World& w, int base = 20, double edge = 0.2);

/// A column of `light` cubes of 1 kg with one cube of `ratio` kg on top.
struct HeavyOnLight {
  std::vector<ObjectId> light;
  ObjectId heavy;
};
HeavyOnLight build_heavy_on_light(World& w, int light = 4, double ratio = 100, double edge = 0.2);

/// A chain of `links` bars (local y along the chain, `pitch` apart, each a
/// little shorter so that neighbours do not touch) hinged about z to each
/// other and the first to the play area at the origin, straight, at `angle`
/// from hanging down (pi/2: horizontal). If weight_ratio > 0, a cube of
/// weight_ratio x a link's mass hangs on a last hinge at the end.
struct Chain {
  std::vector<ObjectId> links;  ///< the weight, if any, is the last
  std::vector<ObjectId> hinges;
  double pitch = 0.1, link_mass = 0.1, weight_size = 0.1;
  bool weighted = false;
  /// Largest distance between the two ends that a hinge joins (m): how far the
  /// chain has come apart.
  double joint_gap(const World& w) const;
};
Chain build_chain(World& w, int links, double angle, double weight_ratio = 0, double pitch = 0.1,
                  double link_mass = 0.1);

/// A projectile sphere fired at a static wall 0.1 m thick whose near face is
/// the plane x = 0 (4 m x 4 m): shot `k` of `shots` varies the angle from the
/// normal (0 to 60 degrees), the point of aim and the starting phase (how far
/// from the wall the projectile starts, as a fraction of one step's travel).
struct Shot {
  ObjectId projectile, wall;
  double speed = 500, radius = 0.02, thickness = 0.1;
  Vec3 start, velocity;
  /// Where the projectile is now: 1 beyond the wall, -1 in front, 0 inside.
  int side(const World& w) const;
};
Shot build_shot(World& w, int k, int shots, double dt, double speed = 500);

/// `n` cube magnets of `edge` m (permanent, neodymium: Br 1.2 T, 7500 kg/m^3)
/// packed in a cube lattice with 1 mm gaps on a floor, magnetised along x; each
/// x-row's sign alternates with its neighbours', so rows attract end to end and
/// side by side (the lowest-energy packing).
struct MagnetPack {
  std::vector<ObjectId> magnets;
  double pole_strength = 0;  ///< A*m
};
/// `gap`: between neighbours, m; negative: they start pressed together by
/// that much (within the rigid body's surface layer, so at rest).
MagnetPack build_magnet_pack(World& w, int n = 1000, double edge = 0.01, double gap = 0.001);

/// A battery (emf `e`, 0.1 ohm) on a coil whose L / R is `tau` (s), wired with
/// 0.01 ohm wires: a loop far stiffer than the step when tau << dt.
struct StiffCircuit {
  ObjectId battery, coil;
  double e = 6, r_total = 6, l = 6e-6;
  double steady() const { return e / r_total; }
};
StiffCircuit build_stiff_circuit(World& w, double tau = 1e-6, double e = 6);

}  // namespace alloy::scenes::stress
