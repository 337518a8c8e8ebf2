// The `magnetic_forces` derived property set (paper 4.1.3.2): from the magnetic
// parts' properties, the poles of every part (permanent, electromagnet, and the
// poles the field induces in soft iron) and the force and torque on each part.
//
// Contract:
//   reads     magnet, pole_strength, pole_separation, susceptibility, core_diameter,
//             saturation_pole, position, orientation, shape, size, radius, length;
//             the magnetism resolver (whose electromagnets it sees through pole_strength);
//             current, turns, coil_factor, coil_time_constant (coils_from_current)
//   writes    only its own data below; recomputed only when an input changed
//   settings  softening (m, default 0.005): the Plummer length eps of the pole force law
//             method ("auto" | "direct" | "tree" | "fmm", default "auto"): how pole
//             pairs are summed; auto is direct below kFmmAutoPoles poles
//             (pole_model.hpp), from there the fast multipole method, its error
//             checked against the direct sum on 32 parts (kAutoCheckEvery) and the
//             update redone on the tree (direct below kTreeCrossoverPoles) where
//             it exceeds `tolerance`; fmm is the FMM alone: its error is not
//             bounded by `tolerance` (docs/magnetism.md "Fast summation")
//             tolerance (default 1e-3, in [1e-5, 0.1]): the RMS relative error of
//             the parts' forces the tree (and auto's FMM) may make; sets theta through
//             theta_for_tolerance (measured on the worst configuration we know,
//             a packed block of aligned bars)
//             theta (in (0, 1)): the tree's opening angle, set directly (overrides
//             tolerance); with fmm, its separation parameter (default kFmmTheta)
//             order (whole, 1 to 6, default 4): the fmm's expansion order
//             reuse_tree (default false): refit the last step's tree when the
//             parts moved little (multipole::TreeOptions::reuse); faster, but
//             the bits then depend on the tree's history, so a restored save
//             is no longer bit-identical to an uninterrupted run
//             rates (default false): also publish each part's force and torque
//             rates, d/dt along the parts' present motion (velocity,
//             angular_velocity), for a first-order hold over the rigid body's
//             substeps (docs/performance.md "Multi-rate coupling"); one more
//             evaluation of the pole model per update. With the magnetism
//             resolver's rates, the electromagnets' pole_strength_rate moves
//             their strengths on in the same evaluation, so the loads' rates
//             also carry a coil's rising or falling current
//             near_field (default true): an air-cored coil's near field as a
//             finite solenoid's for the permanent magnets near it (force and
//             flux: solenoid_field.hpp, docs/magnetism.md "A coil's near
//             field"); false makes every coil its pole pair (a magnet inside
//             a coil then links flux of the wrong sign)
//             coils_from_current (default true): a coil that a circuit drives (its
//             `current` published, no coil_time_constant) is coil_factor x turns x
//             current of this update, the current of the instant the rigid body
//             kicks with the force; off, and with rates, the magnetism resolver's
//             pole_strength, commanded a step before (the paper's path; it needs
//             the current predicted a step on: docs/magnetism.md "The coupling's
//             timing")
//   events    "magnetic_induction_unconverged" when the soft-iron solve falls back
//             to the uncoupled estimate (text says why; emitted once per episode)
//
// Readers (rigid_body_from_magnetism, the viewer, tests) get it from the world
// by name and read bodies() and poles(). Forces are in newtons, torques in
// newton metres about the part's position (its centre of mass), both in the
// world frame.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::magnetism {

/// The tree's opening angle for an RMS relative force error of at most
/// `tolerance` (clamped to [1e-5, 0.1]): the largest theta whose error on a
/// packed block of 10,000 aligned bars (bench/scaling.cpp --magnets, the worst
/// of the configurations measured: near forces cancel there) is within it;
/// random configurations are 10 to 50 times more accurate at the same theta.
double theta_for_tolerance(double tolerance);
inline constexpr double kDefaultTolerance = 1e-3;

