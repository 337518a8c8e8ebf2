// The viewer: an SDL2 window onto the 2D play area in which a player builds
// and changes contraptions while they run (`alloy view SCENE`).
//
// One frame:
//   input     scripted events are pushed (SDL_PushEvent), then every SDL
//             event goes to the panels (Dear ImGui) or, over the play area,
//             to the tools (hand, wire, place); tools edit the world through
//             the Editor, between steps
//   simulate  as many fixed steps as the frame's time times the time scale
//             asks for; what the hand holds is put back before each step
//   sound     the sound resolver's new samples go to SDL audio
//   draw      the play area (scene_draw), then the panels; present
//
// Headless (`--screenshot`, `--headless`): SDL's dummy video driver and the
// software renderer, a fixed 1/60 s per frame, no audio: the same frames on
// every machine, with or without a display.
//
// Bad input never ends the viewer: a scene that fails to load is shown with
// its file and line (and loaded again when the file changes), a refused edit
// is a message, a step that throws is reported and the world paused.
#pragma once

#include <SDL.h>

#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/viewer/audio_out.hpp"
#include "apps/viewer/camera.hpp"
#include "apps/viewer/editor.hpp"
#include "apps/viewer/history.hpp"
#include "apps/viewer/input_script.hpp"
#include "apps/viewer/palette.hpp"
#include "apps/viewer/png_writer.hpp"
#include "apps/viewer/scene_draw.hpp"
#include "apps/viewer/viewer_options.hpp"
#include "lua/scene_loader.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/replay.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {

/// What a click on the play area does. Hinge, Glue: join the parts under
/// the click (or the part and the board). String: two clicks, one per end.
enum class Tool { Hand, Wire, Place, Hinge, Glue, String, Spring };

class Viewer {
 public:
  /// Opens the window (throws std::runtime_error if SDL cannot) and loads the
  /// scene (a scene that fails is shown, not thrown).
  explicit Viewer(ViewerOptions options);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  /// Runs frames until the window closes or `frames` have run, then writes
  /// the screenshot and the saved scene if asked. Returns an exit code.
  int run(std::ostream& out, std::ostream& err);
  /// One frame (input, simulate, sound, draw). False once the player quits.
  bool frame();

  // --- for scripts and tests ----------------------------------------------------
  /// Pushes a mouse event at a play-area point (m) onto SDL's queue; it is
  /// handled in the next frame exactly like the player's.
  void push_mouse(Uint32 type, Vec2 at, Uint8 button = SDL_BUTTON_LEFT);
  void push_key(SDL_Keycode key, Uint16 mod = KMOD_NONE);
  void push_wheel(int notches);
  void add_script(std::vector<ScriptEvent> events);
  /// Draws the present state again (no input, no step) and returns the picture.
  Image render_image();
  /// Whether a window point lies on a panel (the play area is not there).
  bool over_panel(float x, float y) const;

  World* world() { return scene_ ? scene_->world.get() : nullptr; }
  const lua::LoadedScene* scene() const { return scene_.get(); }
  const Camera& camera() const { return camera_; }
  Editor& editor() { return editor_; }
  /// Empty if the scene loaded; else the error with file and line.
  const std::string& load_error() const { return load_error_; }
  /// Messages shown to the player so far (refused edits, drops, errors), oldest first.
  const std::vector<std::string>& messages() const { return log_; }
  /// Events the world published since the scene was loaded, by type.
  std::size_t event_count(const std::string& type) const;
  std::uint64_t frame_count() const { return frames_; }
  const AudioOut& audio() const { return audio_; }

