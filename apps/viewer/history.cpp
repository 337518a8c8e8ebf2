#include "apps/viewer/history.hpp"

namespace alloy::viewer {

namespace {
const std::string kNothing;
}

void History::record(const World& world, std::string what) {
  // A delta against the last record: columns the edit leaves alone are shared.
  const Snapshot* base = undo_.empty() ? nullptr : &undo_.back().snapshot;
  undo_.push_back({world.snapshot(base), std::move(what)});
  if (undo_.size() > kDepth) undo_.pop_front();
  redo_.clear();
  ++edits_since_save_;
}

void History::forget_last() {
  if (undo_.empty()) return;
  undo_.pop_back();
  --edits_since_save_;
}

bool History::undo(World& world) {
  if (undo_.empty()) return false;
  Entry now{world.snapshot(&undo_.back().snapshot), undo_.back().what};
  world.restore(undo_.back().snapshot);  // throws before changing anything if it cannot
  undo_.pop_back();
  redo_.push_back(std::move(now));
  --edits_since_save_;
  return true;
}

bool History::redo(World& world) {
  if (redo_.empty()) return false;
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