/// Parts whose forces Auto's check sums directly (issue 16): 32 parts of
/// 10,000 cost 64 targets x 20,000 poles, 1.3e6 pairs, about 0.6 ms on the
/// SIMD kernel; fewer make the estimate too noisy to tell 3e-4 from 1e-3.
inline constexpr std::size_t kAutoCheckParts = 32;
/// When Auto's check runs (issue 16: it was 6 % of the stage at 10,000
/// magnets, run every update): at the first update on the FMM, and then
/// again when any of these holds since the last check: kAutoCheckEvery
/// updates have passed (pole_model.hpp; SummationOptions::check_every);
/// more than kAutoCheckMovedShare of the parts have a pole that moved farther
/// than kAutoCheckMove of its own pole separation (the configuration changed
/// much); the poles changed in number; or that check found more than
/// kAutoCheckMargin of the tolerance (or fell back). Between checks nearly
/// every part is within a quarter of a bar of a configuration whose error
/// was checked with room to spare. A restored save checks at its first
/// update, so its forces can differ from the uninterrupted run's only where a
/// check skipped there would have failed, which the margin and the motion
/// limit keep out of the runs we measured (docs/magnetism.md "Summation").
inline constexpr double kAutoCheckMove = 0.25;
inline constexpr double kAutoCheckMovedShare = 0.01;
inline constexpr double kAutoCheckMargin = 0.5;

struct MagneticBody;
/// Auto's check: the RMS relative error of the net pole force on
/// kAutoCheckParts of `bodies` (those with poles, evenly spaced in body order:
/// the same parts for the same poles, so the choice is a function of the
/// configuration alone and a restored save repeats it) between `approx` (per
/// pole, N) and the direct sum over every other part's poles.
double sampled_force_error(std::span<const Pole> poles, std::span<const MagneticBody> bodies,
                           std::span<const Vec3> approx, double softening);

/// The co-energy of a saturating induced moment over m . H at the same field,
/// given |m| / m_sat (the saturation curve m = m_sat tanh(u / m_sat) of
/// saturate_moment): 1/2 for linear iron (|m| << m_sat), rising to 1 as the
/// iron saturates (a saturated moment no longer grows with H, so all of
/// m . H is co-energy). Soft iron's store in the energy books is this times
/// the induced moment's interaction with the permanent magnets.
double iron_coenergy_ratio(double moment_over_saturation);

/// One magnetic part, as the derived set publishes it.
struct MagneticBody {
  ObjectId id;  ///< the object
  Vec3 force;   ///< total magnetic force on it, N (world)
  Vec3 torque;  ///< about its position (centre of mass), N*m (world)
  /// With `rates`: d force / dt and d torque / dt as every part moves on with
  /// its present velocity and angular velocity (pole strengths held), N/s and
  /// N*m/s; zero without.
  Vec3 force_rate, torque_rate;
  double pole_strength = 0;      ///< its present pole strength, A*m (induced for soft iron)
  std::uint32_t first_pole = 0;  ///< index of its north pole in poles(); south follows
  std::uint32_t pole_count = 0;  ///< 2, or 0 if its pole strength is zero
};

class MagneticForces : public DerivedSet {
 public:
  /// Plugin name.
  static constexpr const char* kName = "magnetic_forces";
  static constexpr double kDefaultSoftening = 0.005;

  /// `coils_from_current`: a coil that a circuit drives takes its pole
  /// strength from the circuit's `current` of this update, not from the
  /// magnetism resolver's `pole_strength` (commanded a step earlier; the
  /// setting of the same name, docs/magnetism.md "The coupling's timing").
  explicit MagneticForces(double softening = kDefaultSoftening,
                          SummationOptions summation = {.method = Summation::Auto},
                          bool rates = false, bool near_field = true,
                          bool coils_from_current = true)
      : softening_(softening),
        summation_(summation),
        rates_(rates),
        near_field_(near_field),
        coils_from_current_(coils_from_current) {}

  void update(const WorldView& world) override;
  /// Its forces matter only to the stages that read them (the rigid body's
  /// interaction): with the rigid body every n-th step, summed once in n.
  bool on_demand() const override { return true; }
  /// The work the forces between the permanent magnets and the moments
  /// they alone induce in the iron did on the parts since the last report:
  /// transfer "magnetism", given to the rigid body. The permanent magnets'
  /// pairs (at their strengths) are minus the change of their interaction
  /// energy (a store). The iron is solved again with every coil's current
  /// off; its pairs with the magnets and with one another, at the mean of
  /// the strengths of the two reports, draw on soft iron's store, their
  /// co-energy in the magnets' field (-1/2 m.B for linear iron); what the
  /// store does not explain (the model's own error) is a source
  /// (docs/energy.md "Session 21"). A coil's own share, and the iron's share
  /// from the coils' currents, are the EMF's (emf_iron_poles): electricity
  /// books them.
  void report_energy(const WorldView& view, EnergyReport& out) override;

