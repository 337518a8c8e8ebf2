#include "apps/viewer/history.hpp"

namespace alloy::viewer {

namespace {
const std::string kNothing;
}

void History::sync(World& world) {
  // The stages built afresh from the properties, as loading a saved file
  // builds them: a rigid body grown part by part while the player builds
  // steps a few bits apart from one built at once, and the file the player
  // saves must run as the board did. World::sync() does both: the stage set
  // brought up to date, then every stage rebuilt as a restore would.
  world.sync();
}

void History::record(World& world, std::string what) {
  sync(world);
  ++changes_;
  // Whole snapshots, not deltas: a kit board's snapshot is a few kilobytes.
  // (Deltas taken after a create() are restorable since session 13.)
  undo_.push_back({world.snapshot(), std::move(what)});
  if (undo_.size() > kDepth) undo_.pop_front();
  redo_.clear();
  ++edits_since_save_;
}

void History::forget_last() {
  if (undo_.empty()) return;
  ++changes_;
  undo_.pop_back();
  --edits_since_save_;
}

bool History::undo(World& world) {
  if (undo_.empty()) return false;
  sync(world);
  ++changes_;
  Entry now{world.snapshot(), undo_.back().what};
  world.restore(undo_.back().snapshot);  // throws before changing anything if it cannot
  undo_.pop_back();
  redo_.push_back(std::move(now));
  --edits_since_save_;
  return true;
}

bool History::redo(World& world) {
  if (redo_.empty()) return false;
  sync(world);
  ++changes_;
  Entry before{world.snapshot(), redo_.back().what};
  world.restore(redo_.back().snapshot);
  redo_.pop_back();
  undo_.push_back(std::move(before));
  ++edits_since_save_;
  return true;
}

const std::string& History::undo_what() const {
  return undo_.empty() ? kNothing : undo_.back().what;
}
const std::string& History::redo_what() const {
  return redo_.empty() ? kNothing : redo_.back().what;
}

void History::clear() {
  undo_.clear();
  redo_.clear();
  edits_since_save_ = 0;
}

}  // namespace alloy::viewer
