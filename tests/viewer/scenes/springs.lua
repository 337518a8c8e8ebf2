-- Springs and their energy books (issue 17): `alloy run tests/viewer/scenes/springs.lua --energy`.
-- A rubber ball bobs on a damped spring under a shelf, and a plank hinged at
-- one end to the board swings on an undamped spring from its tip. The ledger books the
-- springs' energy (a store), the damper's heat (a sink) and the springs' work
-- on the parts (the transfer "springs", booked on both sides).
local kit = require "kit"

world { name = "springs", dt = 1 / 240, seconds = 6 }

kit.floor { name = "floor", at = { 0, -0.01 }, size = { 1, 0.02 } }
kit.floor { name = "shelf", at = { -0.2, 0.5 }, size = { 0.3, 0.02 } }
kit.disk { name = "ball", material = "rubber", at = { -0.2, 0.22 }, radius = 0.02 }
kit.spring { name = "bob", a = "ball", b = "shelf", at_b = { 0, -0.01 },
             stiffness = 20, rest_length = 0.2, damping = 0.05 }

kit.bar { name = "plank", material = "wood", at = { 0.275, 0.3 }, length = 0.25, width = 0.02 }
kit.hinge { name = "axle", a = "plank", anchor = { 0.15, 0.3 } }
kit.spring { name = "tip", a = "plank", at_a = { 0.125, 0 }, at_b = { 0.4, 0.55 },
             stiffness = 5, rest_length = 0.15 }
