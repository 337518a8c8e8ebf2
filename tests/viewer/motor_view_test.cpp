// The motor (mods/motor) in the viewer, headless: the screenshot that
// docs/images/viewer_motor.png is made from shows every spoke's poles in the
// paper's colours (figure 6: north red, south green), the coil that is on with
// its north pole facing the rotor, the brass slider on the spoke it powers.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "apps/viewer/viewer.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;

const fs::path kMotor = test::source("mods/motor");

/// Share of the pixels in a (2r+1)^2 square about `at` within `tol` of `c`.
double share_of(const Image& img, ScreenPoint at, ImU32 c, int r = 1, int tol = 12) {
  const int cr = int(c & 0xff), cg = int((c >> 8) & 0xff), cb = int((c >> 16) & 0xff);
  int hits = 0, n = 0;
  for (int y = int(at.y) - r; y <= int(at.y) + r; ++y)
    for (int x = int(at.x) - r; x <= int(at.x) + r; ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      const std::uint8_t* p = img.at(x, y);
      ++n;
      hits +=
          std::abs(p[0] - cr) <= tol && std::abs(p[1] - cg) <= tol && std::abs(p[2] - cb) <= tol;
    }
  return n ? double(hits) / n : 0;
}

std::string pixel(const Image& img, ScreenPoint at) {
  const std::uint8_t* p = img.at(int(at.x), int(at.y));
  std::ostringstream s;
  s << "pixel at (" << int(at.x) << ", " << int(at.y) << ") is rgb(" << int(p[0]) << ", "
    << int(p[1]) << ", " << int(p[2]) << ")";
  return s.str();
}

TEST(ViewerMotor, TheSpokesPolesAreRedAndGreenAndThePoweredCoilFacesNorth) {
  if (!fs::exists(kMotor / "mod.lua")) GTEST_SKIP() << "mods/motor is not here";
  Viewer v(test::headless(kMotor));
  // The README's screenshot: 50 frames (0.83 s), the slider on a north spoke
  // (N2 from 0.75 to 0.92 s since the motor's coils are back-EMF-limited).
  // Labels off (L): a label may lie over a pole (the axle's over an inner one).
  v.push_key(SDLK_l);
  for (int i = 0; i < 50; ++i) v.frame();
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  v.set_paused(true);
  World& w = *v.world();
  const Image img = v.render_image();
  auto* forces =
      dynamic_cast<magnetism::MagneticForces*>(w.stage(magnetism::MagneticForces::kName));
  ASSERT_NE(forces, nullptr);

  // Every spoke: two poles, north out or south out, in their colours where
  // the magnetic_forces set puts them.
  int checked = 0;
  for (const char* name : {"spoke_N1", "spoke_N2", "spoke_N3", "spoke_N4", "spoke_S1", "spoke_S2",
                           "spoke_S3", "spoke_S4"}) {
    const ObjectId spoke = w.find(name);
    ASSERT_TRUE(bool(spoke)) << name;
    const magnetism::MagneticBody* body = forces->find(spoke);
    ASSERT_NE(body, nullptr) << name;
    ASSERT_EQ(body->pole_count, 2u) << name;
    const Vec2 centre = xy(std::get<Vec3>(w.get(spoke, "position")));
    for (std::uint32_t k = 0; k < 2; ++k) {
      const magnetism::Pole pole = forces->poles()[body->first_pole + k];
      const Vec2 at = xy(pole.position);
      // North out for the N spokes: the north pole is the one farther from the axle.
      const Vec2 axle = xy(std::get<Vec3>(w.get(w.find("axle"), "position")));
      const bool outer = length(at - axle) > length(centre - axle);
      const bool north = pole.strength > 0;
      EXPECT_EQ(north, outer == (name[6] == 'N')) << name << " pole " << k;
      const ScreenPoint s = v.camera().to_screen(at);
      ASSERT_FALSE(v.over_panel(s.x, s.y)) << name;
      EXPECT_GT(share_of(img, s, north ? colour::kNorth : colour::kSouth), 0.5)
          << name << (north ? " north: " : " south: ") << pixel(img, s);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 16);

  // The slider lies on spoke N2 at this frame: the upper coil is on, and its
  // end facing the rotor is north; the lower coil is off.
  EXPECT_LT(std::get<double>(w.get(w.find("upper_coil"), "pole_strength")), -1)
      << "the upper coil is on, north at -x";
  EXPECT_EQ(std::get<double>(w.get(w.find("lower_coil"), "pole_strength")), 0.0);
  const magnetism::MagneticBody* coil = forces->find(w.find("upper_coil"));
  ASSERT_NE(coil, nullptr);
  ASSERT_EQ(coil->pole_count, 2u);
  for (std::uint32_t k = 0; k < 2; ++k) {
    const magnetism::Pole pole = forces->poles()[coil->first_pole + k];
    const ScreenPoint s = v.camera().to_screen(xy(pole.position));
    EXPECT_GT(share_of(img, s, pole.strength > 0 ? colour::kNorth : colour::kSouth), 0.5)
        << "upper coil " << (pole.strength > 0 ? "north: " : "south: ") << pixel(img, s);
  }
  // The bias magnet below: north up.
  const magnetism::MagneticBody* bias = forces->find(w.find("bias"));
  ASSERT_NE(bias, nullptr);
  for (std::uint32_t k = 0; k < bias->pole_count; ++k) {
    const magnetism::Pole pole = forces->poles()[bias->first_pole + k];
    const Vec2 centre = xy(std::get<Vec3>(w.get(w.find("bias"), "position")));
    EXPECT_EQ(pole.strength > 0, pole.position.y > centre.y) << "north up";
    const ScreenPoint s = v.camera().to_screen(xy(pole.position));
    EXPECT_GT(share_of(img, s, pole.strength > 0 ? colour::kNorth : colour::kSouth), 0.5)
        << "bias: " << pixel(img, s);
  }
}

}  // namespace
}  // namespace alloy::viewer
