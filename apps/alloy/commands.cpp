#include "apps/alloy/commands.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "apps/alloy/event_log.hpp"
#include "apps/alloy/profile_report.hpp"
#include "apps/alloy/trace_writer.hpp"
#include "apps/viewer/view_command.hpp"
#include "lua/lua_host.hpp"
#include "lua/mod_loader.hpp"
#include "lua/save_meta.hpp"
#include "lua/scene_loader.hpp"
#include "lua/watch_loop.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/sound/sound_resolver.hpp"
#include "resolvers/sound/wav_writer.hpp"
#include "runtime/energy_ledger.hpp"
#include "runtime/replay.hpp"
#include "runtime/save_file.hpp"
#include "runtime/state_hash.hpp"

namespace alloy::app {

namespace {

using lua::save_meta;
using lua::scene_mods;

struct RunOptions {
  std::string scene;
  std::optional<std::uint64_t> steps;
  std::optional<double> seconds;
  std::optional<double> dt;
  std::string trace;
  std::string trace_props = "position,orientation,velocity,angular_velocity";
  std::uint64_t trace_every = 1;
  std::string audio;
  std::vector<std::string> swaps;
  std::vector<std::string> reports;
  std::string events;
  bool profile = false;
  bool quiet = false;
  bool watch = false;
  bool hash = false;                    ///< print the state hash after the run
  bool energy = false;                  ///< keep the energy ledger and print its balance
  std::uint64_t hash_every = 0;         ///< and every N steps (0: only at the end)
  std::string save;                     ///< --save FILE: the world at the end of the run
  std::vector<std::string> save_every;  ///< --save-every T DIR: {T, DIR}
  std::string record;                   ///< --record FILE: a recording for `alloy replay`
};

constexpr double kDefaultSeconds = 5.0;  // when neither the scene nor the user says

std::vector<std::string> split_list(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) {
    const auto b = item.find_first_not_of(' '), e = item.find_last_not_of(' ');
    if (b != std::string::npos) out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

lua::LoadOptions load_options() {
  lua::LoadOptions o;
  if (const char* env = std::getenv("ALLOY_MODS")) {
    std::stringstream ss(env);
    for (std::string dir; std::getline(ss, dir, ':');)
      if (!dir.empty()) o.mod_paths.emplace_back(dir);
  }
  o.mod_paths.emplace_back(std::string(ALLOY_SOURCE_DIR) + "/mods");
  return o;
}

/// Where the mods' print() and reports go during `alloy run`: on standard
/// output in their place among the narration (a line printed in step N comes
/// after the narration of step N-1 and before that of step N's events), or
/// on standard error with --quiet. What one mod writes in a run is bounded
/// here too, whatever its budget (lua/mod_state.hpp) allows.
class ModLog {
 public:
  static constexpr std::uint64_t kBytesPerMod = 8u << 20;
  ModLog(Narrator* narrator, std::ostream& err) : narrator_(narrator), err_(err) {}
  void write(const std::string& mod, const std::string& line) {
    std::uint64_t& used = used_[mod];
    std::string text = "[" + mod + "] " + line;
    const std::uint64_t room = used < kBytesPerMod ? kBytesPerMod - used : 0;
    if (text.size() + 1 > room) {
      dropped_[mod] += text.size() + 1 - std::min<std::uint64_t>(room, text.size() + 1);
      if (room == 0) return;
      text.resize(room - 1);
    }
    used += text.size() + 1;
    if (narrator_)
      narrator_->line(text);
    else
      err_ << text << '\n';
  }
  void summary() {
    for (const auto& [mod, bytes] : dropped_) {
      const std::string text = "[" + mod + "] ... (" + std::to_string(bytes) +
                               " more bytes dropped: a mod's output is cut at " +
                               std::to_string(kBytesPerMod >> 20) + " MiB a run)";
      if (narrator_)
        narrator_->line(text);
      else
        err_ << text << '\n';
    }
  }

 private:
  Narrator* narrator_;
  std::ostream& err_;
  std::map<std::string, std::uint64_t> used_, dropped_;
};

/// The mod whose stage emitted `e` ("" for the engine's own stages), to
/// bound what each mod gets written. Sources are stage instances
/// ("plugin" or "plugin@area"); a mod's plugins are asked of the runtime.
class EventOwners {
 public:
  explicit EventOwners(const lua::ModRuntime* mods) : mods_(mods) {}
  const std::string& of(const Event& e) {
    auto it = cache_.find(e.source);
    if (it != cache_.end()) return it->second;
    std::string owner;
    if (mods_) {
      const std::string plugin = e.source.substr(0, e.source.find('@'));
      for (const auto& m : mods_->loaded())
        for (const auto& p : mods_->plugins_of(m))
          if (p == plugin) owner = m;
      if (e.source == "mods" && !e.text.empty()) owner = "mods";  // a mod stopped in a handler
    }
    return cache_.emplace(e.source, owner).first->second;
  }

 private:
  const lua::ModRuntime* mods_;
  std::map<std::string, std::string> cache_;
};

/// A scene with no object simulates nothing: said, not refused (an empty
/// scene is a valid start), as a compiler warns of an empty file.
void warn_if_empty(const World& world, const std::string& path, std::ostream& err) {
  if (world.store().object_count() == 0)
    err << "warning: " << path << ": the scene holds no objects: there is nothing to simulate\n";
}

/// Refuses an --audio path whose folder does not exist before the run, not after it.
void check_audio_path(const std::string& path) {
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError("cannot write audio file '" + path + "': no folder '" + dir.string() + "'");
}

/// Writes what the run sounded like, from t = 0 to the end, as a 16-bit WAV.
/// A run in which no part could ring is written as silence of its length.
void write_audio(World& world, const std::string& path, std::ostream& out, bool quiet) {
  const auto* sound = dynamic_cast<const sound::SoundResolver*>(world.stage("sound"));
  const double rate = sound ? sound->sample_rate() : sound::SoundSettings{}.sample_rate;
  std::vector<float> samples;
  if (sound) {
    // A resolver brought to life mid-run starts at its start_time: pad the
    // front so that the file's time is the world's time.
    samples.assign(std::size_t(std::llround(sound->start_time() * rate)), 0.0f);
    samples.insert(samples.end(), sound->samples().begin(), sound->samples().end());
  } else {
    samples.assign(std::size_t(std::llround(world.time() * rate)), 0.0f);
  }
  sound::WavInfo info;
  try {
    info = sound::write_wav(path, samples, int(rate), sound::WavLevel::fit);
  } catch (const std::runtime_error& e) {
    throw InputError(std::string("cannot write audio file: ") + e.what());
  }
  if (quiet) return;
  char line[160];
  std::snprintf(line, sizeof line, "audio: %s, %.3f s at %.0f Hz, ", path.c_str(),
                double(info.frames) / rate, rate);
  out << line;
  if (info.peak > 0) {
    std::snprintf(line, sizeof line, "peak %.1f dBFS", 20 * std::log10(info.peak));
    out << line;
  } else {
    out << "silent";
  }
  if (info.scale < 1) out << " (scaled down to fit)";
  if (!sound) out << " (no part can ring)";
  out << "\n";
}

/// A value the run reports as it goes: --report OBJECT.PROPERTY[.COMPONENT][@SECONDS]
/// (or the scene's world{ report = {...} }), e.g. the motor's axle speed.
struct Report {
  ObjectId id;
  PropertyId property;
  std::string label, unit;
  char component = 0;  // 0, or x y z w (vec3, quat), or 'a' (a quat's play-area angle)
  double every = 1, next = 0;
};

Report parse_report(const World& world, const std::string& spec) {
  const auto bad = [&](const std::string& why) {
    return InputError("report '" + spec + "': " + why);
  };
  std::string rest = spec;
  Report r;
  if (auto at = rest.rfind('@'); at != std::string::npos) {
    try {
      r.every = std::stod(rest.substr(at + 1));
    } catch (const std::logic_error&) {
      throw bad("the interval after '@' must be a number of seconds");
    }
    if (!(r.every > 0)) throw bad("the interval after '@' must be positive");
    rest.resize(at);
  }
  const auto dot = rest.find('.');
  if (dot == std::string::npos) throw bad("expected OBJECT.PROPERTY[.COMPONENT][@SECONDS]");
  const std::string object = rest.substr(0, dot);
  std::string property = rest.substr(dot + 1), component;
  if (auto d2 = property.find('.'); d2 != std::string::npos)
    component = property.substr(d2 + 1), property.resize(d2);
  r.id = world.find(object);
  if (!r.id) throw bad("no object is called '" + object + "'");
  r.property = world.properties().id(property);
  const PropertyDef& def = world.properties().def(r.property);
  if (def.kind == PropertyKind::Vec3 || def.kind == PropertyKind::Quat) {
    const bool quat = def.kind == PropertyKind::Quat;
    if (component == "angle" && quat)
      r.component = 'a';
    else if (component.size() == 1 &&
             std::string(quat ? "wxyz" : "xyz").find(component[0]) != std::string::npos)
      r.component = component[0];
    else
      throw bad("name a component: " + std::string(quat ? "w, x, y, z or angle" : "x, y or z"));
  } else if (def.kind != PropertyKind::Number && def.kind != PropertyKind::Integer &&
             def.kind != PropertyKind::Bool) {
    throw bad("only numbers, booleans and vector components can be reported");
  } else if (!component.empty()) {
    throw bad("'" + property + "' has no components");
  }
  r.label = object + " " + property + (component.empty() ? "" : "." + component);
  r.unit = r.component == 'a' ? "rad" : def.unit;
  return r;
}

void print_report(const World& world, const Report& r, std::ostream& out) {
  if (!world.store().alive(r.id) || !world.store().has(r.id, r.property))
    return;  // removed meanwhile
  const PropertyValue v = world.store().get(r.id, r.property);
  double x = 0;
  if (const double* d = std::get_if<double>(&v))
    x = *d;
  else if (const std::int64_t* i = std::get_if<std::int64_t>(&v))
    x = double(*i);
  else if (const bool* b = std::get_if<bool>(&v))
    x = *b;
  else if (const Vec3* p = std::get_if<Vec3>(&v))
    x = r.component == 'x' ? p->x : r.component == 'y' ? p->y : p->z;
  else if (const Quat* q = std::get_if<Quat>(&v))
    x = r.component == 'a'   ? angle_z(*q)
        : r.component == 'w' ? q->w
        : r.component == 'x' ? q->x
        : r.component == 'y' ? q->y
                             : q->z;
  char line[200];
  std::snprintf(line, sizeof line, "step %6llu  t=%7.3f s  report: %s = %.4g %s\n",
                (unsigned long long)world.step_count(), world.time(), r.label.c_str(), x,
                r.unit.c_str());
  out << line;
}

/// --swap [AREA:]FROM=TO[@TIME]: a resolver swap at TIME (default 0, before the first step).
void schedule_swap(World& world, const std::string& spec) {
  const auto bad = [&] {
    return InputError(
        "--swap '" + spec +
        "': expected [AREA:]FROM=TO[@TIME], e.g. orbit:gravity.nbody=gravity.uniform@2.5");
  };
  std::string rest = spec, area;
  double time = 0;
  if (auto at = rest.rfind('@'); at != std::string::npos) {
    try {
      std::size_t used = 0;
      time = std::stod(rest.substr(at + 1), &used);
      if (used != rest.size() - at - 1) throw bad();
    } catch (const std::logic_error&) {
      throw bad();
    }
    rest.resize(at);
  }
  if (auto colon = rest.find(':'); colon != std::string::npos) {
    area = rest.substr(0, colon);
    rest = rest.substr(colon + 1);
  }
  const auto eq = rest.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == rest.size()) throw bad();
  world.schedule_swap(time, area, rest.substr(0, eq), rest.substr(eq + 1));
}

/// --hash: one line a user compares between two runs (runtime/state_hash.hpp).
void print_hash(const World& world, std::ostream& out) {
  out << "state hash at step " << world.step_count() << ": " << hex(hash_state(world).world)
      << "\n";
}

/// A save file read back, with the scene it names loaded and the world put
/// in the saved state (InputError for a save that does not fit it).
struct Continued {
  SaveData save;
  std::string scene_path;
};
Continued load_save_into(const std::string& file, lua::LoadedScene& scene, PluginRegistry& registry,
                         const lua::LoadOptions& load, std::ostream& err, bool restore = true) {
  Continued c{read_save_file(file), {}};
  c.scene_path = c.save.meta.scene;
  std::error_code ec;
  if (!std::filesystem::exists(c.scene_path, ec))
    throw InputError(file + ": the save's scene '" + c.scene_path + "' is not found");
  try {
    scene = lua::load_scene(c.scene_path, registry, load);
  } catch (const InputError& e) {
    throw InputError(file + ": its scene does not load: " + e.what());
  }
  std::vector<std::string> notes;
  check_save_fits(c.save, file, *scene.world, scene_mods(scene, load, c.scene_path), &notes);
  for (const auto& n : notes) err << "note: " << file << ": " << n << "\n";
  if (restore) {
    try {
      scene.world->restore(c.save.snapshot);
    } catch (const InputError& e) {
      throw InputError(file + ": " + e.what());
    }
  }
  return c;
}

/// --save-every T DIR: the file of the save at the world's step.
std::string periodic_save_path(const std::string& dir, const World& world) {
  char name[64];
  std::snprintf(name, sizeof name, "step-%08llu.alloysave", (unsigned long long)world.step_count());
  return (std::filesystem::path(dir) / name).string();
}

int run(const RunOptions& opt, std::ostream& out, std::ostream& err) {
  PluginRegistry registry;
  register_native_plugins(registry);
  Narrator narrator(out);
  ModLog mod_log(opt.quiet ? nullptr : &narrator, err);
  lua::LoadOptions load = load_options();
  load.mod_log = [&](const std::string& mod, const std::string& line) { mod_log.write(mod, line); };
  // `alloy run FILE` of a save: the scene it names, rebuilt, then restored.
  const bool continuing = is_save_file(opt.scene);
  lua::LoadedScene scene;
  std::string scene_path = opt.scene;
  if (continuing) {
    if (opt.dt) throw InputError("--dt: a saved world keeps the time step it was saved with");
    Continued c = load_save_into(opt.scene, scene, registry, load, err);
    if (c.save.meta.kind != "save")
      throw InputError(opt.scene + ": is a recording: replay it with `alloy replay`");
    scene_path = c.scene_path;
  } else {
    scene = lua::load_scene(opt.scene, registry, load);
  }
  World& world = *scene.world;
  warn_if_empty(world, opt.scene, err);
  if (opt.dt) world.set_dt(*opt.dt);
  world.set_timing(opt.profile);
  double save_period = 0;
  if (!opt.save_every.empty()) {
    try {
      std::size_t used = 0;
      save_period = std::stod(opt.save_every[0], &used);
      if (used != opt.save_every[0].size()) throw std::invalid_argument("");
    } catch (const std::logic_error&) {
      save_period = 0;
    }
    if (!(save_period > 0) || !std::isfinite(save_period))
      throw InputError("--save-every '" + opt.save_every[0] +
                       "': T must be a positive number of seconds");
    std::error_code ec;
    if (!std::filesystem::is_directory(opt.save_every[1], ec))
      throw InputError("--save-every: no folder '" + opt.save_every[1] + "'");
  }
  for (const std::string& path : {opt.save, opt.record}) {
    if (path.empty()) continue;
    const auto dir = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
      throw InputError("cannot write '" + path + "': no folder '" + dir.string() + "'");
    if (std::filesystem::is_directory(path, ec))
      throw InputError("cannot write '" + path + "': it is a folder");
  }

  std::uint64_t steps;
  if (opt.steps) {
    steps = *opt.steps;
  } else {
    const double seconds = opt.seconds         ? *opt.seconds
                           : scene.seconds > 0 ? scene.seconds
                                               : kDefaultSeconds;
    steps = std::uint64_t(std::llround(seconds / world.dt()));
  }

  // --watch: real time, mods reloaded as their files change; without a
  // length, until Ctrl-C.
  if (opt.watch && !opt.steps && !opt.seconds) steps = std::numeric_limits<std::uint64_t>::max();
  std::optional<lua::WatchLoop> watch;
  if (opt.watch) watch.emplace(scene.mods.get(), out);

  for (const std::string& spec : opt.swaps) schedule_swap(world, spec);
  std::vector<Report> reports;
  std::vector<std::string> specs = scene.report;
  specs.insert(specs.end(), opt.reports.begin(), opt.reports.end());
  for (const std::string& spec : specs) reports.push_back(parse_report(world, spec));
  // The first report after the time the world starts at (0, or a save's).
  for (Report& r : reports)
    r.next = (std::floor((world.time() + 0.5 * world.dt()) / r.every) + 1) * r.every;
  // What saves and recordings say of the scene they come from.
  std::optional<SaveMeta> meta;
  if (!opt.save.empty() || !opt.save_every.empty() || !opt.record.empty())
    meta = save_meta(scene, load, scene_path);
  std::unique_ptr<Recorder> recorder;
  // It hears every step and every input from the world itself.
  if (!opt.record.empty()) recorder = std::make_unique<Recorder>(world, *meta);
  auto save_now = [&](const std::string& path) {
    SaveData data;
    data.meta = *meta;
    data.snapshot = world.snapshot();
    write_save_file(path, data);
  };
  double next_save =
      save_period > 0
          ? (std::floor((world.time() + 0.5 * world.dt()) / save_period) + 1) * save_period
          : 0;
  if (!opt.audio.empty()) check_audio_path(opt.audio);
  std::unique_ptr<TraceWriter> trace;
  if (!opt.trace.empty())
    trace = std::make_unique<TraceWriter>(opt.trace, world, split_list(opt.trace_props));
  std::unique_ptr<EventLog> events;
  if (!opt.events.empty()) events = std::make_unique<EventLog>(opt.events);
  EventOwners owners(scene.mods.get());
  world.add_observer([&](const Event& e) {
    const std::string& mod = owners.of(e);
    if (events) events->write(world, e, mod);
    if (!opt.quiet) narrator.narrate(world, e, mod);
  });

  if (!opt.quiet) {
    out << "alloy: " << (scene.name.empty() ? opt.scene : scene.name);
    if (!scene.description.empty()) out << " - " << scene.description;
    out << "\n";
  }
  const double wall0 = now_seconds();
  std::string energy_table;
  try {
    world.start();
    narrator.end_step();
    if (!opt.quiet) {
      out << "stages:";
      for (const auto& s : world.active_stages()) out << " " << s;
      out << "\n";
    }
    if (trace) trace->sample(world);
    std::unique_ptr<EnergyLedger> ledger;
    if (opt.energy) ledger = std::make_unique<EnergyLedger>(), ledger->record(world);
    for (std::uint64_t i = 0; i < steps; ++i) {
      world.step();
      if (ledger) ledger->record(world);
      narrator.end_step();
      if (trace && world.step_count() % opt.trace_every == 0) trace->sample(world);
      for (Report& r : reports)
        if (world.time() + 0.5 * world.dt() >= r.next) {
          if (!opt.quiet) print_report(world, r, out);
          r.next += r.every;
        }
      if (opt.hash_every && world.step_count() % opt.hash_every == 0) print_hash(world, out);
      if (save_period > 0 && world.time() + 0.5 * world.dt() >= next_save) {
        save_now(periodic_save_path(opt.save_every[1], world));
        next_save += save_period;
      }
      if (watch && !watch->between_steps(world)) break;
    }
    if (ledger) energy_table = ledger->table();
  } catch (const InputError& e) {
    // A resolver refused an object (or a setting) only once the world ran:
    // point at the scene line that made it.
    throw lua::locate(scene, e);
  }
  const double wall = now_seconds() - wall0;
  if (!opt.save.empty()) save_now(opt.save);
  if (recorder) recorder->write(opt.record);
  if ((opt.hash || opt.hash_every) && !(opt.hash_every && world.step_count() % opt.hash_every == 0))
    print_hash(world, out);
  if (trace) trace->close();
  if (events) events->close(world);
  mod_log.summary();
  if (!opt.quiet) narrator.summary(world, wall);
  if (!opt.audio.empty()) write_audio(world, opt.audio, out, opt.quiet);
  if (opt.profile) print_profile(out, world.profile());
  out << energy_table;
  return kExitOk;
}

/// What the mods print and report while checking: written to standard error
/// when the check ends (whichever way), without the failures the error
/// itself repeats.
class CheckLog {
 public:
  explicit CheckLog(std::ostream& err) : err_(err) {}
  ~CheckLog() {
    for (const auto& [mod, line] : lines_)
      if (!said_.contains(line)) err_ << "[" << mod << "] " << line << "\n";
  }
  void write(const std::string& mod, const std::string& line) {
    if (bytes_ > (8u << 20)) return;  // a mod's print budget bounds this long before
    bytes_ += line.size();
    lines_.emplace_back(mod, line);
  }
  /// The stages disabled and mods stopped while checking, one a line ("" if none).
  std::string failures(lua::ModRuntime* mods) {
    std::string text;
    if (mods)
      for (const auto& r : mods->poll())
        if (r.kind == lua::ModReport::Kind::StageDisabled ||
            r.kind == lua::ModReport::Kind::Stopped) {
          text += (text.empty() ? "" : "\n") + r.message;
          said_.insert(r.message);
        }
    return text;
  }

