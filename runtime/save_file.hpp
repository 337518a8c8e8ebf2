// Save files: a Snapshot (snapshot.hpp) on disk, in one versioned format
// shared by saves (`alloy run --save`) and replays (`alloy run --record`,
// runtime/replay.hpp). docs/saves.md describes every byte; in short:
//
//   prefix (48 bytes, little endian)
//     0  magic        "ALLOYSAV"
//     8  format       u32, kSaveFormat; a reader refuses a newer one
//     12 flags        u32, bit 0: the body is one zstd frame
//     16 meta_size    u64, bytes of the meta block
//     24 body_size    u64, bytes of the body as stored
//     32 body_raw     u64, bytes of the body once decompressed (<= kMaxBody)
//     40 checksum     u64, XXH3-64 of bytes 0..39, the meta block and the
//                     stored body, in that order
//   meta block (never compressed: `alloy check` and tools read it cheaply)
//     sections PROG (program, its version, what the file is), SCEN (the
//     scene), PROP (every property type: name, kind, enum values), PLUG
//     (the plugins registered: name, kind), MODS (the mods: name, version)
//   body: sections STEP, OBJS, COLS, FRZN, AREA, STGS, SSTA, MSTA, INPT, SWAP (one
//     per part of a Snapshot), then a replay's RLOG and RHSH, then END.
//
// A section is a 4-character tag, its size (u64) and its bytes. Sections
// come in a fixed order, each exactly once; a reader names the section and
// the byte where a file is wrong. Adding a field to Snapshot is one new entry
// in the table of snapshot sections in save_file.cpp (and a format bump).
//
// Every count is checked against the bytes left before anything is
// allocated, the body's size is bounded, and the checksum is checked before
// the body is decompressed or read: a damaged file is an InputError naming
// the file, never a crash, a hang or a huge allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/snapshot.hpp"

