#include "resolvers/rigid_body/rigid_body_impl.hpp"

namespace alloy::rigid {

// --- settings -------------------------------------------------------------------------

const std::vector<std::string>& RigidBodyConfig::keys() {
  static const std::vector<std::string> k = {"solver",
                                             "iterations",
                                             "sor",
                                             "erp",
                                             "cfm",
                                             "max_contacts",
                                             "surface_layer",
                                             "max_correcting_velocity",
                                             "substeps",
                                             "substep_contacts",
                                             "auto_disable",
                                             "auto_disable_linear",
                                             "auto_disable_angular",
                                             "auto_disable_steps",
                                             "ccd",
                                             "contact_stiffness",
                                             "contact_damping",
                                             "max_collision_impulses",
                                             "joint_projection"};
  return k;
}

RigidBodyConfig RigidBodyConfig::from(const PluginSettings& s) {
  s.check_known("rigid_body", keys());
  RigidBodyConfig c;
  const std::string solver = s.string("solver", "quick");
  if (solver == "quick")
    c.solver = Solver::Quick;
  else if (solver == "step")
    c.solver = Solver::Step;
  else
    throw InputError(s.where,
                     "rigid_body: solver must be \"quick\" or \"step\", got \"" + solver + "\"");
  auto bad = [&](const char* what) {
    throw InputError(s.where, std::string("rigid_body: ") + what);
  };
  c.iterations = int(s.integer("iterations", c.iterations));
  if (c.iterations < 1 || c.iterations > 10000) bad("iterations must be between 1 and 10000");
  c.sor = s.number("sor", c.sor);
  if (!(c.sor > 0 && c.sor < 2)) bad("sor must be in (0, 2)");
  c.erp = s.number("erp", c.erp);
  if (!(c.erp >= 0 && c.erp <= 1)) bad("erp must be in [0, 1]");
  c.cfm = s.number("cfm", c.cfm);
  if (!(c.cfm >= 0 && c.cfm < 1)) bad("cfm must be in [0, 1)");
  c.contact_stiffness = s.number("contact_stiffness", c.contact_stiffness);
  if (!(c.contact_stiffness >= 0 && c.contact_stiffness < 1e300))
    bad("contact_stiffness must be >= 0 N/m (0: rigid)");
  c.contact_damping = s.number("contact_damping", c.contact_damping);
  if (!(c.contact_damping >= 0 && c.contact_damping < 1e300))
    bad("contact_damping must be >= 0 N*s/m");
  c.max_collision_impulses = int(s.integer("max_collision_impulses", c.max_collision_impulses));
  if (c.max_collision_impulses < 0 || c.max_collision_impulses > 1000000)
    bad("max_collision_impulses must be between 0 and 1000000");
  c.max_contacts = int(s.integer("max_contacts", c.max_contacts));
  if (c.max_contacts < 1 || c.max_contacts > 64) bad("max_contacts must be between 1 and 64");
  c.surface_layer = s.number("surface_layer", c.surface_layer);
  if (!(c.surface_layer >= 0 && c.surface_layer < 1)) bad("surface_layer must be in [0, 1) m");
  c.max_correcting_velocity = s.number("max_correcting_velocity", c.max_correcting_velocity);
  if (!(c.max_correcting_velocity > 0)) bad("max_correcting_velocity must be > 0");
  c.substeps = int(s.integer("substeps", c.substeps));
  if (c.substeps < 1 || c.substeps > 1000) bad("substeps must be between 1 and 1000");
  const std::string contacts = s.string("substep_contacts", "kept");
  if (contacts == "kept")
    c.substep_contacts = RigidBodyConfig::SubstepContacts::Kept;
  else if (contacts == "found")
    c.substep_contacts = RigidBodyConfig::SubstepContacts::Found;
  else
    bad("substep_contacts must be \"kept\" or \"found\"");
  c.auto_disable = s.boolean("auto_disable", c.auto_disable);
  c.joint_projection = s.boolean("joint_projection", c.joint_projection);
  c.ccd = s.boolean("ccd", c.ccd);
  c.auto_disable_linear = s.number("auto_disable_linear", c.auto_disable_linear);
  if (!(c.auto_disable_linear >= 0)) bad("auto_disable_linear must be >= 0 m/s");
  c.auto_disable_angular = s.number("auto_disable_angular", c.auto_disable_angular);
  if (!(c.auto_disable_angular >= 0)) bad("auto_disable_angular must be >= 0 rad/s");
  c.auto_disable_steps = int(s.integer("auto_disable_steps", c.auto_disable_steps));
  if (c.auto_disable_steps < 1 || c.auto_disable_steps > 100000)
    bad("auto_disable_steps must be between 1 and 100000");
  return c;
}

}  // namespace alloy::rigid