  /// Every magnetic part with a position, in slot order.
  std::span<const MagneticBody> bodies() const { return bodies_; }
  /// Every non-zero pole; Pole::body indexes bodies(). North (> 0) red, south (< 0) green.
  std::span<const Pole> poles() const { return poles_; }
  /// The part `id`, or nullptr if it is not magnetic (or was not at the last update).
  const MagneticBody* find(ObjectId id) const;
  /// Magnetic flux density B at `point` from every pole, T (for field lines and compasses).
  Vec3 field(Vec3 point) const;

  double softening() const { return softening_; }

  /// A part's pose: its centre and its local x, y, z axes (unit) in the world.
  struct PartPose {
    Vec3 centre;
    Vec3 axes[3];
  };
  /// Each body's pose at the last update (index of bodies()).
  std::vector<PartPose> poses() const;
  /// Whether some part has soft iron (a free part or a coil's live core).
  bool has_iron() const { return !models_.empty(); }
  /// Per body (index of bodies()): the share of its pole strength the field
  /// induced, A*m (soft iron's whole strength, a cored coil's core beyond its
  /// own current's); 0 for the rest. The rest of a pole's strength is fixed.
  std::span<const double> induced_shares() const { return induced_share_; }
  /// The induced poles whose flux a coil's EMF integrates, with every part at
  /// `poses` (one per body, as poses()): the iron solved there with the fixed
  /// strengths of the last update (the coils' currents of now) and solved
  /// again with the coils' currents off, each pair at half its strength, so
  /// that the flux through coil j is the mean of the two (exact for linear
  /// iron: the integral over s in [0, 1] of the flux at the currents s I,
  /// whose change at fixed currents is d/dx of the co-energy the currents add
  /// to the iron's). With no coil carrying a current, the one solve at full
  /// strength. Body indices as bodies(); empty without iron. A coil's own core
  /// is in its own body, so coil_flux skips it (its response to the coil's
  /// current is in coil_factor). docs/magnetism.md "Induction through soft
  /// iron".
  void emf_iron_poles(std::span<const PartPose> poses, std::vector<Pole>& out) const;
  /// Per body (index of bodies()): 1 where a coil's near field acts on its
  /// poles as a finite solenoid's (permanent magnets), else 0 (the pole pair's
  /// field only: coils, soft iron). solenoid_field.hpp.
  std::span<const std::uint8_t> sheet_bodies() const { return sheet_body_; }
  const SummationOptions& summation() const { return summation_; }
  void set_summation(const SummationOptions& s) { summation_ = s; }
  /// Whether the last update summed the forces with the tree (or the FMM).
  bool used_tree() const { return used_tree_; }
  /// How the last update summed the forces: Direct, Tree or Fmm (never Auto).
  Summation used_method() const { return used_method_; }
  /// Auto with the FMM: the error its last check measured (RMS relative,
  /// over a sample of parts; kAutoCheckEvery says when it runs); NaN when the
  /// last update was not on the FMM.
  double last_check_error() const { return last_check_error_; }
  /// Whether the last update ran Auto's check, and how many updates did.
  bool checked() const { return checked_; }
  std::uint64_t checks() const { return checks_; }
  /// Newton iterations of the last soft-iron solve, and whether it converged.
  int induction_iterations() const { return induction_iterations_; }
  bool induction_converged() const { return induction_converged_; }
  /// Whether force_rate and torque_rate are computed (setting `rates`).
  bool rates() const { return rates_; }
  /// Times update() ran (the harness skips it when the inputs did not change).
  std::uint64_t updates() const { return updates_; }

