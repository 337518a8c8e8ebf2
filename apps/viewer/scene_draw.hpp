// Drawing the play area with Dear ImGui's draw lists (anti-aliased polygons,
// lines and text, rendered by the SDL_Renderer backend): parts in their
// materials' colours and true shapes, static parts hatched, pins and hinges,
// magnet poles (north red, south green, as in the paper's figures), wires
// coloured and animated by their current, powered parts glowing, bells
// ringing, and optional force arrows and contact points.
#pragma once

#include <imgui.h>

#include <string>
#include <vector>

#include "apps/viewer/camera.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {

/// Colours of the picture, shared with the tests that check pixels.
namespace colour {
inline constexpr ImU32 rgb(int r, int g, int b, int a = 255) {
  return IM_COL32(r, g, b, a);
}
inline constexpr ImU32 kBackground = rgb(238, 240, 243);
inline constexpr ImU32 kGridMinor = rgb(230, 233, 237);
inline constexpr ImU32 kGridMajor = rgb(212, 216, 223);
inline constexpr ImU32 kSteel = rgb(122, 138, 160);
inline constexpr ImU32 kIron = rgb(92, 98, 110);
inline constexpr ImU32 kBrass = rgb(226, 186, 58);
inline constexpr ImU32 kBronze = rgb(176, 128, 52);
inline constexpr ImU32 kCopper = rgb(201, 110, 60);
inline constexpr ImU32 kWood = rgb(196, 150, 98);
inline constexpr ImU32 kRubber = rgb(62, 62, 70);
inline constexpr ImU32 kStaticWood = rgb(150, 112, 74);  ///< floors and walls
inline constexpr ImU32 kNorth = rgb(218, 48, 48);
inline constexpr ImU32 kSouth = rgb(36, 160, 72);
inline constexpr ImU32 kBattery = rgb(48, 54, 64);
inline constexpr ImU32 kWireIdle = rgb(90, 92, 104);
inline constexpr ImU32 kWireLive = rgb(255, 140, 0);
inline constexpr ImU32 kPowered = rgb(255, 204, 0);
inline constexpr ImU32 kLabel = rgb(110, 40, 160);  ///< the paper's annotations were purple
inline constexpr ImU32 kMagneticForce = rgb(160, 50, 200);
inline constexpr ImU32 kContactForce = rgb(230, 90, 20);
inline constexpr ImU32 kSelected = rgb(0, 150, 220);
}  // namespace colour

/// What a part is made of, from its density (the kit writes the material's
/// density on every part it makes).
enum class Material { Steel, Iron, Brass, Bronze, Copper, Wood, Rubber, Other };
Material material_of(const World& world, ObjectId id);
/// The fill colour a part is drawn in (its material's; magnets and batteries
/// have their own).
ImU32 fill_colour(const World& world, ObjectId id);

struct DrawOptions {
  bool grid = true;
  bool labels = true;
  bool wires = true;
  bool poles = true;
  bool magnetic_forces = true;  // on by default: they show why a coil pulls and a rotor turns
  bool contact_forces = false;
  bool compass = false;  ///< a grid of compass needles showing the magnetic field
};

/// A compass needle: where it stands, which way its north end points (a unit
/// vector in the play area) and the field's strength there.
struct Needle {
  Vec2 at;
  Vec2 north;
  double tesla = 0;
};
/// Needles on a grid of `spacing` pixels over the screen rectangle `width` x
/// `height`, from the magnetic_forces set's field (B of every pole). None
/// where the field is under 1 uT (a needle there would only show the noise),
/// nor with no magnetism in the world.
std::vector<Needle> compass_needles(World& world, const Camera& camera, float width, float height,
                                    float spacing = 36);
/// Below this field a compass shows nothing, T.
inline constexpr double kCompassFloor = 1e-6;

struct Highlight {
  ObjectId selected, hovered, wire_start;
  bool carrying = false;
};

/// A part that was struck and rings (drawn as fading circles).
struct Ring {
  ObjectId part;
  double born = 0;      ///< animation clock at the strike, s
  double strength = 1;  ///< 0..1
};

/// Draws the world onto `dl`. `clock` is the animation time (wall or frame
/// clock), s: wires' current flows with it.
void draw_world(ImDrawList* dl, World& world, const Camera& camera, const DrawOptions& options,
                const Highlight& highlight, double clock, const std::vector<Ring>& rings);

/// A wire as it is drawn: a quadratic curve from terminal `a` to terminal
/// `b` through `control` (it sags below the straight line).
struct WireCurve {
  Vec2 a, control, b;
};
/// The wire's curve, or nullopt if it is not a wire or an end is gone.
std::optional<WireCurve> wire_curve(const World& world, ObjectId wire);
/// The wire whose drawn curve passes within `margin` (m) of `point`, or null;
/// the tenth of the curve at each end does not count (it lies on a part).
ObjectId wire_at(const World& world, Vec2 point, double margin);

/// A label to lay out, in screen pixels (y down): the part's bounding box and
/// the text's size.
struct LabelSpot {
  float left, top, right, bottom;  ///< the part's box on screen
  float width, height;             ///< the text's
};
/// Where a label goes: its top-left corner, and whether it was moved off its
/// first place (then a thin line joins it to its part).
struct LabelPlace {
  float x, y;
  bool moved = false;
};
/// Lays labels out so that no two overlap where it can: each, in the order
/// given, takes the first free place of: centred above its part, below it,
/// right of it, left of it, then further above and below in steps of a line;
/// failing all, the place that overlaps the least.
std::vector<LabelPlace> place_labels(const std::vector<LabelSpot>& spots);

/// Where a wire ends on a part: a two-terminal part's terminal 0 at its -x
/// end, 1 at its +x end; a node part's centre.
Vec2 terminal_point(const World& world, ObjectId part, std::int64_t terminal);

}  // namespace alloy::viewer
