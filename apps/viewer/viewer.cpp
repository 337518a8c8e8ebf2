#include "apps/viewer/viewer.hpp"

#include <imgui.h>
#include <imgui_impl_sdl.h>
#include <imgui_impl_sdlrenderer.h>
#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "apps/viewer/engines.hpp"
#include "apps/viewer/scene_writer.hpp"
#include "lua/mod_runtime.hpp"
#include "lua/save_meta.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/sound/sound_resolver.hpp"
#include "runtime/contact_set.hpp"

namespace alloy::viewer {

namespace fs = std::filesystem;

namespace {

constexpr double kHeadlessFrame = 1.0 / 60.0;  // s of simulated time per headless frame
constexpr int kMaxStepsPerFrame = 240;         // beyond this the picture falls behind real time
constexpr double kTurnStep = std::numbers::pi / 12;  // 15 degrees per wheel notch or key
constexpr float kLeftWidth = 232, kRightWidth = 300, kMargin = 8;
constexpr double kToastSeconds = 7;

const char* kFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

std::string value_text(const World& w, PropertyId p, const PropertyValue& v) {
  char buf[160];
  const PropertyDef& def = w.properties().def(p);
  struct V {
    const World& w;
    const PropertyDef& def;
    char* buf;
    std::string operator()(double d) const {
      std::snprintf(buf, 160, "%.6g %s", d, def.unit.c_str());
      return buf;
    }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(Vec3 v) const {
      std::snprintf(buf, 160, "(%.4g, %.4g, %.4g) %s", v.x, v.y, v.z, def.unit.c_str());
      return buf;
    }
    std::string operator()(Quat q) const {
      std::snprintf(buf, 160, "%.2f deg about z", angle_z(q) * 180 / std::numbers::pi);
      return buf;
    }
    std::string operator()(const std::string& s) const { return "\"" + s + "\""; }
    std::string operator()(ObjectId id) const {
      return w.store().alive(id) ? w.describe(id) : "(none)";
    }
    std::string operator()(const RefList& l) const {
      std::string s;
      for (ObjectId id : l) s += (s.empty() ? "" : ", ") + w.describe(id);
      return "{" + s + "}";
    }
    std::string operator()(EnumValue e) const {
      return e.index >= 0 && std::size_t(e.index) < def.enum_values.size()
                 ? def.enum_values[std::size_t(e.index)]
                 : "?";
    }
  };
  return std::visit(V{w, def, buf}, v);
}

const char* material_name(Material m) {
  switch (m) {
    case Material::Steel:
      return "steel";
    case Material::Iron:
      return "iron";
    case Material::Brass:
      return "brass";
    case Material::Bronze:
      return "bronze";
    case Material::Copper:
      return "copper";
    case Material::Wood:
      return "wood";
    case Material::Rubber:
      return "rubber";
    case Material::Other:
      break;
  }
  return "other";
}

ImU32 kind_colour(StageKind k) {
  switch (k) {
    case StageKind::Resolver:
      return IM_COL32(70, 130, 220, 255);
    case StageKind::Derived:
      return IM_COL32(60, 170, 100, 255);
    case StageKind::Interaction:
      return IM_COL32(230, 140, 40, 255);
  }
  return IM_COL32(128, 128, 128, 255);
}

}  // namespace

// --- set-up ---------------------------------------------------------------------

Viewer::Viewer(ViewerOptions options) : opt_(std::move(options)) {
  paused_ = opt_.paused;
  time_scale_ = std::clamp(opt_.time_scale, 1.0 / 64, 64.0);
  init_sdl();
  init_imgui();
  save_path_ = save_path_for(opt_.scene).string();
  if (opt_.scene.empty())
    new_board();
  else
    load();
}

Viewer::~Viewer() {
  recorder_.reset();  // it holds the world
  scene_.reset();
  if (imgui_ready_) {
    ImGui::SetCurrentContext(imgui_);
    ImGui_ImplSDLRenderer_Shutdown();
    ImGui_ImplSDL2_Shutdown();
    ImGui::DestroyContext(imgui_);
  }
  if (renderer_) SDL_DestroyRenderer(renderer_);
  if (window_) SDL_DestroyWindow(window_);
  SDL_QuitSubSystem(SDL_INIT_VIDEO | SDL_INIT_EVENTS);
}

void Viewer::init_sdl() {
  if (opt_.headless) {
    // No display needed: SDL's dummy video driver gives a window whose
    // framebuffer is plain memory, and the software renderer draws into it.
    SDL_SetHint(SDL_HINT_VIDEODRIVER, "dummy");
    SDL_SetHint(SDL_HINT_RENDER_DRIVER, "software");
  }
  // Subsystems are reference-counted: several viewers (tests) may be open at once.
  if (SDL_InitSubSystem(SDL_INIT_VIDEO | SDL_INIT_EVENTS) != 0)
    throw std::runtime_error(std::string("cannot open a window: ") + SDL_GetError() +
                             " (without a display, use --headless or --screenshot)");
  // Without a display SDL does not fail: it falls back to its "offscreen"
  // driver (EGL into memory), and the viewer would draw 60 frames a second
  // into a window no one sees. Session 19's "no window in 45 s" under Xvfb
  // was this: the X server was resetting (its last client had just left)
  // when the viewer connected.
  const std::string driver = SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : "";
  if (!opt_.headless && (driver == "offscreen" || driver == "dummy") &&
      !std::getenv("SDL_VIDEODRIVER")) {
    const char* display = std::getenv("DISPLAY");
    SDL_QuitSubSystem(SDL_INIT_VIDEO | SDL_INIT_EVENTS);
    throw std::runtime_error(std::string("cannot open a window: no display answered (DISPLAY=") +
                             (display ? display : "not set") + "; SDL fell back to its " + driver +
                             " driver, whose window nobody sees); use --headless or --screenshot");
  }
  // Hidden until the panels stand still (Viewer::frame): a click on the
  // window then lands where the panels are drawn.
  const Uint32 flags = SDL_WINDOW_RESIZABLE | SDL_WINDOW_HIDDEN;
  window_ = SDL_CreateWindow("alloy view", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED,
                             opt_.width, opt_.height, flags);
  if (!window_) throw std::runtime_error(std::string("cannot open a window: ") + SDL_GetError());
  if (!opt_.headless)
    renderer_ =
        SDL_CreateRenderer(window_, -1, SDL_RENDERER_ACCELERATED | SDL_RENDERER_PRESENTVSYNC);
  if (!renderer_) renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_SOFTWARE);
  if (!renderer_)
    throw std::runtime_error(std::string("cannot draw in the window: ") + SDL_GetError());
  SDL_SetRenderDrawBlendMode(renderer_, SDL_BLENDMODE_BLEND);
  last_ticks_ = SDL_GetPerformanceCounter();
}

void Viewer::init_imgui() {
  IMGUI_CHECKVERSION();
  // A context of its own, made current whenever this viewer draws: several
  // viewers may live in one process (tests).
  imgui_ = ImGui::CreateContext();
  ImGui::SetCurrentContext(imgui_);
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // the layout is fixed: nothing to remember between runs
  io.LogFilename = nullptr;
  std::error_code ec;
  if (fs::exists(kFontPath, ec))
    io.Fonts->AddFontFromFileTTF(kFontPath, 15.0f);
  else
    io.Fonts->AddFontDefault();
  ImGui::StyleColorsLight();
  ImGuiStyle& style = ImGui::GetStyle();
  style.WindowRounding = 6;
  style.FrameRounding = 4;
  style.GrabRounding = 4;
  style.WindowBorderSize = 1;
  style.WindowPadding = {10, 8};
  style.ItemSpacing = {6, 5};
  style.Colors[ImGuiCol_WindowBg] = ImVec4(0.98f, 0.98f, 0.99f, 0.94f);
  style.Colors[ImGuiCol_TitleBgActive] = style.Colors[ImGuiCol_TitleBg] =
      ImVec4(0.86f, 0.88f, 0.92f, 1);
  ImGui_ImplSDL2_InitForSDLRenderer(window_);
  ImGui_ImplSDLRenderer_Init(renderer_);
  imgui_ready_ = true;
}

void Viewer::load() {
  // Each load has a registry of its own: a scene's mods register their
  // plugins in it, and unregister them when the scene goes, which must not
  // touch the plugins of the scene that replaces it.
  auto fresh_registry = std::make_unique<PluginRegistry>();
  register_native_plugins(*fresh_registry);
  std::unique_ptr<lua::LoadedScene> fresh;  // declared after its registry: destroyed first
  many_.clear();
  lua::LoadOptions options = opt_.load;
  options.mod_log = [this](const std::string& mod, const std::string& line) {
    note(mod + ": " + line);
  };
  std::string error;
  try {
    fresh =
        std::make_unique<lua::LoadedScene>(lua::load_scene(opt_.scene, *fresh_registry, options));
    fresh->world->start();  // the plugins it needs are made now and check their settings
  } catch (const InputError& e) {
    error = fresh ? lua::locate(*fresh, e).what() : e.what();
  } catch (const std::exception& e) {
    error = std::string("cannot load the scene: ") + e.what();
  }
  // The modification time of what was loaded, to notice edits on disk.
  std::error_code ec;
  scene_mtime_ = fs::last_write_time(fresh ? fresh->file : opt_.scene, ec);
  if (!error.empty()) {
    load_error_ = error;
    note(error, true);
    if (scene_) note("the world as it was goes on; fix the file and press Reset");
    return;
  }
  load_error_.clear();
  finish_recording();  // a recording is of one world
  editor_.attach(nullptr);
  scene_.reset();  // the old world and its mods go before their registry
  registry_ = std::move(fresh_registry);
  scene_ = std::move(fresh);
  if (scene_->mods) scene_->mods->watch();  // a mod saved on disk is reloaded while the world runs
  World& w = *scene_->world;
  w.set_timing(true);  // the stage panel shows each stage's time
  editor_.attach(&w);
  // A recording follows the user: each world loaded (the first, a New, an
  // Open, a Reset) is recorded from its own first snapshot, to FILE, then
  // FILE-2.EXT, FILE-3.EXT, ...; each part replays on its own.
  if (!opt_.record.empty()) {
    const fs::path first(opt_.record);
    const std::string path =
        ++record_part_ == 1
            ? opt_.record
            : (first.parent_path() / (first.stem().string() + "-" + std::to_string(record_part_) +
                                      first.extension().string()))
                  .string();
    recorder_ =
        std::make_unique<Recorder>(w, lua::save_meta(*scene_, opt_.load, opt_.scene.string()));
    record_path_ = path;
    if (record_part_ > 1) note("recording " + scene_->name + " to " + path);
  }
  selected_ = hovered_ = wire_start_ = {};
  event_counts_.clear();
  event_log_.clear();
  rings_.clear();
  bars_.clear();
  profile_steps_seen_ = 0;
  accumulator_ = 0;
  failing_steps_ = 0;
  w.add_observer([this](const Event& e) {
    auto it = std::find_if(event_counts_.begin(), event_counts_.end(),
                           [&](auto& p) { return p.first == e.type; });
    if (it == event_counts_.end())
      event_counts_.push_back({e.type, 1});
    else
      ++it->second;
    World* wp = world();
    if (!wp) return;
    if (e.type == "sound") {
      rings_.push_back({e.a, clock_, std::clamp(e.value("amplitude", 0.6) * 2, 0.35, 1.0)});
    }
    if (e.type == "contact_began" || e.type == "contact_ended") return;  // too many to list
    char head[48];
    std::snprintf(head, sizeof head, "%7.3f s  ", e.time);
    std::string line = head + e.type;
    if (wp->store().alive(e.a)) line += " " + wp->describe(e.a);
    if (wp->store().alive(e.b)) line += ", " + wp->describe(e.b);
    event_log_.push_back(line);
    if (event_log_.size() > 8) event_log_.pop_front();
  });
  SDL_SetWindowTitle(window_, ("alloy view - " + scene_->name).c_str());
}

void Viewer::reset() {
  // Undoable: the world as it was is recorded, and a snapshot restores into
  // the world the same file builds again.
  if (World* w = world()) history_.record(*w, "reset");
  editor_.attach(world());
  const bool had = scene_ != nullptr;
  load();
  if (had && !load_error_.empty())
    history_.forget_last();
  else if (had)
    note("reset to the file: Ctrl+Z brings the edits back");
}

// --- files and history -------------------------------------------------------------

namespace {

// The empty board: a floor 1 m wide, at the kit's scale (a battery is a
// tenth of it), under uniform gravity.
constexpr const char* kNewBoard = R"(-- A new board (alloy view: New).
local kit = require "kit"

world {
  name = "new board",
  dt = 1 / 240,
  seconds = 10,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } },
}

kit.floor { name = "floor", at = { 0, -0.01 }, size = { 1.0, 0.02 } }
)";

}  // namespace

bool Viewer::written_by_viewer(const fs::path& file) {
  std::ifstream in(file);
  std::string first;
  return in && std::getline(in, first) && first.rfind(kSavedHeader, 0) == 0;
}

fs::path Viewer::save_path_for(const fs::path& scene) {
  if (scene.empty()) return "scene_saved.lua";
  // A folder named with a trailing slash has an empty file name: its own name.
  const fs::path whole = scene.has_filename() ? scene : scene.parent_path();
  std::error_code ec;
  if (whole.extension() == ".lua" && !fs::is_directory(whole, ec) && written_by_viewer(whole))
    return whole;
  const std::string name =
      (whole.extension() == ".lua" ? whole.stem() : whole.filename()).string() + "_saved.lua";
  return whole.has_parent_path() ? whole.parent_path() / name : fs::path(name);
}

void Viewer::new_board() {
  const fs::path dir = fs::temp_directory_path() / ("alloy_view_" + std::to_string(::getpid()));
  std::error_code ec;
  fs::create_directories(dir, ec);
  const fs::path file = dir / "new_board.lua";
  try {
    write_file_whole(file, kNewBoard);
  } catch (const std::exception& e) {
    note(std::string("cannot make a new board: ") + e.what(), true);
    return;
  }
  const fs::path before = opt_.scene;
  opt_.scene = file;
  load();
  if (!load_error_.empty()) {
    opt_.scene = before;
    return;
  }
  history_.clear();
  untitled_ = true;
  save_path_ = "untitled.lua";
  fitted_ = false;
  note("a new board: drop parts from the palette, join them with Hinge, Glue or String");
}

