-- The bundled rigid-body scene: everything the kit's mechanics can show in a
-- few seconds, built from kit parts only. y is up, the floor's top is y = 0;
-- lengths in metres, angles in radians.
local kit = require "kit"

world {
  name = "rigid_demo",
  description = "a hinged pendulum, disks rolling down a ramp, a bouncing rubber ball, a pinned wheel slowing down",
  dt = 1 / 240,
  seconds = 5,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } },
}

-- The play area: a floor, two walls, and a tilted shelf as a ramp.
kit.floor { name = "floor", at = { 0, -0.05 }, size = { 6, 0.1 } }
kit.wall  { name = "left_wall", at = { -3.05, 1 }, size = { 0.1, 2 } }
kit.wall  { name = "right_wall", at = { 3.05, 1 }, size = { 0.1, 2 } }
kit.floor { name = "ramp", at = { -1.5, 0.6 }, size = { 1.6, 0.05 }, angle = -0.35 }

-- A steel pendulum, released horizontal, hinged at its left end.
kit.bar   { name = "pendulum", material = "steel", at = { 1.9, 1.8 }, length = 0.8, width = 0.04 }
kit.hinge { name = "pivot", a = "pendulum", anchor = { 1.5, 1.8 } }

-- Two metal disks (cylinders, coins seen face on) dropped onto the ramp:
-- they land, roll down and off.
kit.cylinder { name = "brass_disk", material = "brass", at = { -2.0, 1.3 }, radius = 0.06 }
kit.cylinder { name = "copper_disk", material = "copper", at = { -1.7, 1.6 }, radius = 0.06 }

-- A rubber ball dropped on the floor: it bounces, a little lower each time.
kit.disk { name = "ball", material = "rubber", at = { 0.3, 1.5 }, radius = 0.08 }

-- A wooden plank falling at an angle: it lands on one end and tips over.
kit.bar { name = "plank", material = "wood", at = { 0.9, 0.6 }, length = 0.6, width = 0.05, angle = 0.3 }

-- A wooden wheel pinned through its centre, spun up: pin friction slows it.
kit.cylinder { name = "wheel", material = "wood", at = { 2.4, 0.5 }, radius = 0.15, depth = 0.04, spin = 6 }
kit.pin  { name = "axle", part = "wheel", friction = 0.05 }
