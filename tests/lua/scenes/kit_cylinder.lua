-- A steel wheel (kit.cylinder) rolling down a 20 degree ramp (kit.floor),
-- and a wheel of iron, which a cylinder does not magnetise
-- (tests/lua/kit_test.cpp: the closed form a = 2/3 g sin(theta)).
local kit = require "kit"

world { seconds = 1 }

local theta = 20 * math.pi / 180
-- The ramp's top face passes through the origin; the wheel touches it 1 m up.
kit.floor { name = "ramp", at = { 0.05 * math.sin(theta), -0.05 * math.cos(theta) }, size = { 4, 0.1 }, angle = -theta }
local r = 0.1
kit.cylinder { name = "wheel", material = "steel", at = { -math.cos(theta) + r * math.sin(theta), math.sin(theta) + r * math.cos(theta) },
               radius = r, depth = 0.03 }
kit.cylinder { name = "iron_wheel", material = "iron", at = { 3, 3 }, radius = 0.05, pinned = true }
