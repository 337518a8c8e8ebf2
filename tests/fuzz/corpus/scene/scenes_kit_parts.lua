-- Every kit part once, with values the tests check (tests/lua/kit_test.cpp).
local kit = require "kit"

world { seconds = 1 }

kit.floor { name = "floor", at = { 0, -0.05 }, size = { 4, 0.1 } }
kit.bar   { name = "arm", material = "steel", at = { 1, 2 }, length = 1, width = 0.05, angle = 0.5 }
kit.disk  { name = "ball", material = "rubber", at = { 0.5, 3 }, radius = 0.1, velocity = { 1, 0 }, spin = 2 }
kit.hinge { name = "pivot", a = "arm", anchor = { 0.5, 2 }, friction = 0.1, limits = { -1, 1 } }
kit.disk  { name = "wheel", material = "brass", at = { 2, 1 }, radius = 0.2 }
kit.pin   { name = "axle", part = "wheel" }
kit.bar   { name = "fixed_bar", material = "wood", at = { -1, 1 }, length = 0.5, pinned = true }
kit.pin   { name = "clamp", part = "fixed_bar", fixed = true }
kit.glue  { name = "weld", a = "arm", b = "ball" }
object    { name = "raw", position = { 0, 1, 0.5 }, shape = "sphere", radius = 0.1, mass = 1, orientation = { 2, 0, 0, 0 } }
kit.bar   { name = "custom", material = { density = 1000, friction = 0.3, restitution = 0.2 },
            at = { 0, 4 }, length = 0.2, props = { linear_damping = 0.5 } }