  bool paused() const { return paused_; }
  void set_paused(bool p) { paused_ = p; }
  /// The help overlay (F1 or ?): the tools and keys, over the board.
  bool help_shown() const { return help_; }
  /// Meter probes (key A on a part): each draws its live reading beside its
  /// part. The readings as drawn, one per probe ("battery: 0.487 A").
  std::vector<std::string> probe_readings();
  const std::vector<ObjectId>& probes() const { return probes_; }
  /// Plots a number property of a part over time: one sample after each
  /// step, the last `seconds` of them kept. False if the part has no such
  /// number. plot_samples() are the samples, oldest first.
  bool plot(ObjectId part, const std::string& property, double seconds = 5);
  const std::vector<float>& plot_samples() const { return plot_samples_; }
  void step_once() { single_steps_ += 1; }
  void set_time_scale(double s);
  double time_scale() const { return time_scale_; }
  /// Loads the scene file again (the contraption as the file says).
  void reset();
  /// Saves the world as a scene; false (with the reason in messages) if it cannot.
  bool save(const std::filesystem::path& path);
  /// Makes a palette part at `at` and moves it out of any part it lands in.
  EditResult drop_part(const PaletteEntry& entry, Vec2 at);
  /// Swaps plugin `from` for `to` in `area` ("" everywhere) between steps.
  EditResult swap(const std::string& area, const std::string& from, const std::string& to);
  Tool tool() const { return tool_; }
  void set_tool(Tool t);
  ObjectId selected() const { return selected_; }
  void select(ObjectId id) {
    selected_ = id;
    many_.clear();
  }
  /// Everything selected: the multi-selection (shift-click adds or takes a
  /// part away, shift-drag on the board draws a rubber band), else the one
  /// selected object. Delete, Ctrl+C and dragging act on all of it.
  std::vector<ObjectId> selection() const;
  /// Snapping (key X, or the toolbar): a carried part's end goes onto
  /// another part's end within 8 pixels, else its centre onto the grid.
  bool snapping() const { return snap_; }
  void set_snapping(bool on) { snap_ = on; }
  /// The grid a carried part snaps to, m.
  static constexpr double kSnapGrid = 0.01;
  /// Compass needles over the board (key C): the magnetic field's direction.
  bool compass() const { return draw_options_.compass; }
  /// The legend (the toolbar's checkbox): what each colour and mark means.
  bool legend() const { return legend_; }
  void set_legend(bool on) { legend_ = on; }
  /// What the clipboard holds (Ctrl+C), how many parts.
  std::size_t clipboard_parts() const { return clipboard_.parts; }
  /// The tooltip drawn for the part under the mouse ("" none), as drawn.
  const std::string& tooltip() const { return tooltip_; }

  // --- files and history --------------------------------------------------------
  /// An empty board with a floor (a scene of its own, "untitled" until saved).
  void new_board();
  /// Loads another scene file or mod folder; false (with the reason in
  /// messages, the present world kept) if it cannot.
  bool open(const std::filesystem::path& path);
  /// Where Save writes (Save as changes it): a scene file the viewer wrote is
  /// saved over; any other scene file or mod folder is saved next to it, as
  /// `<its name>_saved.lua` in the same folder (a scene written by hand is
  /// never overwritten by Save).
  const std::string& save_path() const { return save_path_; }
  /// Where Save writes for a board opened from `scene` (see save_path).
  static std::filesystem::path save_path_for(const std::filesystem::path& scene);
  /// True if `file` begins as the scene writer begins what it writes.
  static bool written_by_viewer(const std::filesystem::path& file);
  /// The file a Save as waits to overwrite until the player says yes ("" none).
  const std::string& asking_to_overwrite() const {
    return popup_ == Popup::ConfirmOverwrite ? pending_save_ : kNone;
  }
  /// A Save as popup is open, waiting for a path.
  bool asking_for_path() const { return popup_ == Popup::SaveAs; }
  /// True for a New board that has not been saved yet.
  bool untitled() const { return untitled_; }
  /// Undo / redo the last edit (Ctrl+Z, Ctrl+Y); false if there was none.
  bool undo();
  bool redo();
  History& history() { return history_; }
  /// Records the world before an edit (for undo); every edit the player
  /// makes goes through it. Runs `f`; a refused edit leaves no record.
  template <class F>
  EditResult edit(const std::string& what, F&& f) {
    World* w = world();
    if (!w) return EditResult::refused("no world");
    history_.record(*w, what);
    EditResult r = f();
    if (!r.ok) history_.forget_last();
    return r;
  }
  /// Resize handle of the selected part: where it is drawn (m), if any.
  std::optional<Vec2> resize_handle() const;