 private:
  std::ostream& err_;
  std::vector<std::pair<std::string, std::string>> lines_;
  std::set<std::string> said_;
  std::uint64_t bytes_ = 0;
};

/// `alloy check MOD` of a mod that has only a runtime (no scene, no main
/// file): its runtime loads (on_load included) and its declarations are
/// checked against the native plugins, as a scene using it would load it.
int check_runtime(const std::filesystem::path& folder, const lua::LoadOptions& options,
                  CheckLog& log, std::ostream& out) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::ModRuntime mods(registry, {options.mod_paths, options.mod_budget, options.mod_log});
  mods.load_folder(folder);
  {
    World world(registry);
    mods.attach(world);
    world.start();
    if (std::string f = log.failures(&mods); !f.empty()) throw InputError(f);
  }
  const std::string name =
      mods.loaded().empty() ? folder.filename().string() : mods.loaded().back();
  const auto count = [](std::size_t n, const char* what) {
    return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  out << folder.string() << ": ok (mod '" << name
      << "' has a runtime and no scene: " << count(mods.plugins_of(name).size(), "stage") << ", "
      << count(mods.handlers_of(name), "event handler") << ")\n";
  return kExitOk;
}

/// `alloy check FILE` of a save or a recording: the file reads back whole
/// (checksum, every section), its scene loads, its mods and property types
/// fit, and the world restores from it. Nothing is written.
int check_save(const std::string& path, std::ostream& out, std::ostream& err) {
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadOptions options = load_options();
  CheckLog log(err);
  options.mod_log = [&](const std::string& mod, const std::string& line) { log.write(mod, line); };
  lua::LoadedScene scene;
  const Continued c = load_save_into(path, scene, registry, options, err);
  const Snapshot& s = c.save.snapshot;
  std::size_t alive = 0;
  for (auto a : s.objects.alive) alive += a != 0;
  char line[200];
  std::snprintf(line, sizeof line, ": ok (%s of '%s' at step %llu, t = %.6g s, %zu objects",
                c.save.meta.kind.c_str(), c.save.meta.scene_name.c_str(),
                (unsigned long long)s.step, s.time, alive);
  out << path << line;
  if (c.save.meta.kind == "replay")
    out << ", " << c.save.hashes.size() << " recorded steps, " << c.save.inputs.size() << " inputs";
  out << ", format " << kSaveFormat << ")\n";
  return kExitOk;
}

/// `alloy replay FILE`: runs a recording again headless; exit 0 if every
/// step's hash is the recorded one, 1 if not (the message names where).
int replay_file(const std::string& path, std::ostream& out, std::ostream& err) {
  SaveData data = read_save_file(path);
  if (data.meta.kind != "replay")
    throw InputError(path + ": is a save, not a recording: continue it with `alloy run " + path +
                     "`");
  lua::LoadOptions options = load_options();
  options.mod_log = [&](const std::string& mod, const std::string& line) {
    err << "[" << mod << "] " << line << "\n";
  };
  std::error_code ec;
  if (!std::filesystem::exists(data.meta.scene, ec))
    throw InputError(path + ": the recording's scene '" + data.meta.scene + "' is not found");
  // One world at a time; the world goes before its mods and its registry.
  std::optional<lua::LoadedScene> scene;
  std::unique_ptr<PluginRegistry> registry;
  auto rebuild = [&]() -> World& {
    scene.reset();
    registry = std::make_unique<PluginRegistry>();
    register_native_plugins(*registry);
    scene.emplace(lua::load_scene(data.meta.scene, *registry, options));
    std::vector<std::string> notes;
    check_save_fits(data, path, *scene->world, scene_mods(*scene, options, data.meta.scene),
                    &notes);
    for (const auto& n : notes) err << "note: " << path << ": " << n << "\n";
    return *scene->world;
  };
  ReplayOptions ro;
  ro.reload = [&](World&, const std::string& mod) {
    if (!scene->mods || !scene->mods->has(mod))
      throw InputError(path + ": the recording reloads mod '" + mod + "', which is not loaded");
    scene->mods->reload(mod);
  };
  const double wall0 = now_seconds();
  ReplayResult r;
  try {
    r = replay(data, rebuild, ro);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  const double wall = now_seconds() - wall0;
  out << path << ": " << r.message() << "\n";
  char line[160];
  std::snprintf(line, sizeof line, "replayed %llu steps in %.3f s\n",
                (unsigned long long)(r.identical ? r.steps : r.steps + 1), wall);
  out << line;
  scene.reset();
  return r.identical ? kExitOk : kExitFailure;
}

int check(const std::string& path, std::ostream& out, std::ostream& err) {
  if (is_save_file(path)) return check_save(path, out, err);
  lua::LoadOptions options = load_options();
  CheckLog log(err);
  options.mod_log = [&](const std::string& mod, const std::string& line) { log.write(mod, line); };
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    lua::LuaHost reader;
    const lua::Manifest m = lua::read_manifest(reader, path);
    if (m.scene.empty()) {
      if (!m.runtime.empty() && !std::filesystem::exists(m.folder / m.main, ec))
        return check_runtime(path, options, log, out);
      // A library mod (the kit): its main file runs as a scene would use it.
      PluginRegistry registry;
      register_native_plugins(registry);
      lua::check(path, registry, options);
      out << path << ": ok\n";
      return kExitOk;
    }
  }
  PluginRegistry registry;
  register_native_plugins(registry);
  lua::LoadedScene scene = lua::load_scene(path, registry, options);
  // A part that the world refuses while it starts (a value out of the
  // engine's bounds, a non-finite one, an engine error) is frozen and the
  // world would go on without it; a check says so and fails.
  std::string refused;
  scene.world->add_observer([&](const Event& e) {
    if (e.type == "non_finite" || e.type == "out_of_bounds")
      refused += (refused.empty() ? "" : "\n") + frozen_message(*scene.world, e);
    else if (e.type == "engine_error")
      refused += (refused.empty() ? "" : "\n") + e.source + ": " + e.text;
  });
  try {
    scene.world->start();  // the plugins the scene needs are created and check their settings
  } catch (const InputError& e) {
    throw lua::locate(scene, e);
  }
  // A Lua stage that fails while the world starts (building, priming) is
  // disabled and the world would go on; a check says so and fails.
  if (std::string f = log.failures(scene.mods.get()); !f.empty()) throw InputError(f);
  if (!refused.empty()) throw InputError(path + ": " + refused);
  warn_if_empty(*scene.world, path, err);
  out << path << ": ok\n";
  return kExitOk;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// Everything `alloy plugins` says of one plugin, from its definition and
/// the property registry (a property's owner is the plugin that defined it
/// first).
nlohmann::json plugin_json(const PluginRegistry& registry, const PluginDef& d) {
  const auto& props = registry.properties();
  nlohmann::json j;
  j["name"] = d.info.name;
  j["kind"] = std::string(to_string(d.info.kind));
  j["origin"] = d.info.owner.empty() ? "native" : "mod";
  if (!d.info.owner.empty()) j["mod"] = d.info.owner;
  j["doc"] = d.info.doc;
  nlohmann::json owns = nlohmann::json::array();
  // A mod owns its properties as a whole: a mod's stage is listed as owning
  // those of them it writes, and the mod's first stage those that none of its
  // stages writes (a mod's inputs: magic's `rune`), so that every property
  // appears once with its kind, unit and doc.
  auto writes = [](const PluginDef& x, const std::string& name) {
    return std::find(x.info.writes.begin(), x.info.writes.end(), name) != x.info.writes.end();
  };
  const PluginDef* first_of_mod = nullptr;
  std::vector<const PluginDef*> mod_stages;
  if (!d.info.owner.empty())
    for (const auto& n : registry.order())
      if (const PluginDef* x = registry.find(n); x && x->info.owner == d.info.owner) {
        if (!first_of_mod) first_of_mod = x;
        mod_stages.push_back(x);
      }
  for (const auto& name : props.names()) {
    const PropertyDef& p = props.def(props.id(name));
    bool mine = p.owner == d.info.name;
    if (!mine && p.owner_is_mod && !d.info.owner.empty() && p.owner == d.info.owner)
      mine = writes(d, p.name) ||
             (first_of_mod == &d &&
              std::none_of(mod_stages.begin(), mod_stages.end(),
                           [&](const PluginDef* x) { return writes(*x, p.name); }));
    if (!mine) continue;
    nlohmann::json pj{{"name", p.name}, {"kind", std::string(to_string(p.kind))}};
    if (!p.unit.empty()) pj["unit"] = p.unit;
    if (!p.doc.empty()) pj["doc"] = p.doc;
    if (!p.enum_values.empty()) pj["values"] = p.enum_values;
    owns.push_back(std::move(pj));
  }
  j["owns"] = std::move(owns);
  j["reads"] = d.info.reads;
  j["writes"] = d.info.writes;
  j["needs"] = d.info.needs;
  j["derived"] = d.info.derived;
  j["resolvers"] = d.info.resolvers;
  j["target"] = d.info.target;
  j["provides"] = d.info.provides;
  j["contacts"] = d.contacts;
  nlohmann::json fns = nlohmann::json::array();
  for (const auto& f : d.functions) {
    nlohmann::json args = nlohmann::json::array();
    for (ArgKind a : f.decl.args) args.push_back(std::string(to_string(a)));
    nlohmann::json fj{{"name", f.decl.name}, {"args", std::move(args)}};
    if (!f.doc.empty()) fj["doc"] = f.doc;
    if (f.record_kind >= 0) fj["record_kind"] = f.record_kind;
    fns.push_back(std::move(fj));
  }
  j["functions"] = std::move(fns);
  return j;
}

/// The reference table of docs/modding.md: every native property a mod can
/// read, from the registry (one row each, sorted by name). A test compares
/// the doc with it; `alloy plugins --doc-table` prints it.
std::string native_property_table(const PluginRegistry& registry) {
  const auto& props = registry.properties();
  std::ostringstream t;
  t << "| property | kind | unit | owner | meaning |\n";
  t << "|---|---|---|---|---|\n";
  for (const auto& name : props.names()) {
    const PropertyDef& p = props.def(props.id(name));
    if (p.owner_is_mod) continue;
    std::string kind(to_string(p.kind));
    if (!p.enum_values.empty()) kind += ": " + joined(p.enum_values);
    std::string doc;  // a '|' in a doc ("|current|") would end the cell
    for (char c : p.doc) doc += c == '|' ? std::string("\\|") : std::string(1, c);
    t << "| `" << p.name << "` | " << kind << " | " << p.unit << " | " << p.owner << " | " << doc
      << " |\n";
  }
  return t.str();
}

/// A mod's text made safe for a terminal: control characters (C0, DEL and
/// the UTF-8 encoded C1 range, which some terminals obey as escape
/// sequences) are printed as \n, \t, \r or \xHH,
/// so that a mod can neither forge lines of the listing nor move the
/// cursor, clear the screen or retitle the window (docs/security.md).
std::string printable(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  auto hex = [&](unsigned char c) {
    static constexpr char kDigits[] = "0123456789abcdef";
    out += "\\x";
    out += kDigits[c >> 4];
    out += kDigits[c & 15];
  };
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c < 0x20 || c == 0x7f) {
      hex(c);
    } else if (c == 0xc2 && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) >= 0x80 &&
               static_cast<unsigned char>(s[i + 1]) <= 0x9f) {
      hex(c), hex(static_cast<unsigned char>(s[++i]));  // U+0080..U+009F: C1 controls
    } else {
      out += char(c);
    }
  }
  return out;
}

