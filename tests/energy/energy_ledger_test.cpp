// The ledger's arithmetic (runtime/energy_ledger.hpp) on hand-made reports:
// what a source, a sink, a store and a transfer do to the balance, and what
// "energy moved" counts.
#include "runtime/energy_ledger.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace alloy {
namespace {

TEST(EnergyLedger, SourcesSinksStoresAndTransfersBalance) {
  EnergyLedger ledger;
  // Opening levels: a capacitor holding 2 J; nothing moved yet.
  EnergyReport circuit;
  circuit.store("capacitor", 2.0);
  ledger.add("circuit", circuit);
  ledger.close_record();
  EXPECT_EQ(ledger.total().moved, 0.0);
  EXPECT_EQ(ledger.total().residue(), 0.0);

  // A step: the battery gives 10 J, 7 J become heat, the capacitor rises to
  // 4 J, and the circuit gives 1 J to a body (transfer -1) that receives it.
  circuit.clear();
  circuit.source("battery", 10.0);
  circuit.sink("heat", 7.0);
  circuit.store("capacitor", 4.0);
  circuit.transfer("magnetism", -1.0);
  ledger.add("circuit", circuit);
  EnergyReport body;
  body.store("kinetic", 1.0);
  body.transfer("magnetism", 1.0);
  ledger.add("body", body);
  ledger.close_record();
  const EnergyBalance& b = ledger.total();
  EXPECT_DOUBLE_EQ(b.sources, 10.0);
  EXPECT_DOUBLE_EQ(b.sinks, 7.0);
  EXPECT_DOUBLE_EQ(b.stored, 3.0);  // +2 capacitor, +1 kinetic (a store met later opens at 0)
  EXPECT_DOUBLE_EQ(b.transfers, 0.0);
  EXPECT_DOUBLE_EQ(b.residue(), 0.0);
  EXPECT_DOUBLE_EQ(b.moved, (10.0 + 7.0 + 2.0 + 1.0) / 2);
  EXPECT_DOUBLE_EQ(ledger.find("circuit", "capacitor")->total, 2.0);
  EXPECT_DOUBLE_EQ(ledger.find("circuit", "capacitor")->level, 4.0);

  // A coupling that creates energy: the body gets 1.5 J for the 1 J given.
  circuit.clear();
  circuit.transfer("magnetism", -1.0);
  circuit.store("capacitor", 4.0);
  ledger.add("circuit", circuit);
  body.clear();
  body.store("kinetic", 2.5);
  body.transfer("magnetism", 1.5);
  ledger.add("body", body);
  ledger.close_record();
  EXPECT_DOUBLE_EQ(ledger.last().transfers, 0.5);
  EXPECT_DOUBLE_EQ(ledger.last().residue(), -1.5);      // 1.5 J more stored, from no source
  EXPECT_DOUBLE_EQ(ledger.last().unexplained(), -1.0);  // of which the coupling made 0.5
  EXPECT_DOUBLE_EQ(ledger.total().residue(), -1.5);
  // Flows are per record: a flow not reported again moved nothing.
  EXPECT_EQ(ledger.find("circuit", "battery")->last, 0.0);
  EXPECT_DOUBLE_EQ(ledger.find("circuit", "battery")->total, 10.0);
  // The table names every account and the mismatch of the transfer.
  const std::string t = ledger.table();
  for (const char* s : {"circuit: battery", "circuit: heat", "body: kinetic",
                        "mismatch of magnetism", "residue / energy moved"})
    EXPECT_NE(t.find(s), std::string::npos) << s << "\n" << t;
}

TEST(EnergyLedger, MovedCountsAStoreSwingingBothWays) {
  // A pendulum's books: kinetic and potential trade 1 J back and forth.
  EnergyLedger ledger;
  auto record = [&](double kinetic, double potential) {
    EnergyReport r;
    r.store("kinetic", kinetic);
    r.store("potential", potential);
    ledger.add("swing", r);
    ledger.close_record();
  };
  record(0, 1);
  record(1, 0);
  record(0, 1);
  EXPECT_DOUBLE_EQ(ledger.total().moved, 2.0);
  EXPECT_DOUBLE_EQ(ledger.total().residue(), 0.0);
  // A non-finite report is booked as 0, and the books stay finite.
  EnergyReport bad;
  bad.sink("heat", std::nan(""));
  ledger.add("swing", bad);
  ledger.close_record();
  EXPECT_EQ(ledger.total().sinks, 0.0);
  EXPECT_EQ(EnergyBalance{}.fraction(), 0.0);
}

}  // namespace
}  // namespace alloy