 private:
  void init_sdl();
  void init_imgui();
  void load();
  void note(const std::string& message, bool error = false);
  void handle(const SDL_Event& e);
  void on_press(Vec2 at, Uint8 button, Uint16 mod);
  void on_release(Vec2 at, Uint8 button);
  void on_key(SDL_Keycode key, Uint16 mod);
  void pump_script();
  /// A script's `set`: the selected object's property as the inspector sets
  /// it; "" or why it was refused.
  std::string script_set(const std::string& property, const std::string& text);
  /// The window's title: the file's name, " *" with edits not saved.
  void update_title();
  std::string title_;
  void simulate(double frame_seconds);
  void step_world();
  void watch_scene_file();
  void poll_mods();
  void draw(bool capture, Image* image);
  void draw_panels();
  void panel_help();
  void draw_scale_bar(ImDrawList* dl);
  void draw_legend(ImDrawList* dl);
  void draw_tooltip(World& w);
  /// Ctrl+C and Ctrl+V.
  void copy_selection();
  void paste_clipboard();
  void panel_toolbar();
  void panel_palette();
  void panel_inspector();
  void panel_resolvers();
  void panel_messages();
  void panel_error();
  void context_menu();
  void panel_files();
  void file_popups();
  void draw_tool_feedback(ImDrawList* dl, World& w);
  void on_drag(Vec2 at);
  void fit_view();
  void play_rect(float& x0, float& y0, float& x1, float& y1) const;
  void remember_panel();

  ViewerOptions opt_;
  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  bool imgui_ready_ = false;
  ImGuiContext* imgui_ = nullptr;
  std::unique_ptr<PluginRegistry> registry_;  // the scene's (its mods register here)
  std::unique_ptr<lua::LoadedScene> scene_;   // declared after: destroyed first
  /// --record: hears the world's every input and step (World's input
  /// observer); goes before the world it records.
  std::unique_ptr<Recorder> recorder_;
  int record_part_ = 0;      ///< worlds recorded so far (each load starts the next part)
  std::string record_path_;  ///< the file of the part under way
  bool finish_recording();   ///< writes it and stops; false if the file could not be written
  std::string load_error_;
  std::filesystem::file_time_type scene_mtime_{};
  double last_watch_ = -1;
  Editor editor_;
  Camera camera_;
  bool fitted_ = false;
  AudioOut audio_;
  bool muted_ = false;
  std::vector<ObjectId> probes_;
  ObjectId plot_part_;               ///< the part plotted (none: no plot)
  std::string plot_property_;        ///< the number property plotted
  double plot_seconds_ = 5;          ///< the rolling window, s
  std::vector<float> plot_samples_;  ///< one per step, oldest first
  void sample_plot();
  void panel_plot();   ///< parts with a meter probe on them (key A)
  bool help_ = false;  ///< the help overlay is open (F1 or ?)
  bool audio_failed_ = false;

  // Running.
  bool paused_ = false;
  int single_steps_ = 0;
  double time_scale_ = 1;
  double accumulator_ = 0;
  int failing_steps_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t last_ticks_ = 0;
  double clock_ = 0;  // animation clock, s
  bool quit_ = false;

