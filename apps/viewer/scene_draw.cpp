#include "apps/viewer/scene_draw.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "apps/viewer/engines.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "runtime/contact_set.hpp"

namespace alloy::viewer {

namespace {

constexpr double kPi = std::numbers::pi;

bool has(const World& w, ObjectId id, const char* name) {
  const auto pid = w.properties().find(name);
  return pid && w.store().has(id, *pid);
}

std::optional<std::string> enum_name(const World& w, ObjectId id, const char* name) {
  const auto pid = w.properties().find(name);
  if (!pid || !w.store().has(id, *pid)) return std::nullopt;
  const EnumValue e = std::get<EnumValue>(w.store().get(id, *pid));
  const auto& values = w.properties().def(*pid).enum_values;
  if (e.index < 0 || std::size_t(e.index) >= values.size()) return std::nullopt;
  return values[std::size_t(e.index)];
}

ImVec2 iv(ScreenPoint p) {
  return {p.x, p.y};
}

ImU32 scale_rgb(ImU32 c, float k, int alpha = -1) {
  ImVec4 v = ImGui::ColorConvertU32ToFloat4(c);
  v.x = std::clamp(v.x * k, 0.f, 1.f);
  v.y = std::clamp(v.y * k, 0.f, 1.f);
  v.z = std::clamp(v.z * k, 0.f, 1.f);
  if (alpha >= 0) v.w = alpha / 255.f;
  return ImGui::ColorConvertFloat4ToU32(v);
}

ImU32 with_alpha(ImU32 c, float a) {
  ImVec4 v = ImGui::ColorConvertU32ToFloat4(c);
  v.w = std::clamp(a, 0.f, 1.f);
  return ImGui::ColorConvertFloat4ToU32(v);
}

void fill(ImDrawList* dl, const Camera& cam, const std::vector<Vec2>& poly, ImU32 c) {
  std::vector<ImVec2> pts;
  pts.reserve(poly.size());
  for (Vec2 v : poly) pts.push_back(iv(cam.to_screen(v)));
  dl->AddConvexPolyFilled(pts.data(), int(pts.size()), c);
}

void stroke(ImDrawList* dl, const Camera& cam, const std::vector<Vec2>& poly, ImU32 c,
            float thickness) {
  std::vector<ImVec2> pts;
  pts.reserve(poly.size());
  for (Vec2 v : poly) pts.push_back(iv(cam.to_screen(v)));
  dl->AddPolyline(pts.data(), int(pts.size()), c, ImDrawFlags_Closed, thickness);
}

/// A quad of the part's own frame, [x0, x1] x [y0, y1] (m).
std::vector<Vec2> local_quad(const Part2D& p, double x0, double x1, double y0, double y1) {
  return {p.to_world({x0, y0}), p.to_world({x1, y0}), p.to_world({x1, y1}), p.to_world({x0, y1})};
}

/// The outline restricted to local x in [x0, x1] (for magnet halves of any shape).
std::vector<Vec2> slice(const Part2D& p, double x0, double x1) {
  std::vector<Vec2> out;
  const std::vector<Vec2> poly = outline(p, 48);
  const std::size_t n = poly.size();
  // Clip the convex polygon against x >= x0 and x <= x1 in the part's frame.
  std::vector<Vec2> local;
  for (Vec2 v : poly) local.push_back(p.to_local(v));
  auto clip = [](const std::vector<Vec2>& in, double bound, bool keep_above) {
    std::vector<Vec2> res;
    for (std::size_t i = 0; i < in.size(); ++i) {
      const Vec2 a = in[i], b = in[(i + 1) % in.size()];
      const bool ina = keep_above ? a.x >= bound : a.x <= bound;
      const bool inb = keep_above ? b.x >= bound : b.x <= bound;
      if (ina) res.push_back(a);
      if (ina != inb) {
        const double t = (bound - a.x) / (b.x - a.x);
        res.push_back({bound, a.y + t * (b.y - a.y)});
      }
    }
    return res;
  };
  (void)n;
  local = clip(clip(local, x0, true), x1, false);
  for (Vec2 v : local) out.push_back(p.to_world(v));
  return out;
}

void text_centred(ImDrawList* dl, ImVec2 at, ImU32 c, const char* s, float size) {
  ImFont* font = ImGui::GetFont();
  const ImVec2 sz = font->CalcTextSizeA(size, 1e9f, 0, s);
  dl->AddText(font, size, {at.x - sz.x / 2, at.y - sz.y / 2}, c, s);
}

void arrow(ImDrawList* dl, ImVec2 from, ImVec2 to, ImU32 c, float thickness) {
  const float dx = to.x - from.x, dy = to.y - from.y;
  const float len = std::sqrt(dx * dx + dy * dy);
  if (len < 2) return;
  const float ux = dx / len, uy = dy / len;
  const float head = std::min(10.f, len * 0.4f);
  const ImVec2 base{to.x - ux * head, to.y - uy * head};
  dl->AddLine(from, base, c, thickness);
  dl->AddTriangleFilled(to, {base.x - uy * head * 0.5f, base.y + ux * head * 0.5f},
                        {base.x + uy * head * 0.5f, base.y - ux * head * 0.5f}, c);
}

/// Arrow length for a force: logarithmic, so that millinewtons and newtons both show.
float arrow_length(double newtons) {
  if (!(newtons > 1e-4)) return 0;
  return float(std::clamp(18 * std::log10(newtons / 1e-4), 4.0, 140.0));
}

void draw_grid(ImDrawList* dl, const Camera& cam, ImVec2 size) {
  const Vec2 lo = cam.to_world(0, size.y), hi = cam.to_world(size.x, 0);
  for (double step : {0.1, 1.0}) {
    if (step * cam.scale < 6) continue;
    const ImU32 c = step < 0.5 ? colour::kGridMinor : colour::kGridMajor;
    for (double x = std::floor(lo.x / step) * step; x <= hi.x; x += step) {
      const float sx = cam.to_screen({x, 0}).x;
      dl->AddLine({sx, 0}, {sx, size.y}, c, 1);
    }
    for (double y = std::floor(lo.y / step) * step; y <= hi.y; y += step) {
      const float sy = cam.to_screen({0, y}).y;
      dl->AddLine({0, sy}, {size.x, sy}, c, 1);
    }
  }
}

void draw_hatch(ImDrawList* dl, const Camera& cam, const Part2D& p, ImU32 c) {
  if (p.shape != Shape2D::Box) return;
  const double step = std::max(0.03, 8 / cam.scale);
  const double hw = p.half.x, hh = p.half.y;
  // Lines y = x - k in the part's frame, clipped to the box.
  for (double k = -hw - hh + step / 2; k < hw + hh; k += step) {
    const double x0 = std::max(-hw, -hh + k), x1 = std::min(hw, hh + k);
    if (x1 <= x0) continue;
    dl->AddLine(iv(cam.to_screen(p.to_world({x0, x0 - k}))),
                iv(cam.to_screen(p.to_world({x1, x1 - k}))), c, 1.0f);
  }
}

}  // namespace

Material material_of(const World& world, ObjectId id) {
  const auto d = world.value<double>(id, "density");
  if (!d) return Material::Other;
  struct Known {
    double density;
    Material m;
  };
  // The kit's materials (mods/kit/materials.lua).
  static constexpr Known known[] = {{7850, Material::Steel},  {7870, Material::Iron},
                                    {8500, Material::Brass},  {8600, Material::Bronze},
                                    {8960, Material::Copper}, {700, Material::Wood},
                                    {1100, Material::Rubber}};
  for (const Known& k : known)
    if (std::abs(*d - k.density) < 1) return k.m;
  // Not a kit material: the nearest one by density, so that iron looks like steel.
  if (*d > 7000)
    return *d < 8200 ? Material::Steel : *d < 8700 ? Material::Brass : Material::Copper;
  if (*d < 1000) return Material::Wood;
  return Material::Other;
}

ImU32 fill_colour(const World& world, ObjectId id) {
  if (has(world, id, "emf")) return colour::kBattery;
  if (has(world, id, "inductance")) return colour::kCopper;  // a coil: its winding is what shows
  const bool is_static = world.value<bool>(id, "static").value_or(false);
  // A static part has no mass, so often no density: a conductive one is metal.
  if (is_static && !has(world, id, "density") &&
      world.value<bool>(id, "conductive").value_or(false))
    return colour::kBrass;
  switch (material_of(world, id)) {
    case Material::Steel:
      return colour::kSteel;
    case Material::Iron:
      return colour::kIron;
    case Material::Brass:
      return colour::kBrass;
    case Material::Bronze:
      return colour::kBronze;
    case Material::Copper:
      return colour::kCopper;
    case Material::Wood:
      return is_static ? colour::kStaticWood : colour::kWood;
    case Material::Rubber:
      return colour::kRubber;
    case Material::Other:
      break;
  }
  if (is_static) return colour::kStaticWood;
  // Something the kit does not make: a colour from its friction and restitution.
  const double f = world.value<double>(id, "friction").value_or(0.5);
  return colour::rgb(120 + int(60 * std::min(f, 1.0)), 150, 170);
}

std::vector<LabelPlace> place_labels(const std::vector<LabelSpot>& spots) {
  struct Box {
    float x0, y0, x1, y1;
  };
  auto overlap = [](const Box& a, const Box& b) {
    const float w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
    const float h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    return w > 0 && h > 0 ? w * h : 0.0f;
  };
  std::vector<Box> taken;
  std::vector<LabelPlace> out;
  constexpr float kGap = 3;
  for (const LabelSpot& s : spots) {
    const float w = s.width, h = s.height, cx = (s.left + s.right) / 2 - w / 2;
    const float cy = (s.top + s.bottom) / 2 - h / 2;
    std::vector<LabelPlace> tries = {{cx, s.top - kGap - h, false},
                                     {cx, s.bottom + kGap, true},
                                     {s.right + kGap + 2, cy, true},
                                     {s.left - kGap - 2 - w, cy, true}};
    for (int k = 1; k <= 4; ++k) {
      tries.push_back({cx, s.top - kGap - h - float(k) * (h + 1), true});
      tries.push_back({cx, s.bottom + kGap + float(k) * (h + 1), true});
    }
    LabelPlace best = tries.front();
    float least = 1e30f;
    for (const LabelPlace& t : tries) {
      const Box b{t.x, t.y, t.x + w, t.y + h};
      float sum = 0;
      for (const Box& o : taken) sum += overlap(b, o);
      if (sum < least) least = sum, best = t;
      if (sum == 0) break;
    }
    taken.push_back({best.x, best.y, best.x + w, best.y + h});
    out.push_back(best);
  }
  return out;
}

std::optional<WireCurve> wire_curve(const World& world, ObjectId wire) {
  const auto a = world.value<ObjectId>(wire, "wire_from");
  const auto b = world.value<ObjectId>(wire, "wire_to");
  const PropertyStore& store = world.store();
  if (!a || !b || !store.alive(*a) || !store.alive(*b)) return {};
  WireCurve c;
  c.a =
      terminal_point(world, *a, world.value<std::int64_t>(wire, "wire_from_terminal").value_or(0));
  c.b = terminal_point(world, *b, world.value<std::int64_t>(wire, "wire_to_terminal").value_or(0));
  // It sags by a quarter of its span and 2 cm more, so that a short wire
  // between two touching ends still shows.
  c.control = (c.a + c.b) * 0.5 + Vec2{0, -0.25 * length(c.b - c.a) - 0.02};
  return c;
}

ObjectId wire_at(const World& world, Vec2 point, double margin) {
  const auto from = world.properties().find("wire_from");
  if (!from) return {};
  ObjectId best;
  double best_d = margin;
  for (const ObjectId w : carriers(world.store(), *from)) {
    const auto c = wire_curve(world, w);
    if (!c) continue;
    // The drawn curve as straight pieces, but for the tenth at each end: the
    // ends lie on parts, and a click there means the part.
    auto at = [&](double t) {
      const double u = 1 - t;
      return c->a * (u * u) + c->control * (2 * u * t) + c->b * (t * t);
    };
    Vec2 prev = at(0.1);
    for (int i = 1; i <= 20; ++i) {
      const Vec2 q = at(0.1 + 0.8 * i / 20.0);
      const double d = segment_distance(point, prev, q);
      if (d <= best_d) best = w, best_d = d;
      prev = q;
    }
  }
  return best;
}

Vec2 terminal_point(const World& world, ObjectId part, std::int64_t terminal) {
  const auto p = read_part(world, part);
  if (!p) return xy(world.value<Vec3>(part, "position").value_or(Vec3{}));
  const bool two =
      has(world, part, "emf") || has(world, part, "inductance") ||
      has(world, part, "capacitance") || has(world, part, "switch_closed") ||
      (world.value<bool>(part, "conductive").value_or(false) && has(world, part, "resistance"));
  if (!two) return p->centre;
  const double x = p->half_extent_x() * 0.8;
  return p->to_world({terminal == 1 ? x : -x, 0});
}

std::vector<Needle> compass_needles(World& world, const Camera& cam, float width, float height,
                                    float spacing) {
  std::vector<Needle> out;
  auto* forces =
      dynamic_cast<magnetism::MagneticForces*>(world.stage(magnetism::MagneticForces::kName));
  if (!forces || forces->poles().empty() || !(spacing > 4)) return out;
  // Needles at the middles of the grid's cells, so that none sits on the
  // window's edge.
  for (float y = spacing / 2; y < height; y += spacing)
    for (float x = spacing / 2; x < width; x += spacing) {
      const Vec2 at = cam.to_world(x, y);
      const Vec3 b = forces->field({at.x, at.y, 0});
      const Vec2 bxy = xy(b);
      const double t = length(bxy);
      if (!(t >= kCompassFloor)) continue;
      out.push_back({at, bxy * (1 / t), t});
    }
  return out;
}

void draw_world(ImDrawList* dl, World& world, const Camera& cam, const DrawOptions& opt,
                const Highlight& hl, double clock, const std::vector<Ring>& rings) {
  // The background is the renderer's clear colour (colour::kBackground): a
  // full-window quad costs a software renderer as much as everything else.
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  if (opt.grid) draw_grid(dl, cam, size);

  const std::vector<Part2D> parts = read_parts(world);
  const float px = float(cam.scale);  // pixels per metre
  auto* forces =
      dynamic_cast<magnetism::MagneticForces*>(world.stage(magnetism::MagneticForces::kName));

  // Static parts first (the scenery), then moving ones on top.
  for (int pass = 0; pass < 2; ++pass) {
    for (const Part2D& p : parts) {
      if (p.is_static != (pass == 0)) continue;
      const ObjectId id = p.id;
      const std::vector<Vec2> poly = outline(p, std::clamp(int(p.radius * px), 24, 64));
      const ImU32 base = fill_colour(world, id);
      const bool powered = world.value<bool>(id, "powered").value_or(false);
      if (powered) stroke(dl, cam, poly, with_alpha(colour::kPowered, 0.55f), 9);
      fill(dl, cam, poly, base);

      const auto magnet = enum_name(world, id, "magnet");
      const double q = world.value<double>(id, "pole_strength").value_or(0);
      const double hx = p.half_extent_x();
      if (magnet == "permanent" && q != 0) {
        // The classic bar magnet: north half red, south half green.
        const bool north_right = q > 0;
        fill(dl, cam, slice(p, 0, hx), north_right ? colour::kNorth : colour::kSouth);
        fill(dl, cam, slice(p, -hx, 0), north_right ? colour::kSouth : colour::kNorth);
        const float letter = std::clamp(
            float(std::min(hx, p.shape == Shape2D::Box ? p.half.y : p.radius) * px * 1.3), 0.f,
            18.f);
        if (letter >= 8) {
          text_centred(dl, iv(cam.to_screen(p.to_world({hx / 2, 0}))), IM_COL32_WHITE,
                       north_right ? "N" : "S", letter);
          text_centred(dl, iv(cam.to_screen(p.to_world({-hx / 2, 0}))), IM_COL32_WHITE,
                       north_right ? "S" : "N", letter);
        }
      } else if (magnet == "electromagnet" || has(world, id, "inductance")) {
        // A coil: windings across the core; its ends take the pole colours while it is on.
        if (p.shape == Shape2D::Box) {
          const int turns = std::clamp(int(hx * 2 * px / 5), 3, 40);
          for (int i = 0; i <= turns; ++i) {
            const double x = -hx * 0.85 + 1.7 * hx * i / turns;
            dl->AddLine(iv(cam.to_screen(p.to_world({x, -p.half.y}))),
                        iv(cam.to_screen(p.to_world({x + 0.2 * hx / turns, p.half.y}))),
                        scale_rgb(base, 0.62f), 1.2f);
          }
        }
        if (q != 0) {
          const float a = float(std::clamp(std::abs(q) / 5.0, 0.2, 0.85));
          fill(dl, cam, slice(p, hx * 0.7, hx),
               with_alpha(q > 0 ? colour::kNorth : colour::kSouth, a));
          fill(dl, cam, slice(p, -hx, -hx * 0.7),
               with_alpha(q > 0 ? colour::kSouth : colour::kNorth, a));
        }
      } else if (has(world, id, "emf")) {
        // A battery: a dark cell with a brass cap at its + end (terminal 1, +x).
        const double emf = world.value<double>(id, "emf").value_or(0);
        const bool plus_right = emf >= 0;
        const double cap = hx * 0.18;
        const double hy = p.shape == Shape2D::Box ? p.half.y : p.radius;
        fill(dl, cam,
             local_quad(p, plus_right ? hx - cap : -hx, plus_right ? hx : -hx + cap, -hy, hy),
             colour::kBrass);
        fill(dl, cam, local_quad(p, -hx * 0.5, hx * 0.5, -hy * 0.35, hy * 0.35),
             scale_rgb(colour::kBattery, 1.6f));
        const float letter = std::clamp(float(hy * px * 1.4), 0.f, 18.f);
        if (letter >= 8) {
          text_centred(dl, iv(cam.to_screen(p.to_world({plus_right ? hx * 0.6 : -hx * 0.6, 0}))),
                       IM_COL32_WHITE, "+", letter);
          text_centred(dl, iv(cam.to_screen(p.to_world({plus_right ? -hx * 0.6 : hx * 0.6, 0}))),
                       IM_COL32_WHITE, "-", letter);
        }
      } else if (has(world, id, "luminous_efficacy")) {
        // A lamp: a glass bulb in its holder, glowing with its luminous flux
        // on a log scale (a halo up to 2.5 times the bulb; full at 30 lm, a 3 W
        // bulb; a generator's 0.1 lm still shows).
        const double hy = p.shape == Shape2D::Box ? p.half.y : p.radius;
        const ImVec2 c = iv(cam.to_screen(p.to_world({0, 0})));
        const float r = float(std::min(hx, hy) * px * 0.8);
        const double flux = world.value<double>(id, "luminous_flux").value_or(0);
        const float glow = float(
            std::clamp(std::log10(1 + 10 * std::max(flux, 0.0)) / std::log10(301.0), 0.0, 1.0));
        if (glow > 0.01f)
          dl->AddCircleFilled(c, r * (1 + 1.5f * glow), IM_COL32(255, 220, 120, int(110 * glow)));
        dl->AddCircleFilled(c, r,
                            glow > 0.01f
                                ? IM_COL32(255, int(200 + 55 * glow), int(90 + 140 * glow), 255)
                                : IM_COL32(200, 205, 210, 255));
        dl->AddCircle(c, r, scale_rgb(base, 0.6f), 0, 1.2f);
      } else if (has(world, id, "capacitance") && p.shape == Shape2D::Box) {
        // A capacitor: two dark plates across its middle, the charged one
        // (terminal 0's plate positive: -x) tinted.
        const double hy = p.half.y, gap = hx * 0.08, t = hx * 0.06;
        const double q = world.value<double>(id, "plate_charge").value_or(0);
        const ImU32 plate = scale_rgb(colour::kBattery, 1.2f);
        fill(dl, cam, local_quad(p, -gap - t, -gap, -hy * 0.8, hy * 0.8),
             q > 0 ? colour::kNorth : plate);
        fill(dl, cam, local_quad(p, gap, gap + t, -hy * 0.8, hy * 0.8),
             q < 0 ? colour::kNorth : plate);
      } else if (has(world, id, "switch_closed") && p.shape == Shape2D::Box) {
        // A knife switch: jaws at both ends and a blade, lying in them while
        // closed, raised 30 degrees from terminal 0's jaw while open.
        const double hy = p.half.y;
        const bool closed = world.value<bool>(id, "switch_closed").value_or(false);
        fill(dl, cam, local_quad(p, -hx, -hx * 0.8, -hy, hy), colour::kBrass);
        fill(dl, cam, local_quad(p, hx * 0.8, hx, -hy, hy), colour::kBrass);
        const Vec2 hinge = p.to_world({-hx * 0.9, 0});
        const double len = hx * 1.8, up = closed ? 0.0 : 0.52;
        const Vec2 tip = p.to_world({-hx * 0.9 + len * std::cos(up), len * std::sin(up)});
        dl->AddLine(iv(cam.to_screen(hinge)), iv(cam.to_screen(tip)), colour::kSteel,
                    std::max(2.0f, float(hy * px * 0.5)));
      }
      if (p.is_static) draw_hatch(dl, cam, p, scale_rgb(base, 0.72f, 150));

      ImU32 edge = scale_rgb(base, 0.55f);
      float width = 1.5f;
      if (id == hl.hovered) {
        edge = scale_rgb(colour::kSelected, 1.0f, 160);
        width = 2.5f;
      }
      if (id == hl.selected || id == hl.wire_start) {
        edge = colour::kSelected;
        width = 3;
      }
      stroke(dl, cam, poly, edge, width);
      if (p.shape == Shape2D::Disk) {
        // A radius line shows a disk's rotation.
        dl->AddLine(iv(cam.to_screen(p.centre)),
                    iv(cam.to_screen(p.to_world({p.radius * 0.85, 0}))), scale_rgb(base, 0.55f),
                    1.5f);
      }
      if (p.pinned) {
        // A pin head through the part into the board.
        const ImVec2 c = iv(cam.to_screen(p.centre));
        dl->AddCircleFilled(c, 5.5f, IM_COL32(40, 40, 48, 255), 16);
        dl->AddCircle(c, 5.5f, IM_COL32_WHITE, 16, 1.5f);
        dl->AddCircleFilled(c, 1.8f, IM_COL32_WHITE, 8);
      }
    }
  }

  // Joints: hinges as rings at the anchor (filled dark when pinned to the
  // board), glue as small squares.
  if (const auto joint = world.properties().find("joint")) {
    const PropertyStore& store = world.store();
    for (const ObjectId j : carriers(store, *joint)) {
      auto anchor = world.value<Vec3>(j, "anchor");
      // The rigid body keeps a hinge's anchor current, not glue's: glue is
      // drawn on its first part, where it moves with it.
      if (enum_name(world, j, "joint") == "fixed")
        if (const auto a = world.value<ObjectId>(j, "body_a"); a && world.store().alive(*a))
          anchor = world.value<Vec3>(*a, "position");
      if (!anchor) continue;
      const ImVec2 c = iv(cam.to_screen(xy(*anchor)));
      const auto b = world.value<ObjectId>(j, "body_b");
      const bool to_board = !b || !store.alive(*b);
      if (enum_name(world, j, "joint") == "fixed") {
        dl->AddRectFilled({c.x - 4, c.y - 4}, {c.x + 4, c.y + 4}, IM_COL32(60, 60, 70, 255));
        dl->AddRect({c.x - 4, c.y - 4}, {c.x + 4, c.y + 4}, IM_COL32_WHITE, 0, 0, 1.5f);
      } else {
        dl->AddCircleFilled(
            c, 6.5f, to_board ? IM_COL32(40, 40, 48, 255) : IM_COL32(250, 250, 250, 255), 20);
        dl->AddCircle(c, 6.5f, to_board ? IM_COL32_WHITE : IM_COL32(40, 40, 48, 255), 20, 2);
        dl->AddCircleFilled(c, 2.0f, to_board ? IM_COL32_WHITE : IM_COL32(40, 40, 48, 255), 8);
      }
    }
  }

  // Springs: a zigzag coil between the two ends (a string: a plain line), with a fixed number of
  // turns so that it bunches as it closes; a dark dot at an end on the board.
  if (const auto k = world.properties().find("spring_stiffness")) {
    for (const ObjectId sp : carriers(world.store(), *k)) {
      const auto ends = spring_ends(world, sp);
      if (!ends) continue;
      const ImVec2 a = iv(cam.to_screen(ends->a)), b = iv(cam.to_screen(ends->b));
      const float dx = b.x - a.x, dy = b.y - a.y;
      const float len = std::sqrt(dx * dx + dy * dy);
      if (len < 1) continue;
      const float ux = dx / len, uy = dy / len;  // along, then across: (-uy, ux)
      const bool chosen = sp == hl.selected;
      const ImU32 ink = chosen ? colour::kSelected : IM_COL32(70, 70, 80, 255);
      if (world.value<bool>(sp, "spring_slack").value_or(false)) {
        // A string: straight when taut; slack, it hangs in a curve whose
        // length is its own (a parabola's sag from the spare length).
        const double rest = world.value<double>(sp, "spring_rest_length").value_or(0);
        const double span = length(ends->b - ends->a);
        const double sag = rest > span ? std::sqrt(3.0 / 8 * span * (rest - span)) : 0;
        const Vec2 mid = (ends->a + ends->b) * 0.5 + Vec2{0, -sag};
        std::vector<ImVec2> line;
        for (int i = 0; i <= 16; ++i) {
          const double t = i / 16.0;
          // A quadratic Bezier through the mid point: control at 2 mid - (a + b) / 2.
          const Vec2 ctl = mid * 2.0 - (ends->a + ends->b) * 0.5;
          const Vec2 p =
              ends->a * ((1 - t) * (1 - t)) + ctl * (2 * t * (1 - t)) + ends->b * (t * t);
          line.push_back(iv(cam.to_screen(p)));
        }
        dl->AddPolyline(line.data(), int(line.size()), IM_COL32(255, 255, 255, 150), 0,
                        chosen ? 4.5f : 3.5f);
        dl->AddPolyline(line.data(), int(line.size()), chosen ? ink : IM_COL32(150, 95, 40, 255), 0,
                        chosen ? 3.0f : 1.8f);
        for (const ImVec2 end : {a, b}) dl->AddCircleFilled(end, 2.5f, ink, 8);
        continue;
      }
      constexpr int kTurns = 8;
      const float lead = std::min(8.0f, len * 0.15f), width = 6;
      std::vector<ImVec2> zig{a, {a.x + ux * lead, a.y + uy * lead}};
      for (int i = 0; i < 2 * kTurns; ++i) {
        const float t = lead + (len - 2 * lead) * (float(i) + 0.5f) / float(2 * kTurns);
        const float side = (i % 2 ? -width : width);
        zig.push_back({a.x + ux * t - uy * side, a.y + uy * t + ux * side});
      }
      zig.push_back({b.x - ux * lead, b.y - uy * lead});
      zig.push_back(b);
      dl->AddPolyline(zig.data(), int(zig.size()), IM_COL32(255, 255, 255, 160), 0,
                      chosen ? 5.0f : 4.0f);
      dl->AddPolyline(zig.data(), int(zig.size()), ink, 0, chosen ? 3.0f : 2.0f);
      for (const ImVec2 end : {a, b}) dl->AddCircleFilled(end, 2.5f, ink, 8);
    }
  }

  // Wires: a sagging curve between terminals; live ones orange, with charges
  // moving the way the current flows. A selected wire is drawn thicker, blue.
  if (opt.wires) {
    if (const auto from = world.properties().find("wire_from")) {
      const PropertyStore& store = world.store();
      for (const ObjectId w : carriers(store, *from)) {
        const auto a = world.value<ObjectId>(w, "wire_from");
        const auto b = world.value<ObjectId>(w, "wire_to");
        if (!a || !b || !store.alive(*a) || !store.alive(*b)) continue;
        const WireCurve curve = *wire_curve(world, w);
        const Vec2 pa = curve.a, pb = curve.b, mid = curve.control;
        const double span = length(pb - pa);
        const ImVec2 sa = iv(cam.to_screen(pa)), sb = iv(cam.to_screen(pb)),
                     sm = iv(cam.to_screen(mid));
        const double current = world.value<double>(w, "current").value_or(0);
        const bool live = world.value<bool>(w, "powered").value_or(false);
        const bool chosen = w == hl.selected;
        dl->AddBezierQuadratic(sa, sm, sb, IM_COL32(255, 255, 255, 200), chosen ? 7.0f : 5.0f, 24);
        dl->AddBezierQuadratic(sa, sm, sb,
                               chosen ? colour::kSelected
                               : live ? colour::kWireLive
                                      : colour::kWireIdle,
                               chosen ? 4.0f : 2.5f, 24);
        for (const ImVec2 end : {sa, sb}) {
          dl->AddCircleFilled(end, 3.5f, live ? colour::kWireLive : colour::kWireIdle, 10);
          dl->AddCircle(end, 3.5f, IM_COL32_WHITE, 10, 1);
        }
        if (live) {
          // Charges: dots every ~25 px moving at a speed that grows with log |I|.
          const float speed =
              float(0.25 * std::clamp(std::log10(std::abs(current) * 1000 + 1), 0.3, 4.0));
          float phase = float(std::fmod(clock * speed, 1.0));
          if (current < 0) phase = 1 - phase;
          const int dots = std::clamp(int(span * px / 25), 2, 40);
          for (int i = 0; i < dots; ++i) {
            const float t = std::fmod((i + phase) / dots, 1.0f);
            const float u = 1 - t;
            const ImVec2 q{u * u * sa.x + 2 * u * t * sm.x + t * t * sb.x,
                           u * u * sa.y + 2 * u * t * sm.y + t * t * sb.y};
            dl->AddCircleFilled(q, 2.2f, IM_COL32(255, 248, 200, 255), 8);
          }
        }
      }
    }
  }

  // Magnetic forces (on by default) under the poles, so that an arrow
  // crossing a pole does not hide its colour.
  if (opt.magnetic_forces && forces) {
    for (const magnetism::MagneticBody& b : forces->bodies()) {
      const auto p = read_part(world, b.id);
      if (!p) continue;
      const Vec2 f = xy(b.force);
      const double n = length(f);
      const float len = arrow_length(n);
      if (len <= 0) continue;
      const ImVec2 from = iv(cam.to_screen(p->centre));
      arrow(dl, from, {from.x + float(f.x / n) * len, from.y - float(f.y / n) * len},
            colour::kMagneticForce, 2.5f);
    }
  }

  // Compass needles (key C): a diamond each, its north half red and its
  // south half pale, pointing along B; the stronger the field, the bolder,
  // from 1 uT (faint) to 10 mT (solid), so that the field's shape reads at a
  // glance and its strength roughly.
  if (opt.compass) {
    for (const Needle& n : compass_needles(world, cam, size.x, size.y)) {
      const float alpha =
          float(std::clamp(0.25 + 0.75 * std::log10(n.tesla / kCompassFloor) / 4, 0.25, 1.0));
      const ImVec2 c = iv(cam.to_screen(n.at));
      const ImVec2 d{float(n.north.x) * 11, -float(n.north.y) * 11};
      const ImVec2 side{-d.y * 0.22f, d.x * 0.22f};
      const ImVec2 tip{c.x + d.x, c.y + d.y}, tail{c.x - d.x, c.y - d.y};
      const ImVec2 l{c.x + side.x, c.y + side.y}, r{c.x - side.x, c.y - side.y};
      dl->AddTriangleFilled(tip, l, r, with_alpha(colour::kNorth, alpha));
      dl->AddTriangleFilled(tail, r, l, with_alpha(colour::rgb(120, 130, 150), alpha));
      dl->AddCircleFilled(c, 1.5f, with_alpha(colour::rgb(40, 40, 40), alpha), 6);
    }
  }

  // Magnet poles as the magnetic_forces set sees them (electromagnets and
  // induced poles in soft iron included).
  if (opt.poles && forces) {
    for (const magnetism::Pole& pole : forces->poles()) {
      const double q = std::abs(pole.strength);
      if (q < 0.05) continue;
      const float r = float(std::clamp(2.5 + 1.6 * std::log10(q + 1), 3.0, 7.0));
      const ImVec2 c = iv(cam.to_screen(xy(pole.position)));
      dl->AddCircleFilled(c, r + 1.5f, IM_COL32_WHITE, 16);
      dl->AddCircleFilled(c, r, pole.strength > 0 ? colour::kNorth : colour::kSouth, 16);
    }
  }

  if (opt.contact_forces) {
    if (auto* contacts = global_contacts(world)) {
      const double dt = world.dt();
      for (const std::span<const ContactPair> list : {contacts->began(), contacts->ongoing()}) {
        for (const ContactPair& pair : list) {
          const auto points = contacts->points(pair);
          if (points.empty()) continue;
          Vec2 at{};
          Vec2 normal = xy(points[0].normal);
          for (const auto& cp : points) at = at + xy(cp.position);
          at = at * (1.0 / double(points.size()));
          const double n = pair.normal_impulse / dt;
          const ImVec2 c = iv(cam.to_screen(at));
          dl->AddCircleFilled(c, 2.5f, colour::kContactForce, 8);
          const float len = arrow_length(n);
          if (len > 0)
            arrow(dl, c, {c.x + float(normal.x) * len, c.y - float(normal.y) * len},
                  colour::kContactForce, 2);
        }
      }
    }
  }

  // Rings round a part that was struck: the doorbell's ding, seen.
  for (const Ring& r : rings) {
    const auto p = read_part(world, r.part);
    if (!p) continue;
    const double age = clock - r.born;
    if (age < 0 || age > 0.8) continue;
    const ImVec2 c = iv(cam.to_screen(p->centre));
    const float base = float(p->half_extent_x() * px);
    for (int k = 0; k < 3; ++k) {
      const double a = age - k * 0.12;
      if (a < 0) continue;
      const float rad = base + float(a * 160);
      dl->AddCircle(c, rad, with_alpha(colour::kBrass, float((1 - a / 0.8) * r.strength)), 48, 3);
    }
  }

  if (opt.labels) {
    // Just above each part, like the paper's annotations, unless another
    // label is there already (place_labels). Small parts are placed first:
    // a large part's label has more room to move.
    std::vector<std::pair<std::string, LabelSpot>> wanted;
    for (const Part2D& p : parts) {
      if (p.is_static && p.half.x * px > 300) continue;  // floors and walls speak for themselves
      const std::string name = world.describe(p.id);
      if (name.empty() || name[0] == '#') continue;
      LabelSpot spot{1e9f, 1e9f, -1e9f, -1e9f, 0, 0};
      for (Vec2 v : outline(p, 16)) {
        const ScreenPoint q = cam.to_screen(v);
        spot.left = std::min(spot.left, q.x), spot.right = std::max(spot.right, q.x);
        spot.top = std::min(spot.top, q.y), spot.bottom = std::max(spot.bottom, q.y);
      }
      const ImVec2 sz = ImGui::GetFont()->CalcTextSizeA(13, 1e9f, 0, name.c_str());
      spot.width = sz.x, spot.height = sz.y;
      wanted.push_back({name, spot});
    }
    std::vector<std::size_t> order(wanted.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    auto box_area = [&](std::size_t i) {
      const LabelSpot& b = wanted[i].second;
      return (b.right - b.left) * (b.bottom - b.top);
    };
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return box_area(a) < box_area(b); });
    std::vector<LabelSpot> spots;
    for (std::size_t i : order) spots.push_back(wanted[i].second);
    const std::vector<LabelPlace> places = place_labels(spots);
    for (std::size_t k = 0; k < order.size(); ++k) {
      const LabelSpot& b = spots[k];
      const LabelPlace& at = places[k];
      if (at.moved) {
        // A leader from the label's nearest edge to the part's box centre.
        const float cx = (b.left + b.right) / 2, cy = (b.top + b.bottom) / 2;
        const float lx = std::clamp(cx, at.x, at.x + b.width);
        const float ly = std::clamp(cy, at.y, at.y + b.height);
        dl->AddLine({lx, ly}, {cx, cy}, with_alpha(colour::kLabel, 0.45f), 1);
      }
      dl->AddText(ImGui::GetFont(), 13, {at.x, at.y}, colour::kLabel,
                  wanted[order[k]].first.c_str());
    }
  }
  (void)kPi;
}

}  // namespace alloy::viewer