namespace alloy {

class World;

/// The format this build writes and the newest it reads.
inline constexpr std::uint32_t kSaveFormat = 1;
/// The largest body (decompressed) a reader accepts: 1 GiB.
inline constexpr std::uint64_t kMaxBody = 1ull << 30;
/// What the PROG section says the file is made by.
inline constexpr const char* kSaveProgram = "alloy";

/// What the meta block says: enough to rebuild the world the snapshot came
/// from, and to refuse it clearly when this installation cannot.
struct SaveMeta {
  std::string program = kSaveProgram;  ///< the program that wrote it
  std::string program_version;         ///< its version (ALLOY_VERSION)
  std::string kind = "save";           ///< "save" or "replay"
  std::string scene;                   ///< the scene file or mod folder, as given to `run`
  std::string scene_name;              ///< the scene's display name
  struct Property {
    std::string name;
    PropertyKind kind = PropertyKind::Number;
    std::vector<std::string> enum_values;  ///< an Enum's value names, in order
  };
  std::vector<Property> properties;  ///< every property type registered, by name
  struct Plugin {
    std::string name, kind;  ///< kind: "resolver", "derived", "interaction"
  };
  std::vector<Plugin> plugins;  ///< every plugin registered (native and mods')
  struct Mod {
    std::string name, version;
  };
  std::vector<Mod> mods;  ///< the mods the scene loaded, with their manifest versions
};

/// The meta block for `world`: its registry's properties and plugins. The
/// caller fills program_version, scene, scene_name and mods.
SaveMeta describe_world(const World& world);

/// One recorded input of a replay (runtime/replay.hpp), applied between
/// steps: `step` is the recording's clock when it came (the initial
/// snapshot's step plus the steps recorded before it), which is the world's
/// step_count() unless an earlier input restored another moment (the
/// viewer's undo). Inputs are in clock order.
struct ReplayInput {
  enum class Kind : std::uint8_t {
    Set = 0,       ///< an edit from outside (the viewer): object, property, value; replayed
    Swap = 1,      ///< World::swap between steps: area, from, to; replayed
    Reload = 2,    ///< a mod reloaded (hot reload): text = the mod; replayed
    Timeline = 3,  ///< a timeline input the world applied; for the report only
    Swapped = 4,   ///< a scheduled swap the world made (scene or --swap); report only
    // The rest of World's inputs (WorldInput), all replayed:
    Remove = 5,           ///< World::remove: object, property
    Create = 6,           ///< World::create: id = the object made, text = its name
    Destroy = 7,          ///< World::destroy: object
    Unfreeze = 8,         ///< World::unfreeze: object
    PluginChanged = 9,    ///< World::plugin_changed: text = the plugin
    Restore = 10,         ///< World::restore (the viewer's undo): snapshot
    Sync = 11,            ///< World::sync
    Schedule = 12,        ///< World::schedule from outside: object, property, value, time
    ScheduleSwap = 13,    ///< World::schedule_swap from outside: area, from, to, time
    DemandImpulses = 14,  ///< World::demand_impulses: value (bool)
  };
  std::uint64_t step = 0;
  Kind kind = Kind::Set;
  ObjectId id;           ///< Set, Timeline, Remove, Create, Destroy, Unfreeze
  std::string property;  ///< Set, Timeline, Remove
  PropertyValue value;   ///< Set, Timeline, Schedule; DemandImpulses (bool)
  double time = 0;       ///< Schedule, ScheduleSwap: when it comes due, s
  std::string area, from, to,
      text;  ///< Swap, Swapped (area, from, to); Reload, Create, PluginChanged (text)
  /// Restore: the snapshot restored (written in the file as the snapshot's
  /// sections, in a string of their own).
  std::shared_ptr<const Snapshot> snapshot;
};

/// The hashes a recording keeps of each step (runtime/replay.hpp).
struct StepHashes {
  std::uint64_t step = 0;   ///< step_count() after the step
  std::uint64_t world = 0;  ///< hash_state(world).world
  /// After each stage that ran in the step, in order: the stage and the hash
  /// of every column plus that stage's own state (replay.hpp, stage_hash).
  std::vector<std::pair<std::string, std::uint64_t>> stages;
  /// Per property column (hash_state's), only those that changed since the
  /// previous step (all of them at the first), by name.
  std::vector<std::pair<std::string, std::uint64_t>> columns;
  /// Per live object (hash_object's), only those that changed since the
  /// previous step (all at the first); a slot whose object died is listed
  /// with a null id.
  std::vector<std::pair<ObjectId, std::uint64_t>> objects;
};

/// What a save file holds once read.
struct SaveData {
  SaveMeta meta;
  Snapshot snapshot;                ///< a save's world; a replay's initial world
  std::vector<ReplayInput> inputs;  ///< a replay's log, in order (empty in a save)
  std::vector<StepHashes> hashes;   ///< a replay's hashes, one per step (empty in a save)
};

/// The container, for tests and tools that need to damage or rebuild a file
/// with a valid checksum: the meta block and the body, uncompressed.
struct SaveContainer {
  std::uint32_t format = kSaveFormat;
  std::string meta, body;
};
/// The bytes of a file holding `c`; the body is compressed with zstd when
/// that makes it smaller.
std::string pack_save(const SaveContainer& c);
/// The inverse: checks the magic, format, sizes and checksum, decompresses.
/// `what` names the file in errors. Throws InputError.
SaveContainer unpack_save(const std::string& bytes, const std::string& what);

/// The file's bytes for `data` (pack_save of encode_save's container).
std::string encode_save(const SaveData& data);
/// Reads a whole file's bytes; `what` names it in errors. Throws InputError.
SaveData decode_save(const std::string& bytes, const std::string& what);

/// Whether `path` is a regular file that starts with the save magic or is
/// named *.alloysave or *.alloyrec (so that `alloy run` and `alloy check`
/// tell a save from a scene, and a damaged save is refused as a save).
bool is_save_file(const std::string& path);

/// Where an atomic write is; a test seam to kill the writer mid-write.
struct WriteHooks {
  /// Called after each chunk of the temporary file is written (before the
  /// fsync and the rename), with the bytes written so far.
  std::function<void(std::size_t written)> after_chunk;
  std::size_t chunk = 64 * 1024;
};
/// Writes `bytes` to `path` atomically: a new temporary file in the same
/// folder ("PATH.tmp.PID"), written, fsync'ed, renamed over `path`, and the
/// folder fsync'ed. A writer that dies before the rename leaves `path` as it
/// was, and its temporary file behind: the next write to `path` removes the
/// temporary files of writers of `path` whose process is gone (a live
/// writer's is left). Throws InputError naming the path.
void write_file_atomic(const std::string& path, const std::string& bytes,
                       const WriteHooks& hooks = {});
/// Reads a save file (refusing folders, empty files and files over the
/// format's bound before reading them whole) and decodes it. Throws InputError.
SaveData read_save_file(const std::string& path);
/// encode_save + write_file_atomic.
void write_save_file(const std::string& path, const SaveData& data, const WriteHooks& hooks = {});

/// Checks that a save fits a world about to restore it: every property of the
/// save is registered with the same kind (and the same enum values), every
/// mod of the save is loaded (`mods`: name and version of each loaded mod).
/// Throws InputError naming the property (and its owner) or the mod. A mod
/// whose version differs is not an error here: `notes` gets one line each.
/// A property no loaded plugin registers and no object of the save carries
/// is dropped from `data` (nothing is lost).
void check_save_fits(SaveData& data, const std::string& what, const World& world,
                     const std::vector<SaveMeta::Mod>& mods, std::vector<std::string>* notes);

}  // namespace alloy
