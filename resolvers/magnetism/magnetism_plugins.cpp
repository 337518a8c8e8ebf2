#include "resolvers/magnetism/magnetism_plugins.hpp"

#include <cmath>

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/electricity/electricity_from_magnetism.hpp"
#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/magnetism_from_electricity.hpp"
#include "resolvers/magnetism/magnetism_resolver.hpp"
#include "resolvers/rigid_body/rigid_body_from_magnetism.hpp"

namespace alloy::magnetism {

namespace {
// The electricity resolver's plugin name (resolvers/electricity/electricity.hpp;
// not included, so that magnetism builds without electricity).
constexpr const char* kElectricity = "electricity";

const std::vector<std::string> kShapeReads = {prop::kShape, prop::kSize, prop::kRadius,
                                              prop::kLength};

std::vector<std::string> with_shape(std::vector<std::string> names) {
  names.insert(names.end(), kShapeReads.begin(), kShapeReads.end());
  return names;
}
}  // namespace

void register_magnetism_resolver(PluginRegistry& registry) {
  ensure_geometry_properties(registry.properties());

  registry.add({
      .info = {.name = MagnetismResolver::kName,
               .kind = StageKind::Resolver,
               .reads = with_shape({prop::kMagnet, prop::kTurns, prop::kCoilFactor,
                                    prop::kCoilTimeConstant, prop::kPoleSeparation}),
               .writes = {prop::kPoleStrength, prop::kPoleStrengthRate},
               .needs = {prop::kMagnet},
               .doc = "magnets: electromagnets' pole strength follows their coil current"},
      .properties = magnetism_property_defs(),
      .create =
          [](PluginContext& ctx) {
            const PluginSettings& s = ctx.settings();
            s.check_known(MagnetismResolver::kName, {"rates"});
            return std::make_unique<MagnetismResolver>(s.boolean("rates", false));
          },
  });

  registry.add({
      .info = {.name = MagneticForces::kName,
               .kind = StageKind::Derived,
               .reads = with_shape({prop::kMagnet, prop::kPoleStrength, prop::kPoleSeparation,
                                    prop::kSusceptibility, prop::kSaturationPole,
                                    prop::kCoreDiameter, prop::kPosition, prop::kOrientation,
                                    prop::kPoleStrengthRate, prop::kCurrent, prop::kTurns,
                                    prop::kCoilFactor, prop::kCoilTimeConstant}),
               .needs = {prop::kMagnet},
               .resolvers = {MagnetismResolver::kName},
               .doc =
                   "poles of magnets, coils and induced soft iron; force and torque on each part"},
      .create =
          [](PluginContext& ctx) {
            const PluginSettings& s = ctx.settings();
            s.check_known(MagneticForces::kName,
                          {"softening", "method", "theta", "tolerance", "reuse_tree", "order",
                           "rates", "near_field", "coils_from_current"});
            const double eps = s.number("softening", MagneticForces::kDefaultSoftening);
            if (!(eps >= 0) || !std::isfinite(eps))
              throw InputError(s.where, "magnetic_forces: 'softening' must be a length >= 0 (m)");
            SummationOptions sum{.method = Summation::Auto};
            const std::string method = s.string("method", "auto");
            if (method == "direct")
              sum.method = Summation::Direct;
            else if (method == "tree")
              sum.method = Summation::Tree;
            else if (method == "fmm")
              sum.method = Summation::Fmm;
            else if (method != "auto")
              throw InputError(s.where,
                               "magnetic_forces: 'method' must be \"auto\", \"direct\", "
                               "\"tree\" or \"fmm\", not \"" +
                                   method + "\"");
            const double tolerance = s.number("tolerance", kDefaultTolerance);
            if (!(tolerance >= 1e-5 && tolerance <= 0.1))
              throw InputError(s.where,
                               "magnetic_forces: 'tolerance' must be a relative error in "
                               "[1e-5, 0.1]");
            // The FMM's theta is its own (no tolerance table: its error depends
            // too much on the configuration; docs/magnetism.md "Fast summation").
            sum.theta = s.number(
                "theta", sum.method == Summation::Fmm ? kFmmTheta : theta_for_tolerance(tolerance));
            const double order = s.number("order", kFmmOrder);
            if (!(order >= 1 && order <= multipole::kMaxFmmOrder && order == std::floor(order)))
              throw InputError(s.where, "magnetic_forces: 'order' must be a whole number in [1, " +
                                            std::to_string(multipole::kMaxFmmOrder) + "]");
            sum.fmm_order = int(order);
            if (!(sum.theta > 0 && sum.theta < 1))
              throw InputError(s.where, "magnetic_forces: 'theta' must be in (0, 1)");
            sum.reuse = s.boolean("reuse_tree", false);
            sum.tolerance = tolerance;
            return std::make_unique<MagneticForces>(eps, sum, s.boolean("rates", false),
                                                    s.boolean("near_field", true),
                                                    s.boolean("coils_from_current", true));
          },
  });

  registry.add({
      .info = {.name = MagnetismFromElectricity::kName,
               .kind = StageKind::Interaction,
               .reads = {prop::kMagnet, prop::kCurrent},
               .needs = {prop::kMagnet},
               // Active with electricity from the first step, so that a current
               // of step n magnetises at n+1 even for the very first current.
               .resolvers = {kElectricity},
               .target = MagnetismResolver::kName,
               .doc = "a coil's current makes it a magnet at the next step"},
      .create =
          [](PluginContext& ctx) {
            // Electricity's induction_order sets the current's lead (its own
            // resolver validates the value).
            int order = electricity::kDefaultInductionOrder;
            const auto& settings = ctx.world().def().settings;
            if (const auto it = settings.find("electricity"); it != settings.end())
              order = int(it->second.integer("induction_order", order));
            return std::make_unique<MagnetismFromElectricity>(ctx.target<MagnetismResolver>(),
                                                              order);
          },
  });
}

void register_magnetism_plugins(PluginRegistry& registry) {
  register_magnetism_resolver(registry);
  // The interactions that join magnetism to the physics registered before it;
  // they live in the folders of the resolvers they feed.
  register_rigid_body_from_magnetism(registry);
  register_electricity_from_magnetism(registry);
}

}  // namespace alloy::magnetism
