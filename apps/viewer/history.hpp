// Undo and redo of the player's edits, built on the world's snapshots
// (World::snapshot / restore, runtime/snapshot.hpp).
//
// Before an edit the viewer records the world as it is (record()); undo puts
// the world back as it was before the last edit and keeps the present for
// redo. A snapshot is the whole state, so undo while running also takes the
// clock back to the moment of the edit: the world goes on from there, as if
// the edit had never been made.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>

#include "runtime/world.hpp"

namespace alloy::viewer {

class History {
 public:
  /// Snapshots kept for undo; older ones are forgotten.
  static constexpr std::size_t kDepth = 200;

  /// Records the world before an edit described by `what` ("move bar",
  /// "hinge"); clears what could be redone.
  void record(World& world, std::string what);
  /// Drops the last record (an edit that turned out to change nothing).
  void forget_last();
  /// Puts the world back as it was before the last edit. False (nothing
  /// changed) if there is nothing to undo. Throws what World::restore throws.
  bool undo(World& world);
  bool redo(World& world);
  bool can_undo() const { return !undo_.empty(); }
  bool can_redo() const { return !redo_.empty(); }
  /// What the next undo / redo would take back ("" if none).
  const std::string& undo_what() const;
  const std::string& redo_what() const;
  std::size_t undo_depth() const { return undo_.size(); }
  /// Forgets everything (another scene was opened).
  void clear();
  /// Edits recorded since the last mark_saved() (the file is out of date).
  bool dirty() const { return edits_since_save_ != 0; }
  void mark_saved() { edits_since_save_ = 0; }
  /// Counts records, undos and redos: the viewer brings the stage set up to
  /// date (sync) after a frame in which it changed.
  std::uint64_t changes() const { return changes_; }

  /// Brings the world's stage set up to date with the edits made since its
  /// last step (the stages a new part needs are instantiated, built and
  /// primed: what the next step would do first). A snapshot is only
  /// restorable when taken so: restore rebuilds the stages the properties
  /// call for and checks them against the snapshot's list.
  static void sync(World& world);

 private:
  struct Entry {
    Snapshot snapshot;
    std::string what;
  };
  std::deque<Entry> undo_, redo_;
  long edits_since_save_ = 0;
  std::uint64_t changes_ = 0;
};

}  // namespace alloy::viewer