bool Viewer::open(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    note("cannot open '" + path.string() + "': no such file or folder", true);
    return false;
  }
  const fs::path before = opt_.scene;
  const bool had = scene_ != nullptr;
  opt_.scene = path;
  load();
  if (!load_error_.empty() && had) {
    // The world as it was goes on; the file stays the one it came from.
    opt_.scene = before;
    return false;
  }
  history_.clear();
  untitled_ = false;
  save_path_ = save_path_for(path).string();
  fitted_ = false;
  if (load_error_.empty()) note("opened " + path.string());
  return load_error_.empty();
}

bool Viewer::undo() {
  World* w = world();
  if (!w) return false;
  if (editor_.carrying()) (void)editor_.drop();
  const std::string what = history_.undo_what();
  try {
    if (!history_.undo(*w)) {
      note("nothing to undo");
      return false;
    }
  } catch (const std::exception& e) {
    note(std::string("cannot undo: ") + e.what(), true);
    return false;
  }
  editor_.attach(w);
  many_.clear();  // its ids may be gone or another's now
  note("undone: " + what);
  return true;
}

bool Viewer::redo() {
  World* w = world();
  if (!w) return false;
  if (editor_.carrying()) (void)editor_.drop();
  const std::string what = history_.redo_what();
  try {
    if (!history_.redo(*w)) {
      note("nothing to redo");
      return false;
    }
  } catch (const std::exception& e) {
    note(std::string("cannot redo: ") + e.what(), true);
    return false;
  }
  editor_.attach(w);
  many_.clear();
  note("redone: " + what);
  return true;
}

void Viewer::set_tool(Tool t) {
  tool_ = t;
  wire_start_ = {};
  string_started_ = false;
  string_start_ = {};
  if (t != Tool::Place) placing_ = -1;
}

void Viewer::ask(Popup p) {
  popup_ = p;
  popup_fresh_ = true;
  const std::string init = p == Popup::SaveAs ? save_path_ : p == Popup::Open ? "" : "";
  std::snprintf(path_buf_, sizeof path_buf_, "%s", init.c_str());
}

void Viewer::popup_enter() {
  // Enter in a popup: what its first button does.
  switch (popup_) {
    case Popup::Open: {
      const std::string path = path_buf_;
      if (path.empty()) return;
      if (history_.dirty()) {
        pending_open_ = path;
        ask(Popup::ConfirmOpen);
        return;
      }
      popup_ = Popup::None;
      open(path);
      return;
    }
    case Popup::SaveAs: {
      const std::string path = path_buf_;
      if (path.empty()) return;
      std::error_code ec;
      // Another file that is there already is replaced only when the player
      // says so (the board's own file is what Save writes anyway).
      if (fs::exists(path, ec) && !fs::equivalent(path, save_path_, ec)) {
        pending_save_ = path;
        ask(Popup::ConfirmOverwrite);
        return;
      }
      popup_ = Popup::None;
      save(path);
      return;
    }
    case Popup::ConfirmOverwrite:
      popup_ = Popup::None;
      save(pending_save_);
      return;
    case Popup::ConfirmNew:
      popup_ = Popup::None;
      new_board();
      return;
    case Popup::ConfirmOpen:
      popup_ = Popup::None;
      open(pending_open_);
      return;
    case Popup::None:
      return;
  }
}

std::optional<Vec2> Viewer::resize_handle() const {
  if (tool_ != Tool::Hand || !selected_) return std::nullopt;
  const World* w = scene_ ? scene_->world.get() : nullptr;
  if (!w || !w->store().alive(selected_)) return std::nullopt;
  const auto p = read_part(*w, selected_);
  if (!p) return std::nullopt;
  switch (p->shape) {
    case Shape2D::Box:
      return p->to_world(p->half);
    case Shape2D::Disk:
      return p->to_world({p->radius, 0});
    case Shape2D::Capsule:
      return p->to_world({p->half_length + p->radius, p->radius});
  }
  return std::nullopt;
}

void Viewer::on_drag(Vec2 at) {
  World* w = world();
  if (!w || !resizing_ || !w->store().alive(resizing_)) return;
  const auto p = read_part(*w, resizing_);
  if (!p) return;
  // The handle is a corner (or the rim): the part grows about its centre so
  // that the handle stays under the mouse.
  const Vec2 local = p->to_local(at);
  Vec2 size{2 * std::abs(local.x), 2 * std::abs(local.y)};
  if (p->shape == Shape2D::Disk) size = {2 * length(local), 2 * length(local)};
  size = {std::max(size.x, 0.004), std::max(size.y, 0.004)};
  if (p->shape == Shape2D::Capsule) size.x = std::max(size.x, size.y);
  const EditResult r = editor_.resize(resizing_, size);
  if (!r.ok) note(r.message, true);
}

void Viewer::on_draw(Vec2 at) {
  World* w = world();
  if (!w || !drawing_ || !w->store().alive(drawing_)) return;
  const Vec2 d = at - draw_from_;
  const double reach = length(d);
  // A click (or a hand's tremor) keeps the palette's size.
  if (!drawn_ && reach * camera_.scale < 6) return;
  drawn_ = true;
  const auto p = read_part(*w, drawing_);
  if (!p) return;
  EditResult r;
  if (p->shape == Shape2D::Disk) {
    // About its centre (a pinned wheel keeps its pin).
    const double radius = std::max(reach, 0.002);
    r = editor_.resize(drawing_, {2 * radius, 2 * radius});
  } else {
    // A bar from the press to the mouse: its length and direction; its
    // thickness stays the palette's.
    const double thick = p->shape == Shape2D::Capsule ? 2 * p->radius : 2 * p->half.y;
    r = editor_.resize(drawing_, {std::max(reach, std::max(thick, 0.004)), thick});
    const Vec2 mid = draw_from_ + d * 0.5;
    const double z = w->value<Vec3>(drawing_, "position").value_or(Vec3{}).z;
    if (r.ok) r = editor_.set_property(drawing_, "position", Vec3{mid.x, mid.y, z});
    if (r.ok && reach > 0)
      r = editor_.set_property(drawing_, "orientation", Quat::from_angle_z(std::atan2(d.y, d.x)));
  }
  if (!r.ok) note(r.message, true);
}

void Viewer::note(const std::string& message, bool error) {
  if (message.empty()) return;
  log_.push_back(message);
  toasts_.push_back({message, clock_, error});
  if (toasts_.size() > 5) toasts_.pop_front();
}

std::size_t Viewer::event_count(const std::string& type) const {
  for (const auto& [t, n] : event_counts_)
    if (t == type) return n;
  return 0;
}

bool Viewer::finish_recording() {
  if (!recorder_) return true;
  const std::unique_ptr<Recorder> r = std::move(recorder_);
  try {
    r->write(record_path_);
    note("recorded " + std::to_string(r->steps()) + " steps to " + record_path_);
    return true;
  } catch (const std::exception& e) {
    note(std::string("the recording was not written: ") + e.what(), true);
    return false;
  }
}

void Viewer::set_time_scale(double s) {
  time_scale_ = std::clamp(s, 1.0 / 64, 64.0);
}

// --- the loop --------------------------------------------------------------------

int Viewer::run(std::ostream& out, std::ostream& err) {
  if (!opt_.script.empty()) add_script(read_script(opt_.script));  // InputError: exit 2
  std::size_t printed = 0;
  auto flush_messages = [&] {
    for (; printed < log_.size(); ++printed) out << "view: " << log_[printed] << "\n";
  };
  while (frame()) {
    if (opt_.headless) flush_messages();
    if (opt_.frames > 0 && frames_ >= std::uint64_t(opt_.frames)) break;
  }
  int code = 0;
  if (!opt_.screenshot.empty()) {
    try {
      write_png(opt_.screenshot, render_image());
      out << "view: screenshot " << opt_.screenshot << " after " << frames_ << " frames\n";
    } catch (const std::exception& e) {
      err << "error: " << e.what() << "\n";
      code = 1;
    }
  }
  if (!opt_.save.empty() && !save(opt_.save)) code = 1;
  if (!finish_recording()) code = 1;
  flush_messages();
  if (!load_error_.empty()) {
    err << "error: " << load_error_ << "\n";
    if (code == 0) code = 2;
  }
  return code;
}

bool Viewer::frame() {
  if (quit_) return false;
  ImGui::SetCurrentContext(imgui_);
  pump_script();
  SDL_Event e;
  // Paused and idle (nothing held, no script, no ring fading), a window
  // waits for input instead of drawing the same picture 60 times a second:
  // a quarter of a second at most while a message fades, else a second (the
  // scene file is still watched for changes). Measured under Xvfb on the
  // doorbell (tests/viewer/idle_cpu.sh): 6.2 % of a core with 250 ms waits.
  // The event is left in the queue: the loop below decides what this frame
  // takes. Not while the panels owe a click its release: that frame is due.
  if (!opt_.headless && paused_ && single_steps_ == 0 && !editor_.carrying() && !resizing_ &&
      !panels_owed_ && script_next_ >= script_.size() && rings_.empty())
    SDL_WaitEventTimeout(nullptr, toasts_.empty() ? 1000 : 250);
  while (true) {
    SDL_PumpEvents();
    if (SDL_PeepEvents(&e, 1, SDL_PEEKEVENT, SDL_FIRSTEVENT, SDL_LASTEVENT) == 1 &&
        waits_for_panels(e))
      break;
    if (!SDL_PollEvent(&e)) break;
    handle(e);
  }
  // Edits this frame: the stages the new parts need are made now, so that the
  // world is whole between frames (and a snapshot of it restores).
  if (history_.changes() != synced_changes_) {
    synced_changes_ = history_.changes();
    if (World* w = world()) {
      try {
        History::sync(*w);
      } catch (const std::exception& ex) {
        note(std::string("after the edit: ") + ex.what(), true);
      }
    }
  }

  update_title();

  double seconds = kHeadlessFrame;
  const std::uint64_t now = SDL_GetPerformanceCounter();
  if (!opt_.headless)
    seconds =
        std::clamp(double(now - last_ticks_) / double(SDL_GetPerformanceFrequency()), 0.0, 0.1);
  last_ticks_ = now;
  clock_ += seconds;

  watch_scene_file();
  poll_mods();
  simulate(seconds);
  poll_mods();
  if (World* w = world()) {
    if (!opt_.headless && opt_.audio && !audio_.is_open() && !audio_failed_)
      if (const Stage* s = w->stage("sound")) {
        (void)s;
        std::string why;
        double rate = 48000;
        if (auto* snd = dynamic_cast<const sound::SoundResolver*>(s)) rate = snd->sample_rate();
        if (!audio_.open(rate, &why)) {
          audio_failed_ = true;
          note("no sound: " + why);
        }
      }
    audio_.pump(*w, muted_);
  }
  rings_.erase(std::remove_if(rings_.begin(), rings_.end(),
                              [&](const Ring& r) { return clock_ - r.born > 1.0; }),
               rings_.end());
  while (!toasts_.empty() && clock_ - toasts_.front().born > kToastSeconds) toasts_.pop_front();
  const std::vector<Rect> panels_before = panels_;
  draw(false, nullptr);
  ++frames_;
  // Shown once two frames in a row put the panels at the same places (the
  // first frames size them), or after 10 frames whatever they do.
  if (!shown_ && !opt_.headless && (panels_ == panels_before || frames_ >= 10)) {
    SDL_ShowWindow(window_);
    shown_ = true;
  }
  return !quit_;
}

bool Viewer::waits_for_panels(const SDL_Event& e) {
  // Dear ImGui 1.86 reads the mouse once a frame, as one position and the
  // buttons held (Viewer::draw): a press and a release, then a move away,
  // all in one frame reach it as a click where the pointer ended, and the
  // button under the press never hears of it. A real X server hands over
  // such bursts whole (xdotool's click, then the move to the board: session
  // 19's lost placements), as does a hand when a frame is slow. So, as
  // ImGui 1.87's input queue does it: after a button change the pointer
  // stays where it was, and no further press is taken, until the panels
  // have drawn a frame with the change (and one more for a click's release).
  // Only for a change the panels take (Viewer::for_panels): clicks on the
  // board go to the board's tools at once, several in a frame if they come so.
  if (!imgui_ready_) return false;
  float x = 0, y = 0;
  if (e.type == SDL_MOUSEMOTION)
    x = float(e.motion.x), y = float(e.motion.y);
  else if (e.type == SDL_MOUSEBUTTONDOWN || e.type == SDL_MOUSEBUTTONUP)
    x = float(e.button.x), y = float(e.button.y);
  else
    return false;
  if (panels_owed_ && (e.type == SDL_MOUSEBUTTONDOWN || x != mouse_x_ || y != mouse_y_))
    return true;
  // A press over a panel where the panels have not yet seen the pointer:
  // ImGui gives a click to a window only if the pointer hovered it in the
  // frame before, so the pointer goes there this frame and the press waits.
  if (e.type == SDL_MOUSEBUTTONDOWN && over_panel(x, y) &&
      (x != panels_saw_x_ || y != panels_saw_y_)) {
    mouse_x_ = x, mouse_y_ = y;
    return true;
  }
  return false;
}