  // Input.
  std::vector<ScriptEvent> script_;
  std::size_t script_next_ = 0;
  float mouse_x_ = -1, mouse_y_ = -1;
  float panels_saw_x_ = -1, panels_saw_y_ = -1;  ///< the pointer as the panels last saw it
  bool mouse_down_[3] = {false, false, false}, mouse_pressed_[3] = {false, false, false};
  /// A button change the panels take (for_panels) since they last drew, or
  /// a click of theirs whose release they have not drawn yet: the pointer
  /// stays put until they have.
  bool panels_owed_ = false;
  /// Whether `e` waits for the next frame, so that the panels see each
  /// button change where it happened (Viewer::frame).
  bool waits_for_panels(const SDL_Event& e);
  /// Whether a button change at (x, y) is the panels' to take: over a panel,
  /// with a popup open, or while Dear ImGui holds the mouse (a drag begun on
  /// a panel).
  bool for_panels(float x, float y, bool popup) const;
  /// The window is mapped once the panels stand still (Viewer::frame).
  bool shown_ = false;
  bool panning_ = false;
  Tool tool_ = Tool::Hand;
  int placing_ = -1;  // palette entry
  bool place_drag_ = false;
  ObjectId selected_, hovered_, wire_start_;
  std::vector<ObjectId> many_;  ///< the multi-selection (two or more), else empty
  bool band_ = false;           ///< a rubber band is being drawn (shift-drag on the board)
  Vec2 band_from_;              ///< its first corner, m
  bool snap_ = false;
  bool legend_ = true;
  Editor::Clipboard clipboard_;
  std::string tooltip_;
  Vec2 wire_start_at_;
  ObjectId context_part_;
  Vec2 context_at_;
  bool open_context_ = false;
  struct Rect {
    float x0, y0, x1, y1;
    bool operator==(const Rect&) const = default;
  };
  std::vector<Rect> panels_, next_panels_;
  std::string save_path_;
  bool untitled_ = false;

  // Files and history.
  History history_;
  std::uint64_t synced_changes_ = 0;
  enum class Popup { None, Open, SaveAs, ConfirmNew, ConfirmOpen, ConfirmOverwrite };
  std::string pending_save_;  // Save as: the existing file to overwrite once confirmed
  static inline const std::string kNone;
  Popup popup_ = Popup::None;
  bool popup_fresh_ = false;  // opened this frame: focus its text field
  char path_buf_[512] = {};
  std::string pending_open_;
  void ask(Popup p);
  void popup_enter();

  // Joining and resizing.
  ObjectId string_start_;
  Vec2 string_start_at_;
  bool string_started_ = false;
  ObjectId resizing_;   // the part whose handle is held
  ObjectId drawing_;    // a bar or disk just put down, drawn to size while the press is held
  Vec2 draw_from_;      // where its press was, m
  bool drawn_ = false;  // the drag went far enough to size it
  /// Sizes the part being drawn by the drag from draw_from_ to `at`: a bar
  /// from the press to the mouse, a disk of the drag's radius about the press.
  void on_draw(Vec2 at);
  std::string fields_of_;  // inspector: the object whose fields are being typed in

  // What happened.
  std::vector<std::string> log_;
  struct Toast {
    std::string text;
    double born;
    bool error;
  };
  std::deque<Toast> toasts_;
  std::vector<std::pair<std::string, std::size_t>> event_counts_;
  std::deque<std::string> event_log_;
  std::vector<Ring> rings_;
  std::string step_error_;

  // Profile per frame: exponential averages of each stage's time per step.
  struct StageBar {
    std::string name;
    StageKind kind;
    double ms = 0;
    double seconds_seen = 0;
    std::uint64_t runs_seen = 0;
  };
  std::vector<StageBar> bars_;
  std::uint64_t profile_steps_seen_ = 0;
  double step_ms_ = 0;
  int steps_last_frame_ = 0;

  DrawOptions draw_options_;  // contact forces: the world demands impulses (step_world)
  std::vector<std::string> palette_problems_;  // per entry: "" or why it cannot be made
};

}  // namespace alloy::viewer
