-- expect: line 5: object 'ball': 'mass' must be a finite number
-- 0/0 is NaN in Lua: it must never reach the rigid body.
local radius = 0.1
local volume = 0
object { name = "ball", position = { 0, 1 }, shape = "sphere", radius = radius, mass = volume / volume }