void Viewer::simulate(double frame_seconds) {
  World* w = world();
  if (!w) return;
  int steps = 0;
  if (!paused_) {
    accumulator_ += frame_seconds * time_scale_;
    steps = int(std::floor(accumulator_ / w->dt() + 1e-9));
    accumulator_ -= steps * w->dt();
    if (steps > kMaxStepsPerFrame) {
      steps = kMaxStepsPerFrame;
      accumulator_ = 0;
    }
  }
  steps += single_steps_;
  single_steps_ = 0;
  steps_last_frame_ = 0;
  for (int i = 0; i < steps && world(); ++i) {
    editor_.hold();  // what the hand holds stays in the hand, step after step
    step_world();
    ++steps_last_frame_;
    if (paused_ && i + 1 < steps && steps > 1 && failing_steps_ > 0) break;
  }
  editor_.hold();  // and while paused, it follows the hand all the same

  // Time per stage per step, averaged over recent frames.
  const Profile& prof = w->profile();
  const std::uint64_t dsteps = prof.steps - profile_steps_seen_;
  if (dsteps > 0) {
    double total = 0;
    for (const StageTiming& t : prof.stages) {
      auto it = std::find_if(bars_.begin(), bars_.end(),
                             [&](const StageBar& b) { return b.name == t.name; });
      if (it == bars_.end()) {
        bars_.push_back({t.name, t.kind, 0, t.seconds, t.runs});
        continue;
      }
      const double ms = (t.seconds - it->seconds_seen) * 1000 / double(dsteps);
      it->ms = it->ms == 0 ? ms : 0.9 * it->ms + 0.1 * ms;
      it->seconds_seen = t.seconds;
      it->runs_seen = t.runs;
      total += it->ms;
    }
    // Stages that left (a swap, a removed battery) leave the bars too.
    bars_.erase(std::remove_if(bars_.begin(), bars_.end(),
                               [&](const StageBar& b) {
                                 return std::none_of(
                                     prof.stages.begin(), prof.stages.end(),
                                     [&](const StageTiming& t) { return t.name == b.name; });
                               }),
                bars_.end());
    step_ms_ = total;
    profile_steps_seen_ = prof.steps;
  }
}

void Viewer::step_world() {
  World* w = world();
  // Drawn contact forces need impulses. The demand changes what the contact
  // sets keep and save, so it goes through the world as an input that a
  // recording logs and a replay makes again (World::demand_impulses).
  w->demand_impulses(draw_options_.contact_forces);
  try {
    w->step();
    sample_plot();
    failing_steps_ = 0;
    step_error_.clear();
  } catch (const InputError& e) {
    // A resolver refused something an edit made (or the scene had): say
    // where, and wait for the player to put it right.
    const std::string msg = lua::locate(*scene_, e).what();
    if (msg != step_error_) note(msg, true);
    step_error_ = msg;
    paused_ = true;
    ++failing_steps_;
    note("paused: the world cannot step until this is put right (remove the part, or Reset)");
  } catch (const std::exception& e) {
    const std::string msg = std::string("a step failed: ") + e.what();
    if (msg != step_error_) note(msg, true);
    step_error_ = msg;
    if (++failing_steps_ >= 3) {
      paused_ = true;
      note("paused: the world failed three steps in a row");
    }
  }
}

void Viewer::poll_mods() {
  // Between steps: mods whose files changed are reloaded (a failed reload
  // keeps the old code), and stages that erred or ran over budget are reported.
  if (!scene_ || !scene_->mods) return;
  for (const lua::ModReport& r : scene_->mods->poll()) {
    using K = lua::ModReport::Kind;
    const bool bad =
        r.kind == K::ReloadFailed || r.kind == K::StageDisabled || r.kind == K::Stopped;
    note(r.message.empty() ? "mod " + r.mod : r.message, bad);
  }
}

void Viewer::watch_scene_file() {
  // Twice a second is plenty for a person saving a file.
  if (clock_ - last_watch_ < 0.5) return;
  last_watch_ = clock_;
  std::error_code ec;
  const fs::path file = scene_ ? scene_->file : opt_.scene;
  const auto t = fs::last_write_time(file, ec);
  if (ec || t == scene_mtime_) return;
  scene_mtime_ = t;
  if (!scene_) {
    note("the scene file changed: loading it again");
    load();
  } else {
    note("the scene file changed on disk: Reset (Ctrl+R) loads it");
  }
}

// --- input -----------------------------------------------------------------------

void Viewer::add_script(std::vector<ScriptEvent> events) {
  for (auto& e : events) {
    e.frame += int(frames_);
    script_.push_back(e);
  }
  std::stable_sort(script_.begin() + std::ptrdiff_t(script_next_), script_.end(),
                   [](const ScriptEvent& a, const ScriptEvent& b) { return a.frame < b.frame; });
}

void Viewer::pump_script() {
  while (script_next_ < script_.size() && script_[script_next_].frame <= int(frames_)) {
    const ScriptEvent& e = script_[script_next_++];
    switch (e.kind) {
      case ScriptEvent::Kind::Press:
        push_mouse(SDL_MOUSEBUTTONDOWN, e.at);
        break;
      case ScriptEvent::Kind::Move:
        push_mouse(SDL_MOUSEMOTION, e.at);
        break;
      case ScriptEvent::Kind::Release:
        push_mouse(SDL_MOUSEBUTTONUP, e.at);
        break;
      case ScriptEvent::Kind::RightPress:
        push_mouse(SDL_MOUSEBUTTONDOWN, e.at, SDL_BUTTON_RIGHT);
        break;
      case ScriptEvent::Kind::RightRelease:
        push_mouse(SDL_MOUSEBUTTONUP, e.at, SDL_BUTTON_RIGHT);
        break;
      case ScriptEvent::Kind::Wheel:
        push_wheel(e.wheel);
        break;
      case ScriptEvent::Kind::Key: {
        const SDL_Keycode k = SDL_GetKeyFromName(e.key.c_str());
        if (k == SDLK_UNKNOWN)
          note("script line " + std::to_string(e.line) + ": unknown key '" + e.key + "'", true);
        else
          push_key(k, Uint16((e.ctrl ? KMOD_LCTRL : 0) | (e.shift ? KMOD_LSHIFT : 0)));
        break;
      }
      case ScriptEvent::Kind::ModifierDown:
      case ScriptEvent::Kind::ModifierUp: {
        // Held in SDL's keyboard state, which every press, drag and key
        // reads (SDL_GetModState), as a hand holding Shift would be.
        const int m = e.key == "shift" ? KMOD_LSHIFT : e.key == "ctrl" ? KMOD_LCTRL : KMOD_LALT;
        const int now = SDL_GetModState();
        SDL_SetModState(SDL_Keymod(e.kind == ScriptEvent::Kind::ModifierDown ? now | m : now & ~m));
        break;
      }
      case ScriptEvent::Kind::Text: {
        // SDL carries text in pieces of at most 31 bytes.
        for (std::size_t at = 0; at < e.key.size(); at += 31) {
          SDL_Event t{};
          t.type = SDL_TEXTINPUT;
          t.text.windowID = SDL_GetWindowID(window_);
          std::snprintf(t.text.text, sizeof t.text.text, "%s", e.key.substr(at, 31).c_str());
          SDL_PushEvent(&t);
        }
        break;
      }
      case ScriptEvent::Kind::Palette: {
        const auto& entries = palette_entries();
        const auto it = std::find_if(entries.begin(), entries.end(),
                                     [&](const PaletteEntry& p) { return p.label == e.key; });
        if (it == entries.end()) {
          note("script line " + std::to_string(e.line) + ": no palette entry '" + e.key + "'",
               true);
          break;
        }
        set_tool(Tool::Place);
        placing_ = int(it - entries.begin());
        place_drag_ = false;
        break;
      }
      case ScriptEvent::Kind::Set: {
        const std::string where = "script line " + std::to_string(e.line) + ": ";
        const std::string error = script_set(e.key, e.value);
        if (!error.empty()) note(where + error, true);
        break;
      }
    }
  }
}

void Viewer::update_title() {
  // "alloy view - FILE", and " *" while there are edits not saved: what a
  // player sees in the task bar, and what a test driving the window through
  // the X server can wait on (tests/viewer/xvfb_mouse_test.sh).
  std::string title = "alloy view - ";
  title += untitled_ ? std::string("new board") : fs::path(save_path_).filename().string();
  if (history_.dirty()) title += " *";
  if (title != title_ && window_) {
    SDL_SetWindowTitle(window_, title.c_str());
    title_ = title;
  }
}

std::string Viewer::script_set(const std::string& property, const std::string& text) {
  // What the inspector does when a value is typed into the field and Enter
  // pressed (panel_inspector): parsed as the property's kind, then one edit.
  World* w = world();
  if (!w || !selected_ || !w->store().alive(selected_))
    return "set " + property + ": nothing is selected";
  const ObjectId id = selected_;
  if (property == "material") {
    const EditResult r =
        edit("material of " + w->describe(id), [&] { return editor_.set_material(id, text); });
    return r.ok ? "" : r.message;
  }
  const auto p = w->properties().find(property);
  if (!p) return "set: no property '" + property + "'";
  const PropertyDef& def = w->properties().def(*p);
  std::istringstream in(text);
  std::optional<PropertyValue> value;
  switch (def.kind) {
    case PropertyKind::Number: {
      double d;
      if (in >> d) value = d;
      break;
    }
    case PropertyKind::Integer: {
      std::int64_t i;
      if (in >> i) value = i;
      break;
    }
    case PropertyKind::Bool:
      if (text == "true" || text == "false") value = text == "true";
      break;
    case PropertyKind::Vec3: {
      Vec3 v;
      if (in >> v.x >> v.y >> v.z) value = v;
      break;
    }
    case PropertyKind::Quat: {
      double deg;
      if (in >> deg) value = Quat::from_angle_z(deg * std::numbers::pi / 180);
      break;
    }
    case PropertyKind::Enum:
      if (const auto e = w->properties().enum_value(*p, text)) value = *e;
      break;
    case PropertyKind::String:
      value = text;
      break;
    case PropertyKind::Ref:
    case PropertyKind::RefList:
      return "set " + property + ": a reference is not typed in the inspector";
  }
  if (!value) return "set " + property + ": cannot read '" + text + "'";
  const EditResult r = edit("set " + w->describe(id) + "." + property,
                            [&] { return editor_.set_property(id, property, *value); });
  return r.ok ? "" : r.message;
}

void Viewer::push_mouse(Uint32 type, Vec2 at, Uint8 button) {
  const ScreenPoint s = camera_.to_screen(at);
  const int x = int(std::lround(s.x)), y = int(std::lround(s.y));
  SDL_Event e{};
  e.type = type;
  if (type == SDL_MOUSEMOTION) {
    e.motion.windowID = SDL_GetWindowID(window_);
    e.motion.x = x;
    e.motion.y = y;
    e.motion.xrel = mouse_x_ < 0 ? 0 : x - int(mouse_x_);
    e.motion.yrel = mouse_y_ < 0 ? 0 : y - int(mouse_y_);
  } else {
    e.button.windowID = SDL_GetWindowID(window_);
    e.button.button = button;
    e.button.state = type == SDL_MOUSEBUTTONDOWN ? SDL_PRESSED : SDL_RELEASED;
    e.button.clicks = 1;
    e.button.x = x;
    e.button.y = y;
  }
  SDL_PushEvent(&e);
}

void Viewer::push_key(SDL_Keycode key, Uint16 mod) {
  SDL_Event e{};
  e.type = SDL_KEYDOWN;
  e.key.windowID = SDL_GetWindowID(window_);
  e.key.state = SDL_PRESSED;
  e.key.keysym.sym = key;
  e.key.keysym.scancode = SDL_GetScancodeFromKey(key);
  e.key.keysym.mod = mod;
  SDL_PushEvent(&e);
  e.type = SDL_KEYUP;
  e.key.state = SDL_RELEASED;
  SDL_PushEvent(&e);
}

void Viewer::push_wheel(int notches) {
  SDL_Event e{};
  e.type = SDL_MOUSEWHEEL;
  e.wheel.windowID = SDL_GetWindowID(window_);
  e.wheel.y = notches;
  e.wheel.preciseY = float(notches);
  SDL_PushEvent(&e);
}

bool Viewer::for_panels(float x, float y, bool popup) const {
  return over_panel(x, y) || popup || popup_ != Popup::None ||
         (imgui_ready_ && ImGui::GetIO().WantCaptureMouse);
}

bool Viewer::over_panel(float x, float y) const {
  for (const Rect& r : panels_)
    if (x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1) return true;
  return false;
}

void Viewer::handle(const SDL_Event& e) {
  if (imgui_ready_) ImGui_ImplSDL2_ProcessEvent(&e);
  const bool popup = imgui_ready_ && ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopupId);
  switch (e.type) {
    case SDL_QUIT:
      quit_ = true;
      break;
    case SDL_WINDOWEVENT:
      if (e.window.event == SDL_WINDOWEVENT_CLOSE) quit_ = true;
      break;
    case SDL_MOUSEMOTION: {
      const float dx = float(e.motion.x) - mouse_x_, dy = float(e.motion.y) - mouse_y_;
      const bool had = mouse_x_ >= 0;
      mouse_x_ = float(e.motion.x);
      mouse_y_ = float(e.motion.y);
      const Vec2 at = camera_.to_world(mouse_x_, mouse_y_);
      if (panning_ && had)
        camera_.centre = camera_.centre - Vec2{dx / camera_.scale, -dy / camera_.scale};
      if (editor_.carrying())
        editor_.carry_to(snap_ ? editor_.snapped(at, kSnapGrid, 8 / camera_.scale) : at);
      if (resizing_) on_drag(at);
      if (drawing_) on_draw(at);
      hovered_ = over_panel(mouse_x_, mouse_y_) ? ObjectId{} : editor_.pick(at, 4 / camera_.scale);
      break;
    }
    case SDL_MOUSEBUTTONDOWN: {
      const int b = e.button.button == SDL_BUTTON_LEFT    ? 0
                    : e.button.button == SDL_BUTTON_RIGHT ? 1
                                                          : 2;
      mouse_down_[b] = mouse_pressed_[b] = true;
      mouse_x_ = float(e.button.x);
      mouse_y_ = float(e.button.y);
      if (for_panels(mouse_x_, mouse_y_, popup)) panels_owed_ = true;
      if (over_panel(mouse_x_, mouse_y_) || popup || popup_ != Popup::None) break;
      on_press(camera_.to_world(mouse_x_, mouse_y_), e.button.button, Uint16(SDL_GetModState()));
      break;
    }
    case SDL_MOUSEBUTTONUP: {
      const int b = e.button.button == SDL_BUTTON_LEFT    ? 0
                    : e.button.button == SDL_BUTTON_RIGHT ? 1
                                                          : 2;
      mouse_down_[b] = false;
      mouse_x_ = float(e.button.x);
      mouse_y_ = float(e.button.y);
      if (for_panels(mouse_x_, mouse_y_, popup)) panels_owed_ = true;
      on_release(camera_.to_world(mouse_x_, mouse_y_), e.button.button);
      break;
    }
    case SDL_MOUSEWHEEL: {
      if (over_panel(mouse_x_, mouse_y_)) break;
      const int notches = e.wheel.y;
      if (editor_.carrying())
        editor_.turn(notches * kTurnStep);
      else
        camera_.zoom_at(mouse_x_, mouse_y_, std::pow(1.15, notches));
      break;
    }
    case SDL_KEYDOWN:
      if (popup_ != Popup::None) {
        // A file popup is open: Enter does what its first button does,
        // Escape closes it; other keys are typing.
        if (e.key.keysym.sym == SDLK_RETURN || e.key.keysym.sym == SDLK_KP_ENTER) popup_enter();
        if (e.key.keysym.sym == SDLK_ESCAPE) popup_ = Popup::None;
        break;
      }
      if (imgui_ready_ && ImGui::GetIO().WantTextInput) break;
      on_key(e.key.keysym.sym, e.key.keysym.mod);
      break;
    default:
      break;
  }
}

