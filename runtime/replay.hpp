// Replays: a recording is the initial snapshot of a world, every input from
// outside with the step before which it came, and hashes of every step; a
// replay runs it again and names the first step, the stage and the objects
// and properties where the two runs part (docs/saves.md, "Replays").
//
// Recording (Recorder) costs, per step, one state hash (hash_state), one
// hash per object and, after each stage that runs, one hash of every column
// and of that stage's own state: a replay keeps no snapshots, so it needs
// the recording's own per-stage hashes to tell where inside a step it parts.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/save_file.hpp"

namespace alloy {

class World;

/// The hash after a stage ran: every column with members (name, kind,
/// members and values, in property-name order) and the stage's own state
/// (Stage::save_state). Cheaper than hash_state: it copies nothing.
std::uint64_t stage_hash(World& world, const std::string& stage);
/// One hash per live object (its name and, in property-name order, every
/// property it carries), computed in one pass over the columns.
std::vector<std::pair<ObjectId, std::uint64_t>> object_hashes(const World& world);

/// Records a world as it runs. Construct it between steps (before the first
/// step, or later: the recording starts from the world as it is then); from
/// then on it hears every input from outside through the world's one input
/// observer (World::add_input_observer: set, remove, create, destroy,
/// unfreeze, swap, plugin_changed, restore, sync, whoever makes them: the
/// viewer's tools and its undo, a test, a script) and hashes the world at
/// the end of every step. Nothing else needs to tell it anything. Timeline
/// inputs and scheduled swaps are in the initial snapshot; the world applies
/// them again by itself, and the recorder logs them (from the world's
/// events) for the report. A mod reloaded between steps is logged from its
/// "mod_reloaded" event, and a replay reloads it from the files it finds
/// then. Recording stops when the recorder is destroyed (its observers go
/// quiet; the world cannot remove them).
class Recorder {
 public:
  Recorder(World& world, SaveMeta meta);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// A reload of `mod` done between steps by the caller (logged only), when
  /// no "mod_reloaded" event tells it.
  void reloaded(const std::string& mod);
  /// Steps recorded so far.
  std::size_t steps() const;
  /// What was recorded so far (meta.kind "replay").
  const SaveData& data() const;
  /// Writes it (atomically, in the save format).
  void write(const std::string& path) const;

 private:
  struct State;
  World& world_;
  std::shared_ptr<State> state_;
};

struct ReplayOptions {
  /// Reloads a mod the recording reloaded (the CLI reloads it from its
  /// files); null: a reload in the log is an InputError.
  std::function<void(World&, const std::string& mod)> reload;
  /// Test seam: called after each stage of each replayed step, to make a
  /// replay part from its recording on purpose (tests/runtime/replay_test).
  std::function<void(World&, std::uint64_t step, const std::string& stage)> tamper;
};

struct ReplayResult {
  bool identical = true;
  std::uint64_t steps = 0;      ///< steps replayed (all, or through the first that differs)
  std::uint64_t last_step = 0;  ///< step_count() after the last replayed step
  std::uint64_t step = 0;       ///< the first step whose hash differs
  std::string stage;            ///< the stage after which it first differs ("" : before any)
  std::vector<std::string> properties;  ///< property columns that differ after that step
  std::vector<std::string> objects;     ///< objects that differ after it ("name (#slot)")
  /// "identical through step N", or the step, stage, properties and objects.
  std::string message() const;
};

/// Replays `data` (a recording). `rebuild` returns a fresh world built from
/// the recording's scene; it is called once, and again when the run differs
/// (the step that differs is run again from the start, with per-stage
/// hashes). Throws InputError if the recording does not fit the world.
ReplayResult replay(const SaveData& data, const std::function<World&()>& rebuild,
                    const ReplayOptions& options = {});

}  // namespace alloy
