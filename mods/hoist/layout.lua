-- The motor of mods/motor with a string wound on its axle and a load tied to
-- it: require "hoist.layout" (options) builds it and returns the numbers
-- used. Any option of motor.layout passes through; these are the hoist's.
-- Nothing here knows what a hoist is: the motor turns as it always does, the
-- string (runtime.lua) winds on the axle it is wound on, and the load hangs
-- from it.
local kit = require "kit"
local hoist = require "hoist"
local motor_layout = require "motor.layout"

local defaults = {
  -- The string is wound on the 10 mm steel axle itself (radius 5 mm), on
  -- its end behind the rotor, and hangs from its right-hand side: an
  -- anticlockwise turn winds it in.
  drum_radius = 0.005,
  -- The load: a steel cylinder 40 mm across, its thickness set by its mass,
  -- hanging drop metres below the axle.
  load_mass = 0.1, load_radius = 0.02, drop = 0.45,
  string_stiffness = 300, string_damping = 0.5,
}

return function(options)
  local o, motor_options = {}, {}
  for k, v in pairs(defaults) do o[k] = v end
  for k, v in pairs(options or {}) do
    if defaults[k] ~= nil then o[k] = v else motor_options[k] = v end
  end
  local motor = motor_layout(motor_options)
  local C = motor.centre
  local steel = kit.material("steel")
  local depth = o.load_mass / (steel.density * math.pi * o.load_radius ^ 2)
  local at = { C[1] + o.drum_radius, C[2] - o.drop }
  kit.cylinder { name = "load", material = "steel", at = at, radius = o.load_radius, depth = depth }
  -- Tied with the string already stretched by the load's weight, so that it
  -- hangs at rest from the start.
  local g = 9.81
  local free = o.drop / (1 + o.load_mass * g / o.string_stiffness)
  hoist.string { name = "line", drum = "axle", radius = o.drum_radius, load = "load", length = free,
                 stiffness = o.string_stiffness, damping = o.string_damping }
  for k, v in pairs(motor) do if o[k] == nil then o[k] = v end end
  o.load_depth = depth
  return o
end