void Viewer::on_press(Vec2 at, Uint8 button, Uint16 mod) {
  World* w = world();
  if (button == SDL_BUTTON_MIDDLE || !w) {
    panning_ = true;
    return;
  }
  const ObjectId part = editor_.pick(at, 4 / camera_.scale);
  if (button == SDL_BUTTON_RIGHT) {
    context_part_ = part;
    context_at_ = at;
    open_context_ = true;
    if (part) selected_ = part;
    return;
  }
  switch (tool_) {
    case Tool::Place: {
      if (placing_ >= 0 && placing_ < int(palette_entries().size())) {
        const PaletteEntry& entry = palette_entries()[std::size_t(placing_)];
        // Bars, disks and fixed shapes can be drawn to any size: held and
        // dragged, the part just put down follows the mouse (Viewer::on_draw),
        // all one edit with the drop.
        if (drop_part(entry, at).ok &&
            (entry.group == "bars" || entry.group == "disks" || entry.group == "fixed")) {
          drawing_ = selected_;
          draw_from_ = at;
          drawn_ = false;
        }
      }
      place_drag_ = false;
      if (!(mod & KMOD_SHIFT)) {
        tool_ = Tool::Hand;
        placing_ = -1;
      }
      break;
    }
    case Tool::Wire: {
      if (!part) {
        wire_start_ = {};
        note("a wire goes from part to part: click a battery, a coil or a conductive part");
        break;
      }
      if (!wire_start_) {
        if (!editor_.electrical(part)) {
          note(w->describe(part) + " does not conduct: a wire cannot end on it", true);
          break;
        }
        wire_start_ = part;
        wire_start_at_ = at;
        break;
      }
      const EditResult r =
          edit("wire", [&] { return editor_.connect_wire(wire_start_, wire_start_at_, part, at); });
      note(r.message, !r.ok);
      wire_start_ = {};
      break;
    }
    case Tool::Hinge:
    case Tool::Glue: {
      const bool hinge = tool_ == Tool::Hinge;
      ObjectId made;
      const EditResult r = edit(hinge ? "hinge" : "glue", [&] {
        return hinge ? editor_.hinge_at(at, 4 / camera_.scale, &made)
                     : editor_.glue_at(at, 4 / camera_.scale, &made);
      });
      note(r.message, !r.ok);
      if (r.ok) selected_ = made;
      if (!(mod & KMOD_SHIFT)) set_tool(Tool::Hand);
      break;
    }
    case Tool::String:
    case Tool::Spring: {
      // First click: the start (a part); second: the end (a part, or the board).
      const bool spring = tool_ == Tool::Spring;
      if (!string_started_) {
        if (!part) {
          note(spring ? "a spring starts on a part: click the part to hang it from or tie it to"
                      : "a string starts on a part: click the part to hang it from or tie it to");
          break;
        }
        string_start_ = part;
        string_start_at_ = at;
        string_started_ = true;
        break;
      }
      ObjectId made_spring;
      const ObjectId from = string_start_;
      const Vec2 from_at = string_start_at_;
      const ObjectId to = part == from ? ObjectId{} : part;
      const EditResult r = edit(spring ? "spring" : "string", [&] {
        return spring ? editor_.spring_between(from, from_at, to, at, &made_spring)
                      : editor_.string_between(from, from_at, to, at, 1.0, &made_spring);
      });
      note(r.message, !r.ok);
      if (r.ok) selected_ = made_spring;
      string_started_ = false;
      string_start_ = {};
      if (r.ok && !(mod & KMOD_SHIFT)) set_tool(Tool::Hand);
      break;
    }
    case Tool::Hand: {
      // The selected part's resize handle comes first, then a joint's pivot.
      if (const auto h = resize_handle(); h && length(*h - at) * camera_.scale <= 7) {
        resizing_ = selected_;
        history_.record(*w, "resize " + w->describe(selected_));
        break;
      }
      if (const ObjectId j = editor_.pick_joint(at, 6 / camera_.scale)) {
        selected_ = j;
        break;
      }
      // A spring or a wire is drawn over the parts: a click on its line (but
      // for its ends, which lie on parts) selects it; Delete removes it.
      if (ObjectId line = editor_.pick_spring(at, 4 / camera_.scale);
          line || (line = wire_at(*w, at, 4 / camera_.scale))) {
        selected_ = line;
        break;
      }
      if (mod & KMOD_SHIFT) {
        // Shift: a click adds a part to the selection (or takes it away); on
        // the board it starts a rubber band.
        if (!part) {
          band_ = true;
          band_from_ = at;
          break;
        }
        if (many_.empty() && selected_ && selected_ != part && read_part(*w, selected_))
          many_.push_back(selected_);
        const auto it = std::find(many_.begin(), many_.end(), part);
        if (it != many_.end())
          many_.erase(it);
        else
          many_.push_back(part);
        selected_ = many_.empty() ? ObjectId{} : many_.back();
        if (many_.size() < 2) many_.clear();
        break;
      }
      if (!part) {
        select({});
        panning_ = true;
        break;
      }
      // A part of the multi-selection carries all of it; another part is
      // selected alone.
      const bool in_many = std::find(many_.begin(), many_.end(), part) != many_.end();
      if (!in_many) many_.clear();
      selected_ = part;
      history_.record(*w, many_.empty() ? "move " + w->describe(part)
                                        : "move " + std::to_string(many_.size()) + " parts");
      std::vector<ObjectId> carried{part};
      for (ObjectId o : many_)
        if (o != part && w->store().alive(o)) carried.push_back(o);
      const EditResult r = editor_.grab_all(carried, at);
      if (!r.ok) {
        history_.forget_last();
        note(r.message, true);
      }
      break;
    }
  }
}

void Viewer::on_release(Vec2 at, Uint8 button) {
  panning_ = false;
  if (button != SDL_BUTTON_LEFT) return;
  if (drawing_) {
    on_draw(at);
    // Made whole as after a resize, so that a redo of the drop (a restore of
    // the synced world) matches what the next step sees.
    if (World* w = world(); w && drawn_) History::sync(*w);
    drawing_ = {};
    return;
  }
  if (band_) {
    band_ = false;
    // Every part the band holds joins the selection (a second band adds).
    std::vector<ObjectId> got = selection();
    if (got.size() == 1 && !read_part(*world(), got.front())) got.clear();
    for (ObjectId id : editor_.parts_in(band_from_, at))
      if (std::find(got.begin(), got.end(), id) == got.end()) got.push_back(id);
    many_ = got.size() >= 2 ? got : std::vector<ObjectId>{};
    selected_ = got.empty() ? ObjectId{} : got.front();
    return;
  }
  if (tool_ == Tool::Place && place_drag_) {
    // Dragged from the palette and let go over the play area: drop it there.
    place_drag_ = false;
    if (!over_panel(mouse_x_, mouse_y_) && placing_ >= 0) {
      drop_part(palette_entries()[std::size_t(placing_)], at);
      tool_ = Tool::Hand;
      placing_ = -1;
    }
    return;
  }
  if (resizing_) {
    on_drag(at);
    resizing_ = {};
    // The resize is done: the world made whole as after every edit (the
    // frame syncs after an edit is recorded, which for a resize was at the
    // press, before the part changed). Without it the rigid body rebuilds in
    // place at the next step, which a redo of this resize (a restore of the
    // synced world) does not repeat.
    if (World* w = world()) History::sync(*w);
    return;
  }
  if (editor_.carrying()) {
    if (snap_) at = editor_.snapped(at, kSnapGrid, 8 / camera_.scale);
    editor_.carry_to(at);
    // A click that moved nothing only selected: it is not an edit to undo.
    const bool moved = editor_.moved();
    const EditResult r = editor_.drop();
    if (!moved) history_.forget_last();
    note(r.message, !r.ok);
    // A click on a switch that did not move it throws it, as a hand would:
    // an edit of its own, so that Ctrl+Z closes it again.
    World* w = world();
    if (!moved && w && selected_ && w->store().alive(selected_))
      if (const auto closed = w->value<bool>(selected_, "switch_closed")) {
        const ObjectId sw = selected_;
        const EditResult t = edit("switch " + w->describe(sw), [&] {
          w->set(sw, "switch_closed", !*closed);
          return EditResult{true, w->describe(sw) + (*closed ? " opened" : " closed")};
        });
        note(t.message, !t.ok);
      }
  }
}

void Viewer::on_key(SDL_Keycode key, Uint16 mod) {
  const bool ctrl = mod & (KMOD_CTRL | KMOD_GUI);
  World* w = world();
  const ObjectId target = hovered_ ? hovered_ : selected_;
  switch (key) {
    case SDLK_SPACE:
      paused_ = !paused_;
      break;
    case SDLK_n:
      if (ctrl) {
        if (history_.dirty())
          ask(Popup::ConfirmNew);
        else
          new_board();
        break;
      }
      [[fallthrough]];
    case SDLK_PERIOD:
      paused_ = true;
      step_once();
      break;
    case SDLK_r:
      if (ctrl) reset();
      break;
    case SDLK_s:
      if (ctrl && ((mod & KMOD_SHIFT) || untitled_))
        ask(Popup::SaveAs);
      else if (ctrl)
        save(save_path_);
      break;
    case SDLK_o:
      if (ctrl) ask(Popup::Open);
      break;
    case SDLK_z:
      if (ctrl && (mod & KMOD_SHIFT))
        redo();
      else if (ctrl)
        undo();
      break;
    case SDLK_y:
      if (ctrl) redo();
      break;
    case SDLK_h:
      set_tool(tool_ == Tool::Hinge ? Tool::Hand : Tool::Hinge);
      break;
    case SDLK_j:
      set_tool(tool_ == Tool::Glue ? Tool::Hand : Tool::Glue);
      break;
    case SDLK_t:
      set_tool(tool_ == Tool::String ? Tool::Hand : Tool::String);
      break;
    case SDLK_k:
      set_tool(tool_ == Tool::Spring ? Tool::Hand : Tool::Spring);
      break;
    case SDLK_q:
    case SDLK_e: {
      const double a = key == SDLK_q ? kTurnStep : -kTurnStep;
      if (editor_.carrying())
        editor_.turn(a);
      else if (target && w) {
        const EditResult r =
            edit("turn " + w->describe(target), [&] { return editor_.rotate(target, a); });
        if (!r.ok || !r.message.empty()) note(r.message, !r.ok);
      }
      break;
    }
    case SDLK_p:
      if (target && w) {
        const EditResult r =
            edit("pin " + w->describe(target), [&] { return editor_.toggle_pin(target); });
        note(r.message, !r.ok);
      }
      break;
    case SDLK_w:
      set_tool(tool_ == Tool::Wire ? Tool::Hand : Tool::Wire);
      break;
    case SDLK_c:
      if (ctrl)
        copy_selection();
      else
        draw_options_.compass = !draw_options_.compass;
      break;
    case SDLK_v:
      if (ctrl) paste_clipboard();
      break;
    case SDLK_x:
      snap_ = !snap_;
      note(snap_ ? "snapping on: part ends onto part ends, else centres onto the 1 cm grid"
                 : "snapping off");
      break;
    case SDLK_DELETE:
    case SDLK_BACKSPACE:
      if (const std::vector<ObjectId> all = selection(); all.size() > 1 && w) {
        const EditResult r = edit("remove " + std::to_string(all.size()) + " parts",
                                  [&] { return editor_.remove_all(all); });
        note(r.message, !r.ok);
        if (r.ok) select({}), hovered_ = {};
      } else if (selected_ && w) {
        const ObjectId doomed = selected_;
        const EditResult r =
            edit("remove " + w->describe(doomed), [&] { return editor_.remove(doomed); });
        note(r.message, !r.ok);
        if (r.ok) selected_ = hovered_ = {};
      }
      break;
    case SDLK_f:
      fit_view();
      break;
    case SDLK_EQUALS:
    case SDLK_PLUS:
    case SDLK_KP_PLUS:
      set_time_scale(time_scale_ * 2);
      break;
    case SDLK_MINUS:
    case SDLK_KP_MINUS:
      set_time_scale(time_scale_ / 2);
      break;
    case SDLK_l:
      draw_options_.labels = !draw_options_.labels;
      break;
    case SDLK_g:
      draw_options_.magnetic_forces = draw_options_.contact_forces = !draw_options_.magnetic_forces;
      break;
    case SDLK_m:
      muted_ = !muted_;
      break;
    case SDLK_ESCAPE:
      set_tool(Tool::Hand);
      help_ = false;
      many_.clear();
      break;
    case SDLK_a:
      // A meter probe on the part under the mouse (again: taken off). It
      // reads what the part carries: current, and the voltage across it.
      if (target && w && !ctrl) {
        const auto it = std::find(probes_.begin(), probes_.end(), target);
        if (it != probes_.end())
          probes_.erase(it);
        else if (w->value<double>(target, "current"))
          probes_.push_back(target);
        else
          note(w->describe(target) + " carries no current: a meter probe reads nothing there",
               true);
      }
      break;
    case SDLK_F1:
    case SDLK_QUESTION:
      help_ = !help_;
      break;
    case SDLK_SLASH:  // '?' on a US keyboard
      if (mod & KMOD_SHIFT) help_ = !help_;
      break;
    default:
      break;
  }
}

