#include "apps/viewer/history.hpp"

namespace alloy::viewer {

namespace {
const std::string kNothing;
}

void History::sync(World& world) {
  // World has no public "sync the structure now"; plugin_changed does exactly
  // that once it has removed the stages of the plugin named, and a name no
  // plugin can have (plugin names never hold a space) removes nothing.
  // (A World::sync() would say it better: see the report of issue 17.)
  world.plugin_changed(" viewer: sync ");
  // And the stages built afresh from the properties, as loading a saved file
  // builds them: a rigid body grown part by part while the player builds
  // steps a few bits apart from one built at once, and the file the player
  // saves must run as the board did.
  world.restore(world.snapshot());
}

void History::record(World& world, std::string what) {
  sync(world);
  ++changes_;
  // Whole snapshots, not deltas: a delta taken after an edit that added an
  // object shares the base's untouched columns, which cover one slot too few,
  // and World::restore refuses it ("its column 'acoustic' does not cover its
  // 2 slots"). A kit board's snapshot is a few kilobytes.
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
