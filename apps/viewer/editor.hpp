// The player's hand: every change a player makes to a running contraption
// (pick up, carry, turn and drop a part; pin and unpin; wire two parts;
// remove a part) as edits through the World's editing API, made between
// steps. Bad edits are refused with a message, never thrown: the viewer shows
// the message and the world goes on. No SDL here, so that tests can drive it.
#pragma once

#include <string>
#include <vector>

#include "apps/viewer/part_geometry.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {

/// What an edit did: ok, or refused (and why); `message` is for the player.
struct EditResult {
  bool ok = true;
  std::string message;
  static EditResult refused(std::string why) { return {false, std::move(why)}; }
};

class Editor {
 public:
  /// Deeper than this, a dropped part is inside another and is moved out, m.
  static constexpr double kOverlapTolerance = 0.003;

  explicit Editor(World* world = nullptr) : world_(world) {}
  /// A new world (after a reload): forgets what was held.
  void attach(World* world);

  /// The part under `point` (m), or a null id: moving parts before static
  /// ones, then the smallest. `margin` (m) makes thin parts easier to hit.
  ObjectId pick(Vec2 point, double margin = 0) const;

  // --- carrying ---------------------------------------------------------------
  /// Picks up `part` at `at`, with every part joined to it (a pinned wheel
  /// with its pin, a rotor with its spokes); they move as one.
  EditResult grab(ObjectId part, Vec2 at);
  /// Picks up several parts at once (a multi-selection), each with what is
  /// joined to it; the first is the one the hand took.
  EditResult grab_all(const std::vector<ObjectId>& parts, Vec2 at);
  /// Where the hand is now.
  void carry_to(Vec2 at) { target_ = at; }
  /// Turns what is held about the hand, rad (counter-clockwise > 0).
  void turn(double radians) { turn_ += radians; }
  /// Puts what is held where the hand is, at rest. The viewer calls it before
  /// every step while carrying (between steps), and once per frame.
  void hold();
  /// Lets go. A part dropped inside another is moved to the nearest free
  /// place (or back where it was picked up); the message says so.
  EditResult drop();
  bool carrying() const { return !held_.empty(); }
  /// Whether what is held was moved or turned since it was picked up.
  bool moved() const { return !(grab_point_ == target_) || turn_ != 0; }
  ObjectId carried() const { return carrying() ? held_.front().id : ObjectId{}; }
  /// Where the hand took hold, and where it is now (for drawing).
  Vec2 hand() const { return target_; }

  /// Where the hand should be so that what is held snaps (the snap toggle):
  /// an end of the carried part (either end along its own x axis) onto the
  /// nearest end of another part within `reach` (m); else its centre onto
  /// the grid of `grid` (m). Not carrying: `hand` as it is.
  Vec2 snapped(Vec2 hand, double grid, double reach) const;

  // --- many parts: the rubber band, copy and paste -----------------------------
  /// The parts that can move (not static) whose centres lie in the box with
  /// corners `a` and `b` (m), in slot order.
  std::vector<ObjectId> parts_in(Vec2 a, Vec2 b) const;
  /// Removes several parts at once (each with its joints, wires and springs).
  EditResult remove_all(const std::vector<ObjectId>& parts);
  /// A copy of some parts with every property they carry, and of the joints,
  /// wires and springs among them: each object that refers only to copied
  /// parts (a hinge, glue or spring to the board comes along too).
  struct Clipboard {
    struct Object {
      std::string name;  ///< "" for an unnamed object
      std::vector<std::pair<PropertyId, PropertyValue>> values;
    };
    std::vector<ObjectId> from;   ///< the objects copied (refs among them are remapped)
    std::vector<Object> objects;  ///< their names and values, in the same order
    Vec2 centre;                  ///< the mean centre of the copied parts, m
    std::size_t parts = 0;        ///< how many of the objects are parts
    bool empty() const { return objects.empty(); }
  };
  Clipboard copy(const std::vector<ObjectId>& parts) const;
  /// Makes the clipboard's objects again, moved by `offset` (m): new names
  /// (name_2, ...), references among them pointing at the new objects, each
  /// checked as the world checks any object. `made`: the new parts (not the
  /// joints, wires and springs).
  EditResult paste(const Clipboard& clip, Vec2 offset, std::vector<ObjectId>* made = nullptr);

  // --- other edits ------------------------------------------------------------
  EditResult set_pinned(ObjectId part, bool pinned);
  EditResult toggle_pin(ObjectId part);
  /// Turns a part (and what is joined to it) in place about its centre.
  EditResult rotate(ObjectId part, double radians);
  /// A wire from part a to part b; `at_a` / `at_b` choose the terminal of a
  /// two-terminal part (a battery's -x end is terminal 0, +x end terminal 1).
  EditResult connect_wire(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b);
  /// Removes a part with the joints and wires that hold it.
  EditResult remove(ObjectId part);
  /// Moves a part (with what is joined to it) out of any part it lies inside.
  EditResult settle(ObjectId part);