 private:
  /// A body's frame at an update: its pose and the separation of its fixed poles.
  struct Frame {
    Vec3 centre;
    Vec3 axes[3];       // the part's local x, y, z in the world
    double separation;  // of its fixed poles (along x)
  };
  /// A body's one pole pair (its fixed share and its core's, or free iron's).
  struct PolePair {
    Vec3 axis;
    double separation = 0, strength = 0;
  };
  /// The induction solve's view of the iron at the frames `at`.
  std::vector<InducedPart> induced_parts(const std::vector<Frame>& at) const;
  /// The fixed poles (strength q[b] along each body's x axis) at `at`.
  std::vector<Pole> fixed_poles(const std::vector<Frame>& at, const std::vector<double>& q) const;
  /// Every body's pole pair at `at`: fixed strengths q, induced moments `moment`.
  std::vector<PolePair> pole_pairs(const std::vector<Frame>& at, const std::vector<double>& q,
                                   const std::vector<Vec3>& moment) const;
  /// The fixed strengths `q` with every coil's set to 0 (the magnets' alone).
  std::vector<double> magnets_only(const std::vector<double>& q) const;
  /// Appends the induced pole pairs of `moment` at `at`, times `scale`.
  void append_induced_poles(const std::vector<Frame>& at, const std::vector<Vec3>& moment,
                            double scale, std::vector<Pole>& out) const;
  /// Whether Auto's check is due at this update (kAutoCheckEvery).
  bool due_check() const;
  double softening_;
  SummationOptions summation_;
  bool rates_ = false;
  bool near_field_ = true;          // the near_field setting (solenoid_field.hpp)
  bool coils_from_current_ = true;  // the coils_from_current setting (constructor)
  multipole::Tree tree_;            // its memory, kept between updates
  bool used_tree_ = false;
  Summation used_method_ = Summation::Direct;
  double last_check_error_ = 0;
  // Auto's check schedule: whether the last update ran it, the updates on the
  // FMM since it ran, and the poles' places then (empty: check next time).
  bool checked_ = false;
  std::uint64_t checks_ = 0;
  std::uint32_t since_check_ = 0;
  std::vector<Vec3> checked_at_;
  std::vector<MagneticBody> bodies_;
  std::vector<Pole> poles_;
  std::vector<std::uint32_t> body_of_slot_;  // slot -> index in bodies_, or kNoBody
  std::vector<std::uint8_t> sheet_body_;     // per body: sheet_bodies()
  // The last update's parts: frames, fixed strengths, iron models (iron_of_:
  // per body, the index in models_ or -1), whether each is a permanent
  // magnet, and the induced moments solved.
  std::vector<Frame> frames_;
  std::vector<double> fixed_strength_;
  std::vector<std::int32_t> iron_of_;
  std::vector<SoftIronModel> models_;
  std::vector<std::uint8_t> permanent_;
  std::vector<Vec3> induced_moment_;
  // Per body: the share of its pole strength the field induced (soft iron's
  // whole strength, a cored coil's core beyond its own current's share), A*m.
  std::vector<double> induced_share_;
  double reported_iron_store_ = 0;
  int induction_iterations_ = 0;
  bool induction_converged_ = true;
  std::uint64_t updates_ = 0;
  // The poles at the last report_energy, their parts, and whether each part
  // is a permanent magnet (1), soft iron (2) or a coil (0).
  /// A pole's strength in its fixed share (a permanent magnet's or a coil's
  /// own) and its induced share, for the energy books.
  struct Share {
    double fixed = 0, induced = 0;
    bool permanent = false;  ///< the fixed share is a permanent magnet's
  };
  std::vector<Pole> reported_poles_;
  std::vector<Share> reported_shares_;
  std::vector<ObjectId> reported_bodies_;
  std::vector<std::uint32_t> reported_first_pole_;  // per body of the last report
  /// The permanent magnets' pairs' work since the last report when the
  /// poles changed (a coil switched, a part came or went): their poles
  /// matched by part (`kinds`: this report's, per body; 1 = permanent).
  /// `poles`: this report's booked poles, `first`: each body's first in them.
  double permanent_work_across_a_change(std::span<const Pole> poles,
                                        std::span<const std::uint32_t> first,
                                        std::span<const std::uint8_t> kinds) const;
  std::vector<std::uint8_t> reported_kinds_;
  bool reported_ = false;
  std::optional<MagnetColumns::Ids> ids_;  // resolved at the first update
  PropertyRef pole_strength_rate_{prop::kPoleStrengthRate};
};

}  // namespace alloy::magnetism