// --- edits -----------------------------------------------------------------------

EditResult Viewer::drop_part(const PaletteEntry& entry, Vec2 at) {
  World* w = world();
  if (!w) return EditResult::refused("there is no world to put a part in");
  history_.record(*w, "add " + entry.label);
  try {
    const std::string name = editor_.unique_name(entry.base);
    const std::vector<ObjectId> ids = make_part(*w, entry, at, opt_.load, name);
    if (ids.empty()) {
      history_.forget_last();
      return EditResult::refused("the kit made nothing for " + entry.label);
    }
    selected_ = ids.front();
    const EditResult r = editor_.settle(ids.front());
    const std::string msg = r.message.empty() ? "added " + w->describe(ids.front()) : r.message;
    note(msg, !r.ok);
    return {r.ok, msg};
  } catch (const std::exception& e) {
    history_.forget_last();
    note(std::string("cannot add ") + entry.label + ": " + e.what(), true);
    return EditResult::refused(e.what());
  }
}

EditResult Viewer::swap(const std::string& area, const std::string& from, const std::string& to) {
  World* w = world();
  if (!w) return EditResult::refused("no world");
  history_.record(*w, "swap " + from + " for " + to);
  try {
    w->swap(area, from, to);
    const std::string msg = "swapped " + from + " for " + to + (area.empty() ? "" : " in " + area);
    note(msg);
    return {true, msg};
  } catch (const std::exception& e) {
    history_.forget_last();
    note(e.what(), true);
    return EditResult::refused(e.what());
  }
}

bool Viewer::save(const fs::path& path) {
  World* w = world();
  if (!w) {
    note("nothing to save: the scene did not load", true);
    return false;
  }
  try {
    SceneMeta meta;
    meta.name = scene_->name;
    meta.description = scene_->description;
    meta.seconds = scene_->seconds;
    meta.origin = opt_.scene.string();
    save_scene(*w, meta, path);
    note("saved " + path.string());
    history_.mark_saved();
    save_path_ = path.string();
    if (untitled_) {
      // The new board is this file now: Reset loads it.
      untitled_ = false;
      opt_.scene = path;
      std::error_code ec;
      scene_mtime_ = fs::last_write_time(path, ec);
    }
    return true;
  } catch (const std::exception& e) {
    note(std::string("cannot save: ") + e.what(), true);
    return false;
  }
}

// --- drawing ---------------------------------------------------------------------

void Viewer::play_rect(float& x0, float& y0, float& x1, float& y1) const {
  int w = opt_.width, h = opt_.height;
  SDL_GetWindowSize(window_, &w, &h);
  x0 = 0;
  y0 = 0;
  x1 = float(w);
  y1 = float(h);
  if (opt_.panels) {
    x0 = kLeftWidth + 2 * kMargin;
    x1 = float(w) - kRightWidth - 2 * kMargin;
    y1 = float(h) - 40;
    if (x1 - x0 < 200) {  // a narrow window: the panels float over the play area
      x0 = 0;
      x1 = float(w);
    }
  }
}

void Viewer::fit_view() {
  float x0, y0, x1, y1;
  play_rect(x0, y0, x1, y1);
  Vec2 lo{1e300, 1e300}, hi{-1e300, -1e300};
  if (World* w = world())
    for (const Part2D& p : read_parts(*w))
      for (Vec2 v : outline(p, 16)) {
        lo = {std::min(lo.x, v.x), std::min(lo.y, v.y)};
        hi = {std::max(hi.x, v.x), std::max(hi.y, v.y)};
      }
  if (lo.x > hi.x) {
    lo = {-1, 0};
    hi = {1, 1.5};
  }
  camera_.fit(lo, hi, x0, y0, x1, y1);
  fitted_ = true;
}

void Viewer::remember_panel() {
  const ImVec2 p = ImGui::GetWindowPos(), s = ImGui::GetWindowSize();
  next_panels_.push_back({p.x, p.y, p.x + s.x, p.y + s.y});
}

Image Viewer::render_image() {
  ImGui::SetCurrentContext(imgui_);
  Image img;
  draw(true, &img);
  return img;
}

void Viewer::draw(bool capture, Image* image) {
  if (!fitted_ && world()) fit_view();
  ImGui_ImplSDLRenderer_NewFrame();
  ImGui_ImplSDL2_NewFrame();
  // The mouse as the events said (the backend asks SDL for the pointer, which
  // knows nothing of pushed events): scripted input drives the panels too.
  ImGuiIO& io = ImGui::GetIO();
  io.MousePos = mouse_x_ >= 0 ? ImVec2(mouse_x_, mouse_y_) : ImVec2(-FLT_MAX, -FLT_MAX);
  panels_saw_x_ = mouse_x_, panels_saw_y_ = mouse_y_;
  const bool owed = panels_owed_;
  panels_owed_ = false;
  for (int i = 0; i < 3; ++i) {
    io.MouseDown[i] = mouse_down_[i] || mouse_pressed_[i];
    // A click on the panels, pressed and released since the last frame: this
    // frame shows the press, the next the release, at the same place
    // (Viewer::waits_for_panels).
    if (owed && mouse_pressed_[i] && !mouse_down_[i]) panels_owed_ = true;
    mouse_pressed_[i] = false;
  }
  if (opt_.headless) io.DeltaTime = float(kHeadlessFrame);
  ImGui::NewFrame();

  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  if (World* w = world()) {
    Highlight hl{selected_, hovered_, wire_start_, editor_.carrying()};
    draw_world(dl, *w, camera_, draw_options_, hl, clock_, rings_);
    // The tools' feedback: a wire being drawn, a part about to be placed.
    if (tool_ == Tool::Wire && wire_start_ && mouse_x_ >= 0 && w->store().alive(wire_start_)) {
      const auto p = read_part(*w, wire_start_);
      const bool two = editor_.two_terminal(wire_start_);
      const Vec2 from =
          two && p ? terminal_point(*w, wire_start_, p->to_local(wire_start_at_).x > 0 ? 1 : 0)
                   : (p ? p->centre : wire_start_at_);
      const ScreenPoint s = camera_.to_screen(from);
      dl->AddLine({s.x, s.y}, {mouse_x_, mouse_y_}, colour::kWireIdle, 2.5f);
    }
    draw_tool_feedback(dl, *w);
    // The multi-selection: each part outlined.
    for (ObjectId id : many_)
      if (const auto p = read_part(*w, id)) {
        std::vector<ImVec2> pts;
        for (Vec2 v : outline(*p, 32)) {
          const ScreenPoint q = camera_.to_screen(v);
          pts.push_back({q.x, q.y});
        }
        dl->AddPolyline(pts.data(), int(pts.size()), colour::kSelected, ImDrawFlags_Closed, 2.5f);
      }
    if (band_ && mouse_x_ >= 0) {
      const ScreenPoint a = camera_.to_screen(band_from_);
      dl->AddRectFilled({std::min(a.x, mouse_x_), std::min(a.y, mouse_y_)},
                        {std::max(a.x, mouse_x_), std::max(a.y, mouse_y_)},
                        colour::rgb(0, 150, 220, 40));
      dl->AddRect({std::min(a.x, mouse_x_), std::min(a.y, mouse_y_)},
                  {std::max(a.x, mouse_x_), std::max(a.y, mouse_y_)}, colour::kSelected, 0, 0,
                  1.5f);
    }
    draw_scale_bar(dl);
    if (legend_) draw_legend(dl);
    draw_tooltip(*w);
    // Meter probes: a reading in a box beside each probed part.
    const std::vector<std::string> readings = probe_readings();
    for (std::size_t k = 0; k < probes_.size(); ++k) {
      const auto p = read_part(*w, probes_[k]);
      if (!p) continue;
      const ScreenPoint s = camera_.to_screen(p->centre);
      const ImVec2 at{s.x + 12, s.y - 34};
      const ImVec2 ts = ImGui::CalcTextSize(readings[k].c_str());
      dl->AddRectFilled({at.x - 3, at.y - 2}, {at.x + ts.x + 3, at.y + ts.y + 2},
                        colour::rgb(255, 255, 235), 3);
      dl->AddRect({at.x - 3, at.y - 2}, {at.x + ts.x + 3, at.y + ts.y + 2}, colour::rgb(40, 40, 40),
                  3);
      dl->AddLine({s.x, s.y}, {at.x - 3, at.y + ts.y + 2}, colour::rgb(40, 40, 40), 1);
      dl->AddText(at, colour::rgb(20, 20, 20), readings[k].c_str());
    }
    if (tool_ == Tool::Place && placing_ >= 0 && mouse_x_ >= 0 && !over_panel(mouse_x_, mouse_y_)) {
      const char* label = palette_entries()[std::size_t(placing_)].label.c_str();
      dl->AddCircle({mouse_x_, mouse_y_}, 10, colour::kSelected, 20, 2);
      dl->AddLine({mouse_x_ - 14, mouse_y_}, {mouse_x_ + 14, mouse_y_}, colour::kSelected, 1.5f);
      dl->AddLine({mouse_x_, mouse_y_ - 14}, {mouse_x_, mouse_y_ + 14}, colour::kSelected, 1.5f);
      dl->AddText({mouse_x_ + 14, mouse_y_ + 6}, colour::kSelected, label);
    }
  }

  next_panels_.clear();
  if (opt_.panels) draw_panels();
  if (help_) panel_help();
  panel_plot();
  panel_error();
  file_popups();
  panel_messages();
  context_menu();
  panels_ = next_panels_;

  ImGui::Render();
  // Headless, nobody sees a frame that is not captured: build it (the panels
  // keep their state) but do not rasterise it.
  if (opt_.headless && !capture) return;
  const ImU32 bg = colour::kBackground;
  SDL_SetRenderDrawColor(renderer_, bg & 0xff, (bg >> 8) & 0xff, (bg >> 16) & 0xff, 255);
  SDL_RenderClear(renderer_);
  ImGui_ImplSDLRenderer_RenderDrawData(ImGui::GetDrawData());
  if (capture && image) {
    int w = 0, h = 0;
    SDL_GetRendererOutputSize(renderer_, &w, &h);
    image->width = w;
    image->height = h;
    image->rgba.assign(std::size_t(w) * h * 4, 0);
    if (SDL_RenderReadPixels(renderer_, nullptr, SDL_PIXELFORMAT_RGBA32, image->rgba.data(),
                             w * 4) != 0)
      throw std::runtime_error(std::string("cannot read the picture back: ") + SDL_GetError());
  }
  SDL_RenderPresent(renderer_);
}

void Viewer::draw_tool_feedback(ImDrawList* dl, World& w) {
  // A string being drawn: a dashed line from its first end to the mouse.
  if ((tool_ == Tool::String || tool_ == Tool::Spring) && string_started_ && mouse_x_ >= 0) {
    const ScreenPoint a = camera_.to_screen(string_start_at_);
    const float dx = mouse_x_ - a.x, dy = mouse_y_ - a.y;
    const int dashes = std::max(1, int(std::sqrt(dx * dx + dy * dy) / 10));
    for (int i = 0; i < dashes; i += 2)
      dl->AddLine({a.x + dx * i / dashes, a.y + dy * i / dashes},
                  {a.x + dx * (i + 1) / dashes, a.y + dy * (i + 1) / dashes}, colour::kSelected, 2);
    dl->AddCircleFilled({a.x, a.y}, 4, colour::kSelected, 12);
  }
  // Hinge and glue: a ring or a square where a click would put one.
  if ((tool_ == Tool::Hinge || tool_ == Tool::Glue) && mouse_x_ >= 0 &&
      !over_panel(mouse_x_, mouse_y_)) {
    if (tool_ == Tool::Hinge)
      dl->AddCircle({mouse_x_, mouse_y_}, 7, colour::kSelected, 20, 2);
    else
      dl->AddRect({mouse_x_ - 5, mouse_y_ - 5}, {mouse_x_ + 5, mouse_y_ + 5}, colour::kSelected, 0,
                  0, 2);
  }
  if (!selected_ || !w.store().alive(selected_)) return;
  // The selected joint: a ring about its pivot.
  if (const auto kind = w.value<EnumValue>(selected_, "joint")) {
    auto anchor = w.value<Vec3>(selected_, "anchor");
    if (kind->index != 0)  // glue: drawn on its first part
      if (const auto a = w.value<ObjectId>(selected_, "body_a"); a && w.store().alive(*a))
        anchor = w.value<Vec3>(*a, "position");
    if (anchor) {
      const ScreenPoint c = camera_.to_screen(xy(*anchor));
      dl->AddCircle({c.x, c.y}, 11, colour::kSelected, 24, 2.5f);
    }
  }
  // The selected part's resize handle: a square at a corner (a disk's rim).
  if (const auto h = resize_handle()) {
    const ScreenPoint c = camera_.to_screen(*h);
    dl->AddRectFilled({c.x - 5, c.y - 5}, {c.x + 5, c.y + 5}, IM_COL32_WHITE);
    dl->AddRect({c.x - 5, c.y - 5}, {c.x + 5, c.y + 5}, colour::kSelected, 0, 0, 2);
  }
}

bool Viewer::plot(ObjectId part, const std::string& property, double seconds) {
  World* w = world();
  if (!w || !part || !w->store().alive(part) || !w->value<double>(part, property) || seconds <= 0)
    return false;
  plot_part_ = part;
  plot_property_ = property;
  plot_seconds_ = seconds;
  plot_samples_.clear();
  return true;
}

void Viewer::sample_plot() {
  World* w = world();
  if (!plot_part_ || !w) return;
  if (!w->store().alive(plot_part_)) {
    plot_part_ = {};
    return;
  }
  plot_samples_.push_back(float(w->value<double>(plot_part_, plot_property_).value_or(0)));
  const std::size_t keep = std::max<std::size_t>(2, std::size_t(plot_seconds_ / w->dt() + 0.5));
  if (plot_samples_.size() > keep)
    plot_samples_.erase(plot_samples_.begin(),
                        plot_samples_.begin() + std::ptrdiff_t(plot_samples_.size() - keep));
}