  // --- joining parts (the rigid body's joints: hinge and fixed) --------------
  /// Every part under `point`, the one a click means first: moving parts
  /// before static ones, then the smallest.
  std::vector<ObjectId> pick_all(Vec2 point, double margin = 0) const;
  /// A hinge (an axle) at `at` through the two topmost parts there, or
  /// through the one part there and the board. `made`: the joint.
  EditResult hinge_at(Vec2 at, double margin = 0, ObjectId* made = nullptr);
  /// Glue at `at`: the two topmost parts there are fixed together (one part
  /// alone is fixed to the board).
  EditResult glue_at(Vec2 at, double margin = 0, ObjectId* made = nullptr);
  /// A string from part `a` at `at_a` to part `b` at `at_b` (b null: the
  /// board at `at_b`): one object, a spring that only pulls (`spring_slack`,
  /// resolvers/rigid_body/rigid_body_from_springs.hpp), as long as the
  /// distance times `slack` (>= 1; longer, it hangs slack). Its stiffness is
  /// the most the step allows on these parts (kStringFigure), so it barely
  /// stretches; the inspector edits it. `made`: it.
  EditResult string_between(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b, double slack = 1.0,
                            ObjectId* made = nullptr);
  /// A spring with a damper from part `a` at `at_a` to part `b` at `at_b`
  /// (b null: the board at `at_b`), its rest length the distance between the
  /// two points: it holds them as they are and pulls or pushes when they move.
  /// Stiffness and damping are the defaults below, editable in the inspector;
  /// a spring too stiff for the step on light parts is refused with the
  /// figures (resolvers/rigid_body/rigid_body_from_springs.hpp). `made`: it.
  EditResult spring_between(ObjectId a, Vec2 at_a, ObjectId b, Vec2 at_b, ObjectId* made = nullptr);
  /// A new spring's stiffness (N/m) and damping (N s/m): a 15 cm steel bar
  /// (118 g) hanging from one sags 6 cm and swings at about 2 Hz, dying out
  /// in a few seconds; stable at 1/240 s on parts down to 4 g.
  static constexpr double kSpringStiffness = 20, kSpringDamping = 0.05;
  /// A new string's (h w)^2 (the springs accept up to 1 with the damper's
  /// share; the tool's damper adds 2 h c / m = 2 sqrt(kStringFigure) / 3),
  /// and its stiffness when both ends are fixed or the parts very heavy, N/m.
  static constexpr double kStringFigure = 0.25, kStringMaxStiffness = 20000;
  /// The joint whose pivot lies within `margin` of `point` (m), or null.
  ObjectId pick_joint(Vec2 point, double margin) const;
  /// The spring whose line passes within `margin` of `point` (m), or null;
  /// the tenth of its length at each end does not count (a click there
  /// means the part the end lies on).
  ObjectId pick_spring(Vec2 point, double margin) const;

  // --- sizes and properties ----------------------------------------------------
  /// Resizes a part in the play area: a box to `size` (full extents along its
  /// x and y, m; its depth is kept), a disk or cylinder to radius size.x, a
  /// capsule to radius size.y / 2 and straight length size.x. Its mass follows
  /// the volume (same density). Refused below 2 mm or beyond the world's limits.
  EditResult resize(ObjectId part, Vec2 size);
  /// Sets one property from the inspector; bounds are the registry's (the
  /// message names the property, its unit and range), then the object's own
  /// checks (World::check): a value either refuses is not kept.
  EditResult set_property(ObjectId id, const std::string& property, const PropertyValue& value);
  /// The kit's materials (mods/kit/materials.lua), by name.
  struct MaterialDef {
    const char* name;
    double density, friction, restitution;
    bool conductive;
  };
  static const std::vector<MaterialDef>& materials();
  /// Makes a part of another material: its density, mass (same volume),
  /// friction, restitution and whether it conducts. Magnetism is left as it is.
  EditResult set_material(ObjectId part, const std::string& material);

  /// Whether the object is an electrical part (a wire can end on it).
  bool electrical(ObjectId id) const;
  /// Whether it has two terminals (battery, coil, resistor).
  bool two_terminal(ObjectId id) const;
  /// Parts joined to `part` through joints, itself first.
  std::vector<ObjectId> joined_group(ObjectId part) const;
  /// A name no object has yet: base, base_2, base_3, ...
  std::string unique_name(const std::string& base) const;

 private:
  struct Held {
    ObjectId id;
    Vec2 offset;   // from the hand, in the play area at grab time
    double angle;  // orientation angle at grab time
    double z;      // kept
    bool is_joint;
    bool moving;  // has a body: velocity is zeroed
  };
  bool has(ObjectId id, const char* prop) const;
  EditResult make_joint(const char* kind, ObjectId a, ObjectId b, Vec2 at, ObjectId* made);
  ObjectId joint_between(ObjectId a, ObjectId b) const;
  std::string enum_of(ObjectId id, const char* prop) const;
  void place(const std::vector<Held>& group, Vec2 hand, double turn);
  double worst_overlap(const std::vector<ObjectId>& group, std::string* with) const;
  EditResult move_out(const std::vector<Held>& group, Vec2 hand, double turn, Vec2 fallback_hand,
                      double fallback_turn);

  World* world_ = nullptr;
  std::vector<Held> held_;
  Vec2 grab_point_, target_;
  double turn_ = 0;
};

}  // namespace alloy::viewer