/// `alloy plugins [PATH] [--json]`: every registered plugin, native and
/// from mods. PATH (a scene or a mod folder) is loaded as `alloy run` and
/// `alloy check` load it, so that its mods' plugins and properties are
/// registered too.
int list_plugins(const std::string& path, bool json, bool doc_table, std::ostream& out,
                 std::ostream& err) {
  PluginRegistry registry;
  register_native_plugins(registry);
  if (doc_table) {
    if (!path.empty()) throw InputError("--doc-table lists the native properties only: no PATH");
    out << native_property_table(registry);
    return kExitOk;
  }
  lua::LoadOptions options = load_options();
  options.mod_log = [&](const std::string& mod, const std::string& line) {
    err << "[" << mod << "] " << line << "\n";
  };
  // Declared before the scene, which must go first.
  std::unique_ptr<lua::ModRuntime> runtime_only;
  std::optional<lua::LoadedScene> scene;
  std::error_code ec;
  if (!path.empty()) {
    bool runtime = false;
    if (std::filesystem::is_directory(path, ec)) {
      lua::LuaHost reader;
      const lua::Manifest m = lua::read_manifest(reader, path);
      runtime =
          m.scene.empty() && !m.runtime.empty() && !std::filesystem::exists(m.folder / m.main, ec);
    }
    if (runtime) {
      runtime_only = std::make_unique<lua::ModRuntime>(
          registry, lua::ModRuntimeOptions{options.mod_paths, options.mod_budget, options.mod_log});
      runtime_only->load_folder(path);
    } else {
      scene.emplace(lua::load_scene(path, registry, options));
    }
  }
  nlohmann::json all = nlohmann::json::array();
  for (const auto& name : registry.order())
    all.push_back(plugin_json(registry, *registry.find(name)));
  if (json) {
    // Every character outside ASCII as \uXXXX: JSON escapes C0 controls
    // itself, and this keeps the C1 ones (U+009B is a one-character CSI)
    // off a terminal the listing is printed on.
    out << all.dump(2, ' ', true) << "\n";
    return kExitOk;
  }
  // Text output: every string a mod gave is passed through printable().
  auto text = [](const nlohmann::json& j) { return printable(j.get<std::string>()); };
  auto list = [](const nlohmann::json& j) {
    std::vector<std::string> v = j.get<std::vector<std::string>>();
    for (auto& x : v) x = printable(x);
    return v;
  };
  for (const auto& p : all) {
    out << text(p["name"]) << " (" << text(p["kind"]);
    if (p["origin"] == "mod") out << ", mod '" << text(p["mod"]) << "'";
    out << ")";
    if (!p["target"].get<std::string>().empty()) out << " -> " << text(p["target"]);
    if (!p["doc"].get<std::string>().empty()) out << ": " << text(p["doc"]);
    out << "\n";
    std::vector<std::string> owns;
    for (const auto& o : p["owns"]) owns.push_back(text(o["name"]));
    const std::pair<const char*, std::vector<std::string>> lists[] = {
        {"owns", owns},
        {"reads", list(p["reads"])},
        {"writes", list(p["writes"])},
        {"needs", list(p["needs"])},
        {"derived", list(p["derived"])},
        {"resolvers", list(p["resolvers"])}};
    for (const auto& [label, items] : lists)
      if (!items.empty()) out << "  " << label << ": " << joined(items) << "\n";
    if (!p["provides"].get<std::string>().empty())
      out << "  provides: " << text(p["provides"]) << "\n";
    if (p["contacts"].get<bool>()) out << "  a contact set (Lua reads it with w:contacts)\n";
    for (const auto& f : p["functions"]) {
      out << "  function " << text(f["name"]) << "(";
      out << joined(list(f["args"])) << ")";
      if (f.contains("doc")) out << ": " << text(f["doc"]);
      out << "\n";
    }
  }
  return kExitOk;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"alloy: physics simulations that cooperate, scripted by Lua mods"};
  app.require_subcommand(1);

  RunOptions ro;
  CLI::App* run_cmd = app.add_subcommand("run", "Run a scene headless and narrate what happens");
  run_cmd
      ->add_option("scene", ro.scene,
                   "Scene file (.lua), mod folder, or a save file to continue (alloy run --save)")
      ->required();
  auto* steps_opt = run_cmd->add_option("--steps", ro.steps, "Number of steps to run");
  run_cmd->add_option("--seconds", ro.seconds, "Simulated seconds to run")
      ->excludes(steps_opt)
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--dt", ro.dt, "Fixed time step in seconds (overrides the scene)")
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--trace", ro.trace,
                      "Write a long-format CSV trace: step,time,object,property,value");
  run_cmd->add_option("--trace-props", ro.trace_props, "Comma-separated properties to trace")
      ->capture_default_str();
  run_cmd->add_option("--trace-every", ro.trace_every, "Trace every K-th step")
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--events", ro.events, "Write the events as JSON lines");
  run_cmd->add_option("--audio", ro.audio,
                      "Write what the run sounded like as a WAV file (16-bit mono)");
  run_cmd->add_option(
      "--report", ro.reports,
      "Report a value as the run goes: OBJECT.PROPERTY[.COMPONENT][@SECONDS] (repeatable)");
  run_cmd->add_option(
      "--swap", ro.swaps,
      "Swap a resolver for another while running: [AREA:]FROM=TO[@TIME] (repeatable); an "
      "engine brings its own contact set, e.g. rigid_body=rigid_body.box2d@2");
  run_cmd->add_flag("--profile", ro.profile, "Print the time per step of each stage");
  run_cmd->add_flag("--energy", ro.energy,
                    "Keep the energy ledger and print the balance of the run: sources, sinks, "
                    "stored change and the residue as a fraction of the energy moved");
  run_cmd->add_flag("--quiet", ro.quiet, "No narration");
  run_cmd->add_flag("--hash", ro.hash,
                    "Print the state hash after the run (every property bit, ids, pending inputs: "
                    "equal hashes, equal worlds; docs/saves.md)");
  run_cmd
      ->add_option("--hash-every", ro.hash_every,
                   "Print the state hash every N steps, and after the run")
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--save", ro.save,
                      "Save the world at the end of the run (continue it with `alloy run FILE`)");
  run_cmd
      ->add_option("--save-every", ro.save_every,
                   "Save the world every T simulated seconds into folder DIR "
                   "(DIR/step-NNNNNNNN.alloysave)")
      ->expected(2)
      ->type_name("T DIR");
  run_cmd->add_option("--record", ro.record,
                      "Record the run (initial world, inputs, a state hash every step) for "
                      "`alloy replay`");
  run_cmd->add_flag("--watch", ro.watch,
                    "Run in real time and reload mods whose files change (until Ctrl-C without "
                    "--steps/--seconds)");

  std::string check_path;
  CLI::App* check_cmd =
      app.add_subcommand("check", "Load and validate a scene or a mod without running it");
  check_cmd->add_option("path", check_path, "Scene file, mod folder, save file or recording")
      ->required();

  std::string replay_path;
  CLI::App* replay_cmd = app.add_subcommand(
      "replay", "Run a recording (alloy run --record) again and say where it differs, if it does");
  replay_cmd->add_option("file", replay_path, "Recording file")->required();

  std::string plugins_path;
  bool plugins_json = false;
  CLI::App* plugins_cmd = app.add_subcommand(
      "plugins",
      "List every plugin, native and from mods: the properties it owns, reads and writes, its "
      "needs, target, provides and interaction functions");
  plugins_cmd->add_option("path", plugins_path,
                          "A scene or mod folder to load first (as `run` does), so that its "
                          "mods' plugins are listed too");
  plugins_cmd->add_flag("--json", plugins_json, "Print the list as JSON");
  bool plugins_doc = false;
  plugins_cmd->add_flag("--doc-table", plugins_doc,
                        "Print the native properties as docs/modding.md's reference table");

  viewer::ViewerOptions vo;
  CLI::App* view_cmd = viewer::add_view_command(app, vo);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream o, e2;
    const int code = app.exit(e, o, e2);
    out << o.str();
    err << e2.str();
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    if (run_cmd->parsed()) return run(ro, out, err);
    if (check_cmd->parsed()) return check(check_path, out, err);
    if (replay_cmd->parsed()) return replay_file(replay_path, out, err);
    if (plugins_cmd->parsed())
      return list_plugins(plugins_path, plugins_json, plugins_doc, out, err);
    if (view_cmd->parsed()) return viewer::run_view(vo, out, err);
  } catch (const InputError& e) {
    err << "error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    err << "alloy: failure: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitFailure;
}

}  // namespace alloy::app