void Viewer::panel_plot() {
  World* w = world();
  if (!plot_part_ || !w || !w->store().alive(plot_part_)) return;
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos({size.x / 2, size.y - 10}, ImGuiCond_Always, {0.5f, 1});
  ImGui::SetNextWindowSize({420, 0});
  bool open = true;
  const std::string title = "Plot: " + w->describe(plot_part_) + " " + plot_property_ + "###plot";
  ImGui::Begin(title.c_str(), &open, ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoResize);
  remember_panel();
  float lo = 0, hi = 0;
  for (const float v : plot_samples_) lo = std::min(lo, v), hi = std::max(hi, v);
  const std::string now =
      plot_samples_.empty() ? "" : std::to_string(plot_samples_.back()).substr(0, 10);
  ImGui::Text("last %.1f s: %.4g .. %.4g", plot_seconds_, double(lo), double(hi));
  ImGui::PlotLines("##values", plot_samples_.data(), int(plot_samples_.size()), 0, now.c_str(), lo,
                   hi > lo ? hi : lo + 1, {400, 90});
  ImGui::End();
  if (!open) plot_part_ = {};
}

std::vector<std::string> Viewer::probe_readings() {
  std::vector<std::string> out;
  World* w = world();
  if (!w) return out;
  std::erase_if(probes_, [&](ObjectId id) { return !w->store().alive(id); });
  for (const ObjectId id : probes_) {
    char buf[160];
    const double i = w->value<double>(id, "current").value_or(0);
    // A battery's voltage is its emf less what its own resistance takes; a
    // resistive part's is I R (Ohm's law, as the electricity resolver solves it).
    std::optional<double> v;
    if (const auto emf = w->value<double>(id, "emf"))
      v = *emf - std::abs(i) * w->value<double>(id, "internal_resistance").value_or(0);
    else if (const auto r = w->value<double>(id, "resistance"))
      v = std::abs(i) * *r;
    if (v)
      std::snprintf(buf, sizeof buf, "%s: %.4g A, %.4g V", w->describe(id).c_str(), std::abs(i),
                    *v);
    else
      std::snprintf(buf, sizeof buf, "%s: %.4g A", w->describe(id).c_str(), std::abs(i));
    out.push_back(buf);
  }
  return out;
}

std::vector<ObjectId> Viewer::selection() const {
  std::vector<ObjectId> out;
  const World* w = scene_ ? scene_->world.get() : nullptr;
  if (!w) return out;
  for (ObjectId id : many_)
    if (w->store().alive(id)) out.push_back(id);
  if (out.empty() && selected_ && w->store().alive(selected_)) out.push_back(selected_);
  return out;
}

void Viewer::copy_selection() {
  World* w = world();
  if (!w) return;
  clipboard_ = editor_.copy(selection());
  if (clipboard_.empty())
    note("nothing to copy: select parts first (a click, Shift+click or a Shift+drag band)", true);
  else
    note("copied " + std::to_string(clipboard_.parts) + " parts and " +
         std::to_string(clipboard_.objects.size() - clipboard_.parts) +
         " joints, wires and springs among them");
}

void Viewer::paste_clipboard() {
  World* w = world();
  if (!w) return;
  // At the mouse (the copy's centre there), else a little aside of the original.
  const bool mouse = mouse_x_ >= 0 && !over_panel(mouse_x_, mouse_y_);
  const Vec2 to =
      mouse ? camera_.to_world(mouse_x_, mouse_y_) : clipboard_.centre + Vec2{0.05, 0.05};
  std::vector<ObjectId> made;
  const EditResult r =
      edit("paste", [&] { return editor_.paste(clipboard_, to - clipboard_.centre, &made); });
  note(r.message, !r.ok);
  if (!r.ok) return;
  // The copy comes selected, so that it can be carried off at once.
  many_ = made.size() >= 2 ? made : std::vector<ObjectId>{};
  selected_ = made.empty() ? ObjectId{} : made.front();
}

void Viewer::draw_legend(ImDrawList* dl) {
  // What each colour and mark on the board means, in the play area's upper
  // right corner (the messages take the bottom).
  float x0, y0, x1, y1;
  play_rect(x0, y0, x1, y1);
  struct Row {
    ImU32 colour;
    int mark;  // 0 dot, 1 line, 2 arrow, 3 square
    const char* text;
  };
  static const Row rows[] = {
      {colour::kNorth, 0, "north pole"},
      {colour::kSouth, 0, "south pole"},
      {colour::kWireLive, 1, "wire carrying current"},
      {colour::kWireIdle, 1, "wire, no current"},
      {colour::kPowered, 3, "powered part"},
      {colour::kMagneticForce, 2, "magnetic force (G)"},
      {colour::kContactForce, 2, "contact force"},
      {colour::kSelected, 1, "selected"},
      {colour::kStaticWood, 3, "fixed to the board"},
  };
  const float line = 16, width = 186;
  const int n = int(std::size(rows)) + (draw_options_.compass ? 1 : 0);
  const float top = y0 + 10, bottom = top + line * float(n) + 8, left = x1 - width - 10;
  dl->AddRectFilled({left, top}, {left + width, bottom}, colour::rgb(255, 255, 255, 225), 4);
  dl->AddRect({left, top}, {left + width, bottom}, colour::rgb(180, 184, 192), 4);
  float y = top + 4;
  auto text = [&](const char* t) {
    dl->AddText({left + 30, y}, colour::rgb(40, 40, 48), t);
    y += line;
  };
  for (const Row& r : rows) {
    const float cy = y + line / 2 - 1, cx = left + 14;
    switch (r.mark) {
      case 0:
        dl->AddCircleFilled({cx, cy}, 5, r.colour, 12);
        break;
      case 1:
        dl->AddLine({cx - 9, cy}, {cx + 9, cy}, r.colour, 3);
        break;
      case 2:
        dl->AddLine({cx - 9, cy}, {cx + 5, cy}, r.colour, 2.5f);
        dl->AddTriangleFilled({cx + 10, cy}, {cx + 3, cy - 4}, {cx + 3, cy + 4}, r.colour);
        break;
      default:
        dl->AddRectFilled({cx - 7, cy - 5}, {cx + 7, cy + 5}, r.colour, 2);
        break;
    }
    text(r.text);
  }
  if (draw_options_.compass) {
    const float cy = y + line / 2 - 1, cx = left + 14;
    dl->AddTriangleFilled({cx + 10, cy}, {cx, cy - 3}, {cx, cy + 3}, colour::kNorth);
    dl->AddTriangleFilled({cx - 10, cy}, {cx, cy + 3}, {cx, cy - 3}, colour::rgb(120, 130, 150));
    text("compass: red end to north");
  }
}

void Viewer::draw_tooltip(World& w) {
  // The part under the mouse, with the hand idle: its name and what it is.
  tooltip_.clear();
  if (tool_ != Tool::Hand || editor_.carrying() || band_ || !hovered_ ||
      !w.store().alive(hovered_) || mouse_x_ < 0 || over_panel(mouse_x_, mouse_y_))
    return;
  const auto p = read_part(w, hovered_);
  if (!p) return;
  char buf[96];
  std::string t = w.describe(hovered_);
  static const char* const names[] = {"steel",  "iron", "brass",  "bronze",
                                      "copper", "wood", "rubber", ""};
  if (const char* m = names[int(material_of(w, hovered_))]; *m) t += std::string(", ") + m;
  if (p->radius > 0 && p->shape != Shape2D::Box)
    std::snprintf(buf, sizeof buf, "\nradius %.1f cm", p->radius * 100);
  else
    std::snprintf(buf, sizeof buf, "\n%.1f x %.1f cm", p->half.x * 200, p->half.y * 200);
  t += buf;
  if (const auto m = w.value<double>(hovered_, "mass")) {
    std::snprintf(buf, sizeof buf, ", %.3g g", *m * 1000);
    t += buf;
  }
  if (p->is_static) t += ", fixed";
  if (p->pinned) t += ", pinned";
  if (const auto v = w.value<double>(hovered_, "emf")) {
    std::snprintf(buf, sizeof buf, "\nbattery %.3g V", *v);
    t += buf;
  }
  if (const auto i = w.value<double>(hovered_, "current")) {
    std::snprintf(buf, sizeof buf, "\ncurrent %.3g A", *i);
    t += buf;
  }
  if (const auto spin = w.value<Vec3>(hovered_, "angular_velocity"); spin && spin->z != 0) {
    std::snprintf(buf, sizeof buf, "\nturning %.3g rad/s", spin->z);
    t += buf;
  }
  tooltip_ = t;
  ImGui::BeginTooltip();
  ImGui::TextUnformatted(tooltip_.c_str());
  ImGui::EndTooltip();
}

void Viewer::draw_scale_bar(ImDrawList* dl) {
  // The longest of 1, 2 or 5 times a power of ten that fits in 120 pixels:
  // a length a reader can take in at a glance.
  const double most = 120 / camera_.scale;
  double len = std::pow(10.0, std::floor(std::log10(most)));
  if (5 * len <= most)
    len *= 5;
  else if (2 * len <= most)
    len *= 2;
  const float px = float(len * camera_.scale);
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  const float x0 = size.x - px - 24, y = size.y - 20;
  dl->AddLine({x0, y}, {x0 + px, y}, colour::kLabel, 2);
  dl->AddLine({x0, y - 5}, {x0, y + 5}, colour::kLabel, 2);
  dl->AddLine({x0 + px, y - 5}, {x0 + px, y + 5}, colour::kLabel, 2);
  char label[32];
  if (len >= 1)
    std::snprintf(label, sizeof label, "%g m", len);
  else if (len >= 0.01)
    std::snprintf(label, sizeof label, "%g cm", len * 100);
  else
    std::snprintf(label, sizeof label, "%g mm", len * 1000);
  dl->AddText({x0 + px / 2 - 12, y - 18}, colour::kLabel, label);
}

void Viewer::panel_help() {
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos({size.x / 2, size.y / 2}, ImGuiCond_Always, {0.5f, 0.5f});
  ImGui::SetNextWindowBgAlpha(0.95f);
  ImGui::Begin("Help (F1 or ? to close)", &help_,
               ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_AlwaysAutoResize);
  remember_panel();
  static const char* const rows[][2] = {
      {"Space", "run / pause"},
      {"N or .", "one step"},
      {"drag a part", "move it (Q / E or the wheel turn it)"},
      {"click a switch", "open or close it"},
      {"palette bar or disk", "click to put it down; press and drag to draw it to any size"},
      {"W", "wire tool: a part's end, then another part's end"},
      {"H", "hinge tool: where two parts overlap"},
      {"J", "glue tool: where two parts overlap or touch"},
      {"T", "string tool: a part, then another part or the board (it pulls, never pushes)"},
      {"K", "spring tool: a part, then another part or the board (a spring with a damper)"},
      {"P", "pin the part under the mouse to the board"},
      {"Delete", "remove the selected part, joint, spring or wire (click a wire to select it)"},
      {"Shift+click, Shift+drag", "add a part to the selection; a rubber band on the board"},
      {"Ctrl+C / Ctrl+V",
       "copy the selection (with its joints, wires, springs); paste at the mouse"},
      {"X", "snapping on / off: part ends onto part ends, else the 1 cm grid"},
      {"C", "compass needles on / off (the magnetic field)"},
      {"Ctrl+Z / Ctrl+Y", "undo / redo"},
      {"Ctrl+N / O / S", "new board / open / save (Shift: save as)"},
      {"Ctrl+R", "reset to the file"},
      {"+ / - or the wheel", "zoom"},
      {"A", "a meter probe on the part under the mouse (again: off)"},
      {"F1 or ?", "this help"},
      {"L", "labels on / off"},
      {"G", "force arrows on / off"},
      {"M", "sound on / off"},
      {"F", "fit the view to the scene"},
      {"middle drag, drag the board", "pan"},
      {"right click", "a part's menu"},
      {"Escape", "back to the hand; closes this help"},
  };
  if (ImGui::BeginTable("keys", 2, ImGuiTableFlags_RowBg)) {
    for (const auto& r : rows) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(ImVec4(0.1f, 0.3f, 0.7f, 1), "%s", r[0]);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r[1]);
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

void Viewer::draw_panels() {
  panel_toolbar();
  panel_palette();
  panel_inspector();
  panel_resolvers();
}

void Viewer::panel_toolbar() {
  ImGui::SetNextWindowPos({kMargin, kMargin});
  ImGui::SetNextWindowSize({kLeftWidth, 0});
  ImGui::Begin("alloy view", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  World* w = world();
  if (scene_) {
    ImGui::TextColored(ImVec4(0.25f, 0.1f, 0.5f, 1), "%s", scene_->name.c_str());
    if (w) ImGui::Text("t = %.3f s   step %llu", w->time(), (unsigned long long)w->step_count());
    // Frames drawn per second, as ImGui averages them (headless: the fixed
    // frame time the tests use).
    ImGui::TextDisabled("%.0f fps", double(ImGui::GetIO().Framerate));
  } else {
    ImGui::TextColored(ImVec4(0.8f, 0.1f, 0.1f, 1), "scene not loaded");
  }
  const float bw = (kLeftWidth - 20 - 2 * 6) / 3;
  if (ImGui::Button(paused_ ? "Run" : "Pause", {bw, 0})) paused_ = !paused_;
  ImGui::SameLine();
  if (ImGui::Button("Step", {bw, 0})) {
    paused_ = true;
    step_once();
  }
  ImGui::SameLine();
  if (ImGui::Button("Reset", {bw, 0})) reset();
  float scale = float(time_scale_);
  ImGui::SetNextItemWidth(kLeftWidth - 20);
  if (ImGui::SliderFloat("##scale", &scale, 1.0f / 16, 4.0f, "time x %.3g",
                         ImGuiSliderFlags_Logarithmic))
    set_time_scale(scale);
  ImGui::Separator();
  // Tools: two rows of three.
  struct ToolButton {
    const char* label;
    Tool tool;
    const char* tip;
  };
  static constexpr ToolButton tools[] = {
      {"Hand", Tool::Hand, "move, turn (wheel), select; drag the square handle to resize"},
      {"Wire W", Tool::Wire, "click a battery or coil end, then another part"},
      {"Hinge H", Tool::Hinge,
       "click where two parts overlap: an axle through both (one part: through it and the board)"},
      {"Glue J", Tool::Glue, "click where two parts overlap or touch: they move as one"},
      {"String T", Tool::String,
       "click a part, then another part or the board: a string, taut as it is made; it only pulls"},
      {"Spring K", Tool::Spring,
       "click a part, then another part or the board: a spring with a damper, at rest as it is"},
  };
  const float tw = (kLeftWidth - 20 - 2 * 6) / 3;
  for (std::size_t i = 0; i < std::size(tools); ++i) {
    if (i % 3) ImGui::SameLine();
    const bool on = tool_ == tools[i].tool;
    if (on) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.55f, 0.8f, 1.0f, 1));
    if (ImGui::Button(tools[i].label, {tw, 0})) set_tool(tools[i].tool);
    if (on) ImGui::PopStyleColor();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tools[i].tip);
  }
  if ((tool_ == Tool::String || tool_ == Tool::Spring) && string_started_)
    ImGui::TextColored(ImVec4(0.1f, 0.4f, 0.8f, 1), "%s: now click its other end",
                       tool_ == Tool::Spring ? "spring" : "string");
  ImGui::Checkbox("labels", &draw_options_.labels);
  ImGui::SameLine();
  ImGui::Checkbox("poles", &draw_options_.poles);
  ImGui::SameLine();
  ImGui::Checkbox("legend", &legend_);
  ImGui::Checkbox("magnetic F", &draw_options_.magnetic_forces);
  ImGui::SameLine();
  ImGui::Checkbox("contacts", &draw_options_.contact_forces);
  ImGui::Checkbox("compass (C)", &draw_options_.compass);
  ImGui::SameLine();
  ImGui::Checkbox("snap (X)", &snap_);
  ImGui::Separator();
  panel_files();
  ImGui::End();
}

