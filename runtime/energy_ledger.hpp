// The energy ledger: each stage reports the energy it moved, and the books of
// a run are balanced (docs/energy.md).
//
// A stage reports through Stage::report_energy(EnergyReport&), called by
// EnergyLedger::record() between steps, on the world's thread. Four kinds of
// account:
//
//   source    energy that entered the books since the last report (a
//             battery's work), J
//   sink      energy that left them since the last report (I^2 R heat,
//             drag, sound), J
//   store     energy held now (kinetic, potential, a coil's field), J: the
//             ledger takes the change between records
//   transfer  energy received from another stage since the last report
//             (negative: given), J. Both sides report the same account name
//             ("magnetism": the EMF's work on the circuits, and the magnetic
//             forces' work on the bodies). Transfers are internal to the
//             books: their sum over the sides is what the coupling created
//             (or destroyed), 0 for a coupling that conserves energy.
//
// Flows are reported once: a stage adds up what it moved in its advances and
// hands the sums over at the next report, then starts again from zero (a
// stage that runs every n-th step reports its flows in the step after the
// advance that made them). Levels are reported every time.
//
// The balance: residue = sources - sinks - (change of stores). It is 0 when
// every joule is booked and the couplings conserve energy. A stage whose own
// books close (what it received, gave, took in and holds agree) leaves in
// the residue exactly minus what its transfers created: so the residue is
// the couplings' mismatch plus what the stages could not account for
// themselves. "Energy moved" is
// sum over records of (sources + sinks + |change of each store|) / 2: the
// energy that passed through the books, counting each joule once whether it
// came from a battery or from a store.
//
// Adding a stage to the books: override report_energy, keep the counters it
// needs (a few doubles), and write a line per account:
//
//   void report_energy(EnergyReport& out) override {
//     out.sink("light", std::exchange(emitted_, 0.0));
//   }
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace alloy {

class World;

enum class EnergyKind : std::uint8_t { Source, Sink, Store, Transfer };
std::string_view to_string(EnergyKind kind);

/// What one stage tells the ledger at one report.
class EnergyReport {
 public:
  struct Entry {
    std::string account;  ///< the account's name within the stage ("battery work")
    EnergyKind kind;
    double joules;  ///< flow since the last report (source, sink, transfer) or level (store)
  };
  /// Energy that entered the books since the last report, J.
  void source(std::string_view account, double joules) { add(account, EnergyKind::Source, joules); }
  /// Energy that left the books since the last report, J.
  void sink(std::string_view account, double joules) { add(account, EnergyKind::Sink, joules); }
  /// Energy held now, J.
  void store(std::string_view account, double joules) { add(account, EnergyKind::Store, joules); }
  /// Energy received from other stages through `account` since the last
  /// report (negative: given), J.
  void transfer(std::string_view account, double joules) {
    add(account, EnergyKind::Transfer, joules);
  }
  const std::vector<Entry>& entries() const { return entries_; }
  void clear() { entries_.clear(); }

 private:
  void add(std::string_view account, EnergyKind kind, double joules);
  std::vector<Entry> entries_;
};

/// One account of the books: a stage's named source, sink, store or side of a transfer.
struct EnergyAccount {
  std::string
      stage;         ///< the stage instance that reports it ("electricity", "gravity.uniform@moon")
  std::string name;  ///< the account's name within the stage
  EnergyKind kind = EnergyKind::Source;
  double last = 0;   ///< flow at the last record (stores: the change since the record before), J
  double total = 0;  ///< flow summed over the run (stores: change since the first level), J
  double level = 0;  ///< stores: the last level reported, J
  double start =
      0;  ///< stores: the level at the first record (0 for a store that appeared later), J
};

/// Sums of the books over some span of records.
struct EnergyBalance {
  double sources = 0;    ///< energy that entered, J
  double sinks = 0;      ///< energy that left, J
  double stored = 0;     ///< change of all stores, J
  double transfers = 0;  ///< net of all transfers (what the couplings created), J
  double moved = 0;      ///< energy moved (header), J
  /// sources - sinks - stored: what no source, sink or store explains, J.
  double residue() const { return sources - sinks - stored; }
  /// The part of the residue the stages' own books leave, J: residue + transfers.
  double unexplained() const { return residue() + transfers; }
  /// |residue| as a fraction of the energy moved (0 when nothing moved).
  double fraction() const;
};

/// The books of a run. Call record() once after World::start() (the stores'
/// opening levels) and after every step (or every few: flows accumulate in
/// the stages until asked for).
class EnergyLedger {
 public:
  /// Asks every active stage of `world` for its report, in run order.
  void record(World& world);
  /// Adds one stage's report (record() calls it; tests may too).
  void add(std::string_view stage, const EnergyReport& report);
  /// Closes a record: computes the changes and the energy moved since the last.
  void close_record();

  const std::vector<EnergyAccount>& accounts() const { return accounts_; }
  /// The account of `stage` named `name`, or null.
  const EnergyAccount* find(std::string_view stage, std::string_view name) const;
  /// The books since the first record.
  const EnergyBalance& total() const { return total_; }
  /// The books of the last record.
  const EnergyBalance& last() const { return last_; }
  std::uint64_t records() const { return records_; }
  /// The balance as a table (alloy run --energy): every account, each
  /// transfer's sides and mismatch, the residue and its fraction of the
  /// energy moved.
  std::string table() const;

 private:
  EnergyAccount& account(std::string_view stage, std::string_view name, EnergyKind kind);
  std::vector<EnergyAccount> accounts_;
  std::vector<bool> reported_;  // accounts reported in the open record
  std::vector<bool> before_;    // and in the record before it
  void hand_over_stores();
  EnergyBalance total_, last_;
  std::uint64_t records_ = 0;
  EnergyReport scratch_;
};

}  // namespace alloy
