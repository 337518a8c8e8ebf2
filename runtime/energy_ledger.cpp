#include "runtime/energy_ledger.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy {

std::string_view to_string(EnergyKind kind) {
  switch (kind) {
    case EnergyKind::Source:
      return "source";
    case EnergyKind::Sink:
      return "sink";
    case EnergyKind::Store:
      return "store";
    case EnergyKind::Transfer:
      return "transfer";
  }
  return "?";
}

void EnergyReport::add(std::string_view account, EnergyKind kind, double joules) {
  entries_.push_back({std::string(account), kind, joules});
}

double EnergyBalance::fraction() const {
  return moved > 0 ? std::abs(residue()) / moved : 0.0;
}

EnergyAccount& EnergyLedger::account(std::string_view stage, std::string_view name,
                                     EnergyKind kind) {
  for (std::size_t i = 0; i < accounts_.size(); ++i) {
    EnergyAccount& a = accounts_[i];
    if (a.stage == stage && a.name == name && a.kind == kind) {
      if (!reported_[i]) a.last = 0;  // the first report of this record
      reported_[i] = true;
      return a;
    }
  }
  accounts_.push_back({.stage = std::string(stage), .name = std::string(name), .kind = kind});
  reported_.push_back(true);
  before_.push_back(false);
  return accounts_.back();
}

void EnergyLedger::add(std::string_view stage, const EnergyReport& report) {
  for (const EnergyReport::Entry& e : report.entries()) {
    // A non-finite report would poison every later sum: it is booked as 0
    // (the stage that made it is refused by the world's own checks anyway).
    const double j = std::isfinite(e.joules) ? e.joules : 0.0;
    EnergyAccount& a = account(stage, e.account, e.kind);
    if (e.kind == EnergyKind::Store) {
      // A store met at the first record opens at its level; one that
      // appears later opens at 0, so the energy it brings is seen.
      if (a.total == 0 && a.level == 0 && a.start == 0 && records_ == 0) a.start = a.level = j;
      a.last += j - a.level;
      a.level = j;
    } else {
      a.last += j;
    }
  }
}

void EnergyLedger::hand_over_stores() {
  // A store that a stage began to report in this record while another
  // stage of the same area stopped reporting a store of the same name (one
  // rigid-body engine swapped for another: "rigid_body" -> "rigid_body.box2d",
  // both holding the bodies' "kinetic energy") is the same energy: the new
  // one continues from the old one's level, so that the swap books none
  // created, and none lost with the engine that left.
  auto area = [](const std::string& stage) {
    const std::size_t at = stage.find('@');
    return at == std::string::npos ? std::string_view() : std::string_view(stage).substr(at);
  };
  for (std::size_t i = 0; i < accounts_.size(); ++i) {
    EnergyAccount& a = accounts_[i];
    if (a.kind != EnergyKind::Store || !reported_[i] || before_[i]) continue;
    for (std::size_t j = 0; j < accounts_.size(); ++j) {
      EnergyAccount& gone = accounts_[j];
      if (gone.kind != EnergyKind::Store || reported_[j] || !before_[j] || gone.name != a.name ||
          area(gone.stage) != area(a.stage))
        continue;
      a.last = a.level - gone.level;
      before_[j] = false;  // handed over once
      break;
    }
  }
}

void EnergyLedger::close_record() {
  if (records_ > 0) hand_over_stores();
  EnergyBalance b;
  double flow = 0;
  for (std::size_t i = 0; i < accounts_.size(); ++i) {
    EnergyAccount& a = accounts_[i];
    if (!reported_[i])
      a.last = 0;  // a flow not reported again moved nothing; a store kept its level
    before_[i] = reported_[i];
    reported_[i] = false;
    a.total += a.last;
    switch (a.kind) {
      case EnergyKind::Source:
        b.sources += a.last, flow += std::abs(a.last);
        break;
      case EnergyKind::Sink:
        b.sinks += a.last, flow += std::abs(a.last);
        break;
      case EnergyKind::Store:
        b.stored += a.last, flow += std::abs(a.last);
        break;
      case EnergyKind::Transfer:
        b.transfers += a.last;
        break;
    }
  }
  b.moved = flow / 2;
  last_ = b;
  total_.sources += b.sources, total_.sinks += b.sinks, total_.stored += b.stored;
  total_.transfers += b.transfers, total_.moved += b.moved;
  ++records_;
}

void EnergyLedger::record(World& world) {
  world.keep_energy_books();
  for (const std::string& name : world.active_stages()) {
    Stage* stage = world.stage(name);
    if (!stage) continue;
    scratch_.clear();
    stage->report_energy(world.stage_view(name), scratch_);
    if (!scratch_.entries().empty()) add(name, scratch_);
  }
  close_record();
}

const EnergyAccount* EnergyLedger::find(std::string_view stage, std::string_view name) const {
  for (const EnergyAccount& a : accounts_)
    if (a.stage == stage && a.name == name) return &a;
  return nullptr;
}

namespace {
std::string joules(double j) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%14.6f J", j);
  return buf;
}
}  // namespace

std::string EnergyLedger::table() const {
  std::string out = "energy ledger (" + std::to_string(records_) + " records)\n";
  auto line = [&](const std::string& label, double j) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "  %-52s", label.c_str());
    out += buf + joules(j) + "\n";
  };
  for (EnergyKind kind : {EnergyKind::Source, EnergyKind::Sink, EnergyKind::Store}) {
    out += std::string(kind == EnergyKind::Source ? "sources"
                       : kind == EnergyKind::Sink ? "sinks"
                                                  : "stores (change)") +
           "\n";
    for (const EnergyAccount& a : accounts_)
      if (a.kind == kind) line(a.stage + ": " + a.name, a.total);
  }
  // Transfers by name: each side, and what the coupling created (the sum).
  std::map<std::string, double> net;
  for (const EnergyAccount& a : accounts_)
    if (a.kind == EnergyKind::Transfer) net[a.name] += a.total;
  if (!net.empty()) out += "transfers (received; the sum over the sides is a mismatch)\n";
  for (const auto& [name, sum] : net) {
    for (const EnergyAccount& a : accounts_)
      if (a.kind == EnergyKind::Transfer && a.name == name) line(a.stage + ": " + a.name, a.total);
    line("  mismatch of " + name, sum);
  }
  const EnergyBalance& b = total_;
  out += "balance\n";
  line("sources", b.sources);
  line("sinks", b.sinks);
  line("stored change", b.stored);
  line("residue (sources - sinks - stored change)", b.residue());
  line("  created by the couplings (transfers' sum)", b.transfers);
  line("  left by the stages' own books", b.unexplained());
  line("energy moved", b.moved);
  char buf[96];
  std::snprintf(buf, sizeof buf, "  residue / energy moved: %.4g %%\n", 100 * b.fraction());
  out += buf;
  return out;
}

}  // namespace alloy
