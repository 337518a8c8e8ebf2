// The view onto the play area: metres to pixels and back. y is up in the
// play area and down on the screen.
#pragma once

#include <algorithm>

#include "apps/viewer/part_geometry.hpp"

namespace alloy::viewer {

struct ScreenPoint {
  float x = 0, y = 0;
};

struct Camera {
  Vec2 centre{0, 1};               ///< the play-area point at the middle of the view, m
  double scale = 150;              ///< pixels per metre
  float mid_x = 640, mid_y = 400;  ///< where `centre` is drawn, px

  ScreenPoint to_screen(Vec2 w) const {
    return {float(mid_x + (w.x - centre.x) * scale), float(mid_y - (w.y - centre.y) * scale)};
  }
  Vec2 to_world(float x, float y) const {
    return {centre.x + (x - mid_x) / scale, centre.y - (y - mid_y) / scale};
  }
  /// Frames the box [lo, hi] (m) in the screen rectangle [x0, x1] x [y0, y1] px.
  void fit(Vec2 lo, Vec2 hi, float x0, float y0, float x1, float y1, double margin = 0.08) {
    const double w = std::max(hi.x - lo.x, 0.2), h = std::max(hi.y - lo.y, 0.2);
    scale = std::min((x1 - x0) / (w * (1 + 2 * margin)), (y1 - y0) / (h * (1 + 2 * margin)));
    scale = std::clamp(scale, 5.0, 5000.0);
    centre = {(lo.x + hi.x) / 2, (lo.y + hi.y) / 2};
    mid_x = (x0 + x1) / 2;
    mid_y = (y0 + y1) / 2;
  }
  /// Zooms by `factor` keeping the play-area point under (x, y) where it is.
  void zoom_at(float x, float y, double factor) {
    const Vec2 before = to_world(x, y);
    scale = std::clamp(scale * factor, 5.0, 5000.0);
    const Vec2 after = to_world(x, y);
    centre = centre + (before - after);
  }
};

}  // namespace alloy::viewer