void Viewer::panel_files() {
  // File: New, Open, Save, Save as; Undo, Redo (the keys say the same).
  const float bw = (kLeftWidth - 20 - 3 * 6) / 4;
  if (ImGui::Button("New", {bw, 0})) {
    if (history_.dirty())
      ask(Popup::ConfirmNew);
    else
      new_board();
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("an empty board with a floor (Ctrl+N)");
  ImGui::SameLine();
  if (ImGui::Button("Open", {bw, 0})) ask(Popup::Open);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("a scene file or a mod folder (Ctrl+O)");
  ImGui::SameLine();
  if (ImGui::Button("Save", {bw, 0})) {
    if (untitled_)
      ask(Popup::SaveAs);
    else
      save(save_path_);
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("to %s (Ctrl+S)", untitled_ ? "a file you name" : save_path_.c_str());
  ImGui::SameLine();
  if (ImGui::Button("as..", {bw, 0})) ask(Popup::SaveAs);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Save as (Ctrl+Shift+S)");
  ImGui::TextDisabled("%s%s", untitled_ ? "untitled" : save_path_.c_str(),
                      history_.dirty() ? "  (edited)" : "");
  const float uw = (kLeftWidth - 20 - 6) / 2;
  if (!history_.can_undo()) ImGui::BeginDisabled();
  if (ImGui::Button("Undo", {uw, 0})) undo();
  if (!history_.can_undo()) ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("Ctrl+Z  %s", history_.undo_what().c_str());
  ImGui::SameLine();
  if (!history_.can_redo()) ImGui::BeginDisabled();
  if (ImGui::Button("Redo", {uw, 0})) redo();
  if (!history_.can_redo()) ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("Ctrl+Y  %s", history_.redo_what().c_str());
}

void Viewer::file_popups() {
  if (popup_ == Popup::None) return;
  int win_w = opt_.width, win_h = opt_.height;
  SDL_GetWindowSize(window_, &win_w, &win_h);
  ImGui::SetNextWindowPos({float(win_w) / 2, float(win_h) / 3}, ImGuiCond_Always, {0.5f, 0.5f});
  ImGui::SetNextWindowSize({std::min(520.0f, float(win_w) - 40), 0});
  const char* title = popup_ == Popup::Open               ? "Open a scene"
                      : popup_ == Popup::SaveAs           ? "Save as"
                      : popup_ == Popup::ConfirmNew       ? "New board"
                      : popup_ == Popup::ConfirmOverwrite ? "Replace a file"
                                                          : "Open";
  ImGui::Begin(title, nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  if (popup_ == Popup::Open || popup_ == Popup::SaveAs) {
    ImGui::TextDisabled(popup_ == Popup::Open ? "a scene file (.lua) or a mod folder"
                                              : "the scene file to write (.lua)");
    if (popup_fresh_) ImGui::SetKeyboardFocusHere();
    popup_fresh_ = false;
    ImGui::SetNextItemWidth(-1);
    ImGui::InputText("##path", path_buf_, sizeof path_buf_, ImGuiInputTextFlags_AutoSelectAll);
    if (popup_ == Popup::Open) {
      // The scene files beside the present one, to click instead of typing.
      std::error_code ec;
      fs::path dir = opt_.scene.has_parent_path() && !untitled_ ? opt_.scene.parent_path() : ".";
      if (fs::is_directory(opt_.scene, ec) && !untitled_) dir = opt_.scene;
      std::vector<std::string> files;
      for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".lua" && it->path().filename() != "mod.lua")
          files.push_back(it->path().string());
      std::sort(files.begin(), files.end());
      if (files.size() > 12) files.resize(12);
      for (const std::string& f : files)
        if (ImGui::Selectable(f.c_str()))
          std::snprintf(path_buf_, sizeof path_buf_, "%s", f.c_str());
      if (history_.dirty())
        ImGui::TextColored(ImVec4(0.75f, 0.3f, 0.05f, 1),
                           "the edits since the last save will be asked about");
    }
    if (ImGui::Button(popup_ == Popup::Open ? "Open (Enter)" : "Save (Enter)")) popup_enter();
  } else if (popup_ == Popup::ConfirmOverwrite) {
    ImGui::TextWrapped("%s is there already%s. Replace it with this board?", pending_save_.c_str(),
                       written_by_viewer(pending_save_)
                           ? ""
                           : " (written by hand: its Lua would be lost, the board's objects "
                             "written instead)");
    if (ImGui::Button("Yes, replace it (Enter)")) popup_enter();
  } else {
    ImGui::TextUnformatted(popup_ == Popup::ConfirmNew
                               ? "Start a new board? The edits since the last save are lost."
                               : "Open another scene? The edits since the last save are lost.");
    if (ImGui::Button("Yes, discard them (Enter)")) popup_enter();
  }
  ImGui::SameLine();
  if (ImGui::Button("Cancel (Esc)")) popup_ = Popup::None;
  ImGui::End();
}

void Viewer::panel_palette() {
  if (palette_problems_.empty()) {
    // Once: which entries the kit can make here (a kit without a part greys it).
    PluginRegistry scratch;
    register_native_plugins(scratch);
    for (const PaletteEntry& e : palette_entries())
      palette_problems_.push_back(check_entry(scratch, e, opt_.load));
  }
  const float top = next_panels_.empty() ? kMargin : next_panels_.back().y1 + kMargin;
  ImGui::SetNextWindowPos({kMargin, top});
  ImGui::SetNextWindowSize({kLeftWidth, 0});
  ImGui::Begin("Parts", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  // One line: the buttons' places are what tests/viewer/xvfb_mouse_test.sh clicks.
  ImGui::TextDisabled("drag onto the board, or click then click");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "bars, disks and fixed shapes: press on the board and drag to draw one "
        "to any size");
  std::string group;
  const float bw = (kLeftWidth - 20 - 6) / 2;
  int in_row = 0;
  const auto& entries = palette_entries();
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const PaletteEntry& e = entries[i];
    if (e.group != group) {
      group = e.group;
      ImGui::Spacing();
      ImGui::TextDisabled("%s", group.c_str());
      in_row = 0;
    }
    if (in_row++ % 2) ImGui::SameLine();
    const bool usable = palette_problems_[i].empty();
    const bool active = tool_ == Tool::Place && placing_ == int(i);
    if (!usable) ImGui::BeginDisabled();
    if (active) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.55f, 0.8f, 1.0f, 1));
    ImGui::Button(e.label.c_str(), {bw, 0});
    if (ImGui::IsItemActivated()) {
      tool_ = Tool::Place;
      placing_ = int(i);
      place_drag_ = true;
    }
    if (active) ImGui::PopStyleColor();
    if (!usable) ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("%s", usable ? e.tip.c_str() : palette_problems_[i].c_str());
  }
  ImGui::End();
}

