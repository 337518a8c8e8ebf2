#include "apps/alloy/profile_report.hpp"

#include <cstdio>

namespace alloy::app {

void print_profile(std::ostream& out, const Profile& p) {
  const double steps = p.steps ? double(p.steps) : 1.0;
  const double total = p.phases.total() > 0 ? p.phases.total() : 1.0;
  char line[200];
  std::snprintf(line, sizeof line, "profile over %llu steps: %.2f us per step\n",
                (unsigned long long)p.steps, 1e6 * p.phases.total() / steps);
  out << line;
  std::snprintf(line, sizeof line, "  %-34s %-12s %9s %9s %12s %7s\n", "stage", "kind", "runs", "skipped",
                "us/step", "share");
  out << line;
  for (const StageTiming& s : p.stages) {
    std::snprintf(line, sizeof line, "  %-34s %-12s %9llu %9llu %12.2f %6.1f%%\n", s.name.c_str(),
                  std::string(to_string(s.kind)).c_str(), (unsigned long long)s.runs,
                  (unsigned long long)s.skipped, 1e6 * s.seconds / steps, 100 * s.seconds / total);
    out << line;
  }
  const std::pair<const char*, double> phases[] = {{"advance", p.phases.advance},
                                                   {"derive", p.phases.derive},
                                                   {"interact", p.phases.interact},
                                                   {"publish", p.phases.publish},
                                                   {"edits and rebuilds", p.phases.edits}};
  out << "  phases:\n";
  for (const auto& [name, t] : phases) {
    std::snprintf(line, sizeof line, "    %-32s %12.2f us/step %6.1f%%\n", name, 1e6 * t / steps, 100 * t / total);
    out << line;
  }
  out << "  not instantiated (no object needs them):";
  if (p.not_instantiated.empty()) out << " none";
  for (const auto& n : p.not_instantiated) out << " " << n;
  out << '\n';
}

}  // namespace alloy::app
