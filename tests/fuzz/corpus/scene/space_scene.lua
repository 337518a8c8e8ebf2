-- The paper's example of areas (section 3): "a game set on a planet might
-- represent gravity as a constant downwards vector. If the play moves to space
-- we might substitute a more involved gravity model for orbiting bodies."
--
-- A planet (a static sphere with mass) carries a launch tower. Its top is the
-- "planet" area, where gravity is the constant vector g; everywhere else is the
-- "orbit" area, where gravity.nbody pulls every body towards every mass. A
-- probe fired horizontally above the tower top leaves the planet area, comes
-- under N-body gravity and orbits: an ellipse with its lowest point where it
-- was fired, so that each orbit skims back over the tower top (through the
-- planet area) and out again. A crate sits on the tower under uniform gravity.
--
-- Why the planet area is so narrow: a closed orbit passes again through the
-- point where it left the planet area, so the probe crosses that area once per
-- orbit. Inside, it feels the constant g instead of Newton's field; the two
-- agree at the launch point and differ by about g * x / r at a distance x
-- from it. Both fields are conservative, so a crossing whose way in and way
-- out mirror each other does no net work; but the probe is counted in or out
-- of the area once per step, at a point that falls differently each pass, and
-- each crossing may change the orbit's energy by up to (GM / r^3) * half_width
-- * v * dt per unit mass. A 10 cm wide area (4 steps to cross at 240 Hz) keeps
-- that to about 1e-4 of the orbit's energy per pass, and the passes' errors
-- partly cancel; docs/gravity.md has the measured figures.
--
-- Units are SI at game scale: G is a game value chosen so that the planet
-- (radius 4 m, 160 t) has a surface gravity of 10 m/s^2. y is up; the probe
-- moves counter-clockwise.
local kit = require "kit"

local G = 1e-3              -- game gravitational constant, m^3 / (kg s^2)
local R = 4                 -- planet radius, m
local M = 1.6e5             -- planet mass, kg: GM = 160 m^3/s^2
local GM = G * M
local tower_top = 5         -- the launch tower stands 1 m on the planet
local r0 = 6                -- launch point, distance from the planet's centre, m
local v_circular = math.sqrt(GM / r0)
local v0 = 1.15 * v_circular  -- eccentricity 1.15^2 - 1 = 0.32: out to 11.7 m and back

world {
  name = "space",
  description = "a probe fired from a tower on a planet (uniform gravity) into orbit (N-body gravity)",
  dt = 1 / 240,
  seconds = 30,  -- launch at 1 s, then two orbits of 13.1 s
  use = { gravity = "gravity.nbody" },
  settings = { ["gravity.nbody"] = { G = G, softening = 0.01 } },
  areas = {
    -- The launch region on the tower top, from the crate on the tower up to
    -- the launch point, 10 cm wide. g is Newton's value at the launch point.
    { name = "planet", center = { 0, 5.55 }, half_extents = { 0.05, 0.6 },
      plugins = { "gravity.uniform" },
      settings = { ["gravity.uniform"] = { g = { 0, -GM / (r0 * r0) } } } },
    -- Everything else (with the world's settings of gravity.nbody).
    { name = "orbit", plugins = { "gravity.nbody" } },
  },
}

object { name = "planet", shape = "sphere", radius = R, position = { 0, 0 }, static = true, mass = M,
         friction = 0.8, restitution = 0.2 }
kit.floor { name = "tower", material = "steel", at = { 0, tower_top - 0.55 }, size = { 0.3, 1.1 } }
kit.bar { name = "crate", material = "wood", at = { 0, tower_top + 0.05 }, length = 0.1, width = 0.1 }
-- The probe waits in its launch clamp (pinned) above the crate, and at t = 1 s
-- is let go at launch speed, tangentially: the launch point is the lowest
-- point of its orbit, 1 m above the tower top, so it never touches the tower
-- or the crate when it comes round again.
kit.disk { name = "probe", material = { density = 100, friction = 0.5, restitution = 0.5 },
           at = { 0, r0 }, radius = 0.1, pinned = true }
at(1, "probe", { pinned = false, velocity = { -v0, 0 } })