void Viewer::panel_inspector() {
  int win_w = opt_.width, win_h = opt_.height;
  SDL_GetWindowSize(window_, &win_w, &win_h);
  ImGui::SetNextWindowPos({float(win_w) - kRightWidth - kMargin, kMargin});
  ImGui::SetNextWindowSize({kRightWidth, 0});
  ImGui::Begin("Part", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  World* w = world();
  if (!w || !selected_ || !w->store().alive(selected_)) {
    selected_ = {};
    ImGui::TextDisabled("click a part to see and edit it here");
    ImGui::TextDisabled("drag: move   wheel / Q E: turn");
    ImGui::TextDisabled("P: pin   W: wire   Del: remove");
    ImGui::TextDisabled("H hinge  J glue  T string  K spring");
    ImGui::TextDisabled("Ctrl+Z / Ctrl+Y: undo / redo");
    ImGui::TextDisabled("right-click: menu   F: fit view");
    ImGui::End();
    return;
  }
  const ObjectId id = selected_;
  const auto part = read_part(*w, id);
  ImGui::TextColored(ImVec4(0.43f, 0.16f, 0.63f, 1), "%s", w->describe(id).c_str());
  const auto joint_kind = w->value<EnumValue>(id, "joint");
  if (part) {
    ImGui::SameLine();
    const char* what = (*w).value<double>(id, "emf")           ? "battery"
                       : (*w).value<double>(id, "inductance")  ? "coil"
                       : (*w).value<double>(id, "capacitance") ? "capacitor"
                       : (*w).value<bool>(id, "switch_closed") ? "switch"
                                                               : material_name(material_of(*w, id));
    ImGui::TextDisabled("%s%s%s", what, part->is_static ? ", static" : "",
                        part->pinned ? ", pinned" : "");
    const double mass = (*w).value<double>(id, "mass").value_or(0);
    if (mass > 0) ImGui::Text("mass %.4g kg", mass);
    ImGui::Text("at (%.3f, %.3f) m, %.1f deg", part->centre.x, part->centre.y,
                part->angle * 180 / std::numbers::pi);
    if (const auto v = (*w).value<Vec3>(id, "velocity"))
      ImGui::Text("centre moves at %.3f m/s", length(xy(*v)));
    // A turning part (an axle, a rotor): its angular speed, which the speed
    // of its centre does not show.
    if (const auto om = (*w).value<Vec3>(id, "angular_velocity"))
      ImGui::Text("turns at %.3f rad/s = %.1f rpm", om->z, om->z * 60 / (2 * std::numbers::pi));
  } else if (joint_kind) {
    ImGui::SameLine();
    ImGui::TextDisabled("%s", joint_kind->index == 0 ? "hinge (an axle)" : "glue");
  } else if (const auto ends = spring_ends(*w, id)) {
    const bool string = (*w).value<bool>(id, "spring_slack").value_or(false);
    ImGui::SameLine();
    ImGui::TextDisabled(string ? "string (pulls only when taut)" : "spring with a damper");
    const double len = length(ends->b - ends->a);
    const double k = (*w).value<double>(id, "spring_stiffness").value_or(0);
    const double rest = (*w).value<double>(id, "spring_rest_length").value_or(0);
    ImGui::Text(string ? "ends %.2f cm apart (length %.2f cm)" : "length %.2f cm (rest %.2f cm)",
                len * 100, rest * 100);
    if (string && len <= rest)
      ImGui::Text("slack: pulls with nothing");
    else
      ImGui::Text("pulls with %.3g N", k * (len - rest));
  } else if ((*w).value<ObjectId>(id, "wire_from")) {
    ImGui::SameLine();
    ImGui::TextDisabled("wire");
  }
  if (const auto emf = (*w).value<double>(id, "emf")) ImGui::Text("battery %.3g V", *emf);
  if (const auto i = (*w).value<double>(id, "current")) ImGui::Text("current %.4g A", *i);
  if (const auto q = (*w).value<double>(id, "plate_charge")) ImGui::Text("charge %.4g C", *q);
  if (const auto c = (*w).value<bool>(id, "switch_closed"))
    ImGui::Text("switch %s", *c ? "closed" : "open");
  if ((*w).value<bool>(id, "powered").value_or(false))
    ImGui::TextColored(ImVec4(0.8f, 0.55f, 0, 1), "powered");
  if (const auto q = (*w).value<double>(id, "pole_strength"); q && *q != 0)
    ImGui::Text("poles %.3g A m, north at %s end", std::abs(*q), *q > 0 ? "+x" : "-x");
  if (part && !part->is_static) {
    bool pinned = part->pinned;
    if (ImGui::Checkbox("pinned to the board (P)", &pinned))
      note(edit("pin " + w->describe(id), [&] { return editor_.set_pinned(id, pinned); }).message);
  }
  {
    // A plot of any number this part has: pick it, then "plot".
    static int pick = 0;
    std::vector<std::string> numbers;
    for (PropertyId p = 0; p < w->properties().size(); ++p)
      if (w->store().has(id, p) && std::holds_alternative<double>(w->store().get(id, p)))
        numbers.push_back(w->properties().def(p).name);
    if (!numbers.empty()) {
      pick = std::clamp(pick, 0, int(numbers.size()) - 1);
      ImGui::SetNextItemWidth(150);
      if (ImGui::BeginCombo("##plotprop", numbers[std::size_t(pick)].c_str())) {
        for (int k = 0; k < int(numbers.size()); ++k)
          if (ImGui::Selectable(numbers[std::size_t(k)].c_str(), k == pick)) pick = k;
        ImGui::EndCombo();
      }
      ImGui::SameLine();
      if (ImGui::Button("plot")) plot(id, numbers[std::size_t(pick)]);
    }
  }
  if (part) {
    if (ImGui::Button("turn +15"))
      note(edit("turn " + w->describe(id), [&] { return editor_.rotate(id, kTurnStep); }).message);
    ImGui::SameLine();
    if (ImGui::Button("turn -15"))
      note(edit("turn " + w->describe(id), [&] { return editor_.rotate(id, -kTurnStep); }).message);
    ImGui::SameLine();
  }
  if (ImGui::Button("remove")) {
    const EditResult r = edit("remove " + w->describe(id), [&] { return editor_.remove(id); });
    note(r.message, !r.ok);
    selected_ = hovered_ = {};
    ImGui::End();
    return;
  }
  if (editor_.electrical(id) && ImGui::Button("wire from here")) {
    tool_ = Tool::Wire;
    wire_start_ = id;
    wire_start_at_ = part ? part->centre : Vec2{};
  }
  // Material: from the kit's list (density, mass, friction, bounce, conduction).
  if (part && !part->is_static && (*w).value<double>(id, "density")) {
    const char* now = material_name(material_of(*w, id));
    ImGui::SetNextItemWidth(kRightWidth - 90);
    if (ImGui::BeginCombo("material", now)) {
      for (const Editor::MaterialDef& m : Editor::materials())
        if (ImGui::Selectable(m.name, std::string(m.name) == now)) {
          const std::string name = m.name;
          const EditResult r = edit("material of " + w->describe(id),
                                    [&] { return editor_.set_material(id, name); });
          note(r.message, !r.ok);
        }
      ImGui::EndCombo();
    }
  }
  // Every property, editable: Enter (or leaving the field) sets it; the
  // registry's bounds are checked and a refused value is a message.
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::CollapsingHeader("properties")) {
    const PropertyRegistry& reg = w->properties();
    // Scrolls within a third of the window, so that a small window keeps its board.
    if (ImGui::BeginTable(
            "props", 2,
            ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_ScrollY,
            {0, std::max(120.0f, float(win_h) * 0.34f)})) {
      ImGui::TableSetupColumn("name", ImGuiTableColumnFlags_WidthFixed, 112);
      ImGui::TableSetupColumn("value", ImGuiTableColumnFlags_WidthStretch);
      for (PropertyId p = 0; p < reg.size(); ++p) {
        if (!w->store().has(id, p)) continue;
        const PropertyDef& def = reg.def(p);
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(def.name.c_str());
        if (ImGui::IsItemHovered()) {
          std::string tip = def.doc;
          char buf[96];
          if (!def.unit.empty()) tip += "\nunit: " + def.unit;
          if (def.min || def.max) {
            std::snprintf(buf, sizeof buf, "\nrange: %s%g .. %g", def.min_exclusive ? "> " : "",
                          def.min.value_or(-HUGE_VAL), def.max.value_or(HUGE_VAL));
            tip += buf;
          }
          ImGui::SetTooltip("%s", tip.c_str());
        }
        ImGui::TableNextColumn();
        ImGui::SetNextItemWidth(-1);
        const std::string label = "##" + def.name;
        const PropertyValue v = w->store().get(id, p);
        std::optional<PropertyValue> to;
        const std::string fmt = "%.6g" + (def.unit.empty() ? "" : " " + def.unit);
        switch (def.kind) {
          case PropertyKind::Number: {
            double d = std::get<double>(v);
            if (ImGui::InputDouble(label.c_str(), &d, 0, 0, fmt.c_str(),
                                   ImGuiInputTextFlags_EnterReturnsTrue))
              to = d;
            break;
          }
          case PropertyKind::Integer: {
            std::int64_t i = std::get<std::int64_t>(v);
            if (ImGui::InputScalar(label.c_str(), ImGuiDataType_S64, &i, nullptr, nullptr, nullptr,
                                   ImGuiInputTextFlags_EnterReturnsTrue))
              to = i;
            break;
          }
          case PropertyKind::Bool: {
            bool b = std::get<bool>(v);
            if (ImGui::Checkbox(label.c_str(), &b)) to = b;
            break;
          }
          case PropertyKind::Vec3: {
            Vec3 x = std::get<Vec3>(v);
            double c[3] = {x.x, x.y, x.z};
            if (ImGui::InputScalarN(label.c_str(), ImGuiDataType_Double, c, 3, nullptr, nullptr,
                                    "%.4g", ImGuiInputTextFlags_EnterReturnsTrue))
              to = Vec3{c[0], c[1], c[2]};
            break;
          }
          case PropertyKind::Quat: {
            double deg = angle_z(std::get<Quat>(v)) * 180 / std::numbers::pi;
            if (ImGui::InputDouble(label.c_str(), &deg, 0, 0, "%.3f deg",
                                   ImGuiInputTextFlags_EnterReturnsTrue))
              to = Quat::from_angle_z(deg * std::numbers::pi / 180);
            break;
          }
          case PropertyKind::Enum: {
            const int now = std::get<EnumValue>(v).index;
            const char* shown = now >= 0 && std::size_t(now) < def.enum_values.size()
                                    ? def.enum_values[std::size_t(now)].c_str()
                                    : "?";
            if (ImGui::BeginCombo(label.c_str(), shown)) {
              for (std::size_t k = 0; k < def.enum_values.size(); ++k)
                if (ImGui::Selectable(def.enum_values[k].c_str(), int(k) == now) && int(k) != now)
                  to = EnumValue{std::int32_t(k)};
              ImGui::EndCombo();
            }
            break;
          }
          case PropertyKind::String: {
            char buf[256];
            std::snprintf(buf, sizeof buf, "%s", std::get<std::string>(v).c_str());
            if (ImGui::InputText(label.c_str(), buf, sizeof buf,
                                 ImGuiInputTextFlags_EnterReturnsTrue))
              to = std::string(buf);
            break;
          }
          case PropertyKind::Ref:
          case PropertyKind::RefList:
            ImGui::TextUnformatted(value_text(*w, p, v).c_str());
            break;
        }
        if (to) {
          const std::string name = def.name;
          const PropertyValue value = *to;
          const EditResult r = edit("set " + w->describe(id) + "." + name,
                                    [&] { return editor_.set_property(id, name, value); });
          if (!r.ok) note(r.message, true);
        }
      }
      ImGui::EndTable();
    }
  }
  ImGui::End();
}

void Viewer::panel_resolvers() {
  int win_w = opt_.width, win_h = opt_.height;
  SDL_GetWindowSize(window_, &win_w, &win_h);
  const float top = next_panels_.empty() ? kMargin : next_panels_.back().y1 + kMargin;
  ImGui::SetNextWindowPos({float(win_w) - kRightWidth - kMargin, top});
  ImGui::SetNextWindowSize({kRightWidth, 0});
  ImGui::Begin("Stages", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  World* w = world();
  if (!w) {
    ImGui::End();
    return;
  }
  ImGui::Text("%.3f ms per step, %d steps this frame", step_ms_, steps_last_frame_);
  // Time bars: each stage's share of a step, coloured by kind.
  double most = 1e-6;
  for (const StageBar& b : bars_) most = std::max(most, b.ms);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float width = kRightWidth - 20;
  for (const StageBar& b : bars_) {
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float h = ImGui::GetTextLineHeight();
    dl->AddRectFilled(p, {p.x + width, p.y + h}, IM_COL32(232, 235, 240, 255), 3);
    dl->AddRectFilled(p, {p.x + std::max(2.0f, float(b.ms / most) * width), p.y + h},
                      kind_colour(b.kind) & 0x90FFFFFF, 3);
    char label[128];
    std::snprintf(label, sizeof label, "%s  %.3f ms", b.name.c_str(), b.ms);
    dl->AddText({p.x + 4, p.y}, IM_COL32(20, 24, 32, 255), label);
    ImGui::Dummy({width, h + 1});
  }
  // Swaps: a resolver with alternatives (StageInfo::provides) can be swapped live.
  bool any = false;
  for (const std::string& stage : w->active_stages()) {
    const auto at = stage.find('@');
    const std::string plugin = stage.substr(0, at),
                      area = at == std::string::npos ? "" : stage.substr(at + 1);
    // By what plugins provide: ODE's `rigid_body` lists rigid_body.box2d.
    const std::vector<std::string> alternatives = swap_alternatives(*registry_, plugin);
    if (alternatives.empty()) continue;
    const PluginDef* def = registry_->find(plugin);
    if (!any) {
      ImGui::Separator();
      ImGui::TextDisabled("swap live");
    }
    any = true;
    ImGui::SetNextItemWidth(width * 0.6f);
    const std::string label = provided(*def) + (area.empty() ? "" : " @" + area) + "##" + stage;
    if (ImGui::BeginCombo(label.c_str(), plugin.c_str())) {
      for (const std::string& alt : alternatives)
        if (ImGui::Selectable(alt.c_str(), alt == plugin) && alt != plugin) swap(area, plugin, alt);
      ImGui::EndCombo();
    }
  }
  if (!event_log_.empty()) {
    ImGui::Separator();
    ImGui::TextDisabled("events");
    for (const std::string& line : event_log_) ImGui::TextUnformatted(line.c_str());
  }
  ImGui::End();
}

void Viewer::panel_messages() {
  // Recent messages float at the bottom of the play area, errors in red.
  if (toasts_.empty()) return;
  float x0, y0, x1, y1;
  play_rect(x0, y0, x1, y1);
  int win_w = opt_.width, win_h = opt_.height;
  SDL_GetWindowSize(window_, &win_w, &win_h);
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  float y = float(win_h) - 10;
  for (auto it = toasts_.rbegin(); it != toasts_.rend(); ++it) {
    const float age = float(clock_ - it->born);
    const float alpha = std::clamp((float(kToastSeconds) - age) / 1.5f, 0.0f, 1.0f);
    const ImVec2 size = ImGui::CalcTextSize(it->text.c_str(), nullptr, false, x1 - x0 - 20);
    y -= size.y + 8;
    const ImVec2 p{x0 + 8, y};
    dl->AddRectFilled({p.x - 6, p.y - 3}, {p.x + size.x + 6, p.y + size.y + 3},
                      it->error ? IM_COL32(255, 232, 232, int(235 * alpha))
                                : IM_COL32(250, 250, 252, int(235 * alpha)),
                      4);
    dl->AddText(ImGui::GetFont(), ImGui::GetFontSize(), p,
                it->error ? IM_COL32(170, 20, 20, int(255 * alpha))
                          : IM_COL32(30, 34, 44, int(255 * alpha)),
                it->text.c_str(), nullptr, x1 - x0 - 20);
  }
}

void Viewer::panel_error() {
  if (load_error_.empty()) return;
  int win_w = opt_.width, win_h = opt_.height;
  SDL_GetWindowSize(window_, &win_w, &win_h);
  const float w = std::min(640.0f, float(win_w) - 40);
  ImGui::SetNextWindowPos({float(win_w) / 2, float(win_h) / 3}, ImGuiCond_Always, {0.5f, 0.5f});
  ImGui::SetNextWindowSize({w, 0});
  ImGui::PushStyleColor(ImGuiCol_TitleBg, ImVec4(0.85f, 0.2f, 0.2f, 1));
  ImGui::PushStyleColor(ImGuiCol_TitleBgActive, ImVec4(0.85f, 0.2f, 0.2f, 1));
  ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0.1f, 0.1f, 0.12f, 1));
  ImGui::Begin(scene_ ? "The scene file has an error (the world as it was goes on)"
                      : "The scene cannot be loaded",
               nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  remember_panel();
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(ImVec4(0.7f, 0.05f, 0.05f, 1), "%s", load_error_.c_str());
  ImGui::PopTextWrapPos();
  ImGui::TextDisabled("Fix the file and save it: it is loaded again by itself.");
  if (ImGui::Button("Load again")) reset();
  if (scene_) {
    ImGui::SameLine();
    if (ImGui::Button("Dismiss")) load_error_.clear();
  }
  ImGui::End();
  ImGui::PopStyleColor(3);
}

void Viewer::context_menu() {
  if (open_context_) {
    ImGui::OpenPopup("part menu");
    open_context_ = false;
  }
  if (!ImGui::BeginPopup("part menu")) return;
  remember_panel();
  World* w = world();
  if (w && context_part_ && w->store().alive(context_part_)) {
    const ObjectId id = context_part_;
    ImGui::TextDisabled("%s", w->describe(id).c_str());
    const auto part = read_part(*w, id);
    const std::string name = w->describe(id);
    if (part && !part->is_static &&
        ImGui::MenuItem(part->pinned ? "Unpin" : "Pin to the board", "P"))
      note(edit("pin " + name, [&] { return editor_.set_pinned(id, !part->pinned); }).message);
    if (ImGui::MenuItem("Turn 90 left"))
      note(edit("turn " + name, [&] { return editor_.rotate(id, std::numbers::pi / 2); }).message);
    if (ImGui::MenuItem("Turn 90 right"))
      note(edit("turn " + name, [&] { return editor_.rotate(id, -std::numbers::pi / 2); }).message);
    if (ImGui::MenuItem("Hinge here", "H")) {
      const EditResult r =
          edit("hinge", [&] { return editor_.hinge_at(context_at_, 4 / camera_.scale); });
      note(r.message, !r.ok);
    }
    if (ImGui::MenuItem("Glue here", "J")) {
      const EditResult r =
          edit("glue", [&] { return editor_.glue_at(context_at_, 4 / camera_.scale); });
      note(r.message, !r.ok);
    }
    if (editor_.electrical(id) && ImGui::MenuItem("Wire from here", "W")) {
      tool_ = Tool::Wire;
      wire_start_ = id;
      wire_start_at_ = context_at_;
    }
    if (ImGui::MenuItem("Remove", "Del")) {
      const EditResult r = edit("remove " + name, [&] { return editor_.remove(id); });
      note(r.message, !r.ok);
      selected_ = hovered_ = {};
    }
  } else if (w) {
    ImGui::TextDisabled("put a part here");
    for (const PaletteEntry& e : palette_entries())
      if (ImGui::MenuItem(e.label.c_str())) drop_part(e, context_at_);
  }
  ImGui::EndPopup();
}

}  // namespace alloy::viewer
