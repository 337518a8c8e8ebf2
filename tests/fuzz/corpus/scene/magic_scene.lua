-- The bundled magic scene: rune stones among ordinary kit parts.
--
-- A lift rune rests on a source set into the floor: it fills with mana,
-- lights, floats up while it spends it, falls back, and charges again. A
-- second lift rune sits on a loose conduit stone that touches another source:
-- mana flows source -> conduit -> lift, and it too takes off. A wooden plank
-- lies across the last lift rune, which must carry it. A steel pendulum and a
-- rubber ball are plain physics in the same world.
local kit = require "kit"
local magic = require "magic"

world {
  name = "magic",
  description = "lift runes charge on a source, float while their mana lasts, and fall back",
  dt = 1 / 240,
  seconds = 8,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } },
}

kit.floor { name = "floor", at = { 0, -0.05 }, size = { 6, 0.1 } }
kit.wall  { name = "left_wall", at = { -3.05, 1.5 }, size = { 0.1, 3 } }
kit.wall  { name = "right_wall", at = { 3.05, 1.5 }, size = { 0.1, 3 } }

-- A source in the floor, a lift rune on it.
magic.stone { name = "altar", rune = "source", at = { -1.5, 0.04 }, fixed = true, mana = 1 }
magic.stone { name = "feather", rune = "lift", at = { -1.5, 0.12 } }

-- Source -> conduit -> lift: a loose conduit stone between the two.
magic.stone { name = "spring", rune = "source", at = { 0.3, 0.04 }, fixed = true, mana = 1 }
magic.stone { name = "channel", rune = "conduit", at = { 0.3, 0.12 } }
magic.stone { name = "kite", rune = "lift", at = { 0.3, 0.2 }, size = { 0.12, 0.08 } }

-- A lift rune under a plank: it must lift the wood too.
magic.stone { name = "well", rune = "source", at = { 1.8, 0.04 }, fixed = true, mana = 1 }
magic.stone { name = "bearer", rune = "lift", at = { 1.8, 0.12 }, capacity = 2 }
kit.bar { name = "plank", material = "wood", at = { 1.8, 0.18 }, length = 0.5, width = 0.04 }

-- Plain physics in the same world.
kit.bar   { name = "pendulum", material = "steel", at = { -0.4, 1.5 }, length = 0.6, width = 0.03 }
kit.hinge { name = "pivot", a = "pendulum", anchor = { -0.7, 1.5 } }
kit.disk  { name = "ball", material = "rubber", at = { 1.0, 1.2 }, radius = 0.07 }
