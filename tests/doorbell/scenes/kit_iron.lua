-- Iron cores and iron bars of the kit, each case built from the viewer's
-- palette parts (apps/viewer/palette.cpp: a pinned 500-turn coil on an iron
-- core, a pinned 6 V battery, a 5 cm armature, a neodymium magnet) and
-- checked by tests/doorbell/kit_iron_test.cpp. The cases stand 1 m apart:
-- at that distance their fields pull with well under a thousandth of what
-- friction holds.
--
--   x = 0  lying:    an armature lies on a shelf, on the coil's axis, 4 mm
--                    from its +x end; the coil is on the battery
--   x = 1  idle:     the same with no battery: nothing pulls
--   x = 2  standing: the coil turned upright, pole face down; an armature
--                    stands on a shelf under it, 1 mm below that face; the
--                    coil is on the battery (and at x = 12, 22, 32: 2, 3
--                    and 4 mm below it)
--   x = 3  touching: the same, the armature touching the pole face, with
--                    nothing under it
--   x = 4  loose:    the same with no battery: it falls
--   x = 5  core:     a magnet hangs from a hinge 12 cm above its centre, its
--                    -x end 10 mm from the +x end of an unpowered cored coil
--   x = 6  air:      the same beside a coil without its core
--   x = 7  turn:     an armature on a pin through its centre, at 60 degrees
--                    across the field between two pinned magnets
local kit = require "kit"

world {
  dt = 1 / 240,
  seconds = 1,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } },
}

local y = 0.2           -- the coils' axis
local half = 0.025      -- half the coil's (and the armature's) length
local radius = 0.015    -- the coil's outside radius

local function powered(name, x)
  kit.battery { name = name .. "_battery", at = { x, 0.05 }, pinned = true }
  kit.wire { name = name .. "_out", from = name .. "_battery", from_terminal = 1, to = name .. "_coil", to_terminal = 0 }
  kit.wire { name = name .. "_back", from = name .. "_coil", from_terminal = 1, to = name .. "_battery", to_terminal = 0 }
end

-- A shelf whose top is at `top`, from x0 to x1.
local function shelf(name, x0, x1, top)
  kit.floor { name = name, at = { (x0 + x1) / 2, top - 0.01 }, size = { x1 - x0, 0.02 } }
end

-- Lying 4 mm from the pole, powered and not.
for _, c in ipairs({ { "lying", 0, true }, { "idle", 1, false } }) do
  local name, x = c[1], c[2]
  kit.coil { name = name .. "_coil", at = { x, y }, pinned = true }
  shelf(name .. "_shelf", x + half + 0.002, x + half + 0.1, y - 0.005)
  kit.armature { name = name .. "_armature", at = { x + half + 0.004 + half, y }, length = 0.05 }
  if c[3] then powered(name, x) end
end

-- Standing under the coil, turned upright (as the doorbell's is: its -x
-- end, its pole face, down), 1, 2, 3 and 4 mm below that face, on its axis.
-- (Until session 16 only the 1 mm one was lifted: the iron's induced poles
-- sat 0.075 of its length inside its faces.)
for i, gap in ipairs({ 0.001, 0.002, 0.003, 0.004 }) do
  local name, x = i == 1 and "standing" or "standing_" .. math.floor(gap * 1000 + 0.5), 2 + (i - 1) * 10
  kit.coil { name = name .. "_coil", at = { x, y }, angle = math.pi / 2, pinned = true }
  shelf(name .. "_shelf", x - 0.05, x + 0.05, y - half - gap - 2 * half)
  kit.armature { name = name .. "_armature", at = { x, y - half - gap - half }, length = 0.05, angle = math.pi / 2 }
  powered(name, x)
end

-- Touching the upright coil's pole face from below, with nothing under it:
-- held up when powered, and falling when not.
for _, c in ipairs({ { "touching", 3, true }, { "loose", 4, false } }) do
  local name, x = c[1], c[2]
  kit.coil { name = name .. "_coil", at = { x, y }, angle = math.pi / 2, pinned = true }
  kit.armature { name = name .. "_armature", at = { x, y - half - half }, length = 0.05, angle = math.pi / 2 }
  if c[3] then powered(name, x) end
end

-- A magnet hung on a hinge 12 cm above it, its -x end 10 mm from the +x end
-- of an unpowered coil: with an iron core, and without.
for _, c in ipairs({ { "core", 5, "iron" }, { "air", 6, "air" } }) do
  local name, x = c[1], c[2]
  kit.coil { name = name .. "_coil", at = { x, y }, core = c[3] }
  local m = { x + half + 0.01 + half, y }
  kit.magnet { name = name .. "_magnet", at = m }
  kit.hinge { name = name .. "_hinge", a = name .. "_magnet", anchor = { m[1], m[2] + 0.12 } }
end

-- An iron bar across a field: two magnets, north facing south, 6 cm apart.
kit.magnet { name = "turn_west", at = { 7 - 0.03 - half, y }, pinned = true }
kit.magnet { name = "turn_east", at = { 7 + 0.03 + half, y }, pinned = true }
kit.armature { name = "turn_armature", at = { 7, y }, length = 0.05, angle = math.rad(60) }
kit.pin { name = "turn_pin", part = "turn_armature", friction = 0.001 }
