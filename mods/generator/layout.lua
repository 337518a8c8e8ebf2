-- A generator from kit parts: the motor's rotor (mods/motor/rotor.lua: eight
-- 50 x 10 x 10 mm NdFeB spokes, north out and south out in turn, glued to a
-- wooden hub on a pinned axle) and its two coils (the motor's coreless coils,
-- 5100 turns each, radial at +22.5 and -22.5 degrees, 1.5 mm outside the
-- spokes' ends), wired in series through a lamp. A crank glued to the axle carries the hand's torque
-- (`drive_torque`, mods/generator/runtime.lua). There is no battery, no
-- slider and no bias magnet: nothing drives a current but the spokes' flux
-- sweeping through the coils (-dPhi/dt, docs/magnetism.md "Induction").
-- Nothing here knows what a generator is.
--
--   require "generator.layout" (options)   builds it and returns the numbers used
--
-- Why the two coils add: the rotor's poles alternate every 45 degrees and
-- the coils stand 45 degrees apart, so the lower coil sees the upper coil's
-- flux with the sign turned round. Wired head to head (upper 1 -> lamp ->
-- lower 1, lower 0 -> upper 0), the two EMFs drive the same way round the loop.
local kit = require "kit"

local defaults = {
  centre = { 0.24, 0.20 },
  -- The motor's rotor and coils, the same numbers (mods/motor/layout.lua).
  spoke_length = 0.05, spoke_width = 0.01, spoke_inner = 0.024, hub_radius = 0.022,
  -- The motor's coils (mods/motor/layout.lua), air-cored as there: an iron
  -- core would be magnetised by the spokes too and cog the rotor
  -- (docs/motor.md, "Iron cores").
  coil_angle = 22.5, coil_gap = 0.0015, coil_length = 0.02, coil_diameter = 0.058, turns = 5100,
  wire_diameter = 0.25e-3, core = "air", core_diameter = 0.0174,
  -- The bearing: dry friction (N m) and a light oil's viscous drag (N m s;
  -- 0.1 Pa s in the motor's bush: a hundredth of the motor's grease, so the
  -- lamp's load is what the hand feels most).
  axle_friction = 0.002, bearing_drag = 9e-5,
  -- The lamp: a 12 V, 30 mA pilot bulb (400 ohm hot, 10 lm/W), matched to
  -- the two coils in series (414 ohm), whose EMF is a few volts at a brisk
  -- turn.
  lamp_resistance = 400, lamp_efficacy = 10,
  -- The falling weight (weight = true): a 100 g steel ball on a string wound
  -- on the hub, hanging from its left side, weight_drop below the axle. The
  -- string: 20 N/m (an elastic cord: 5 cm of stretch under the weight), damped 0.3 N s/m.
  weight = false, weight_mass = 0.1, weight_drop = 0.15, string_stiffness = 20, string_damping = 0.3,
  -- The crank: a wooden arm across the hub's face, glued to it (inside the
  -- hub's outline, so that it touches no spoke).
  crank_length = 0.04,
}

return function(options)
  local o = {}
  for k, v in pairs(defaults) do o[k] = v end
  for k, v in pairs(options or {}) do
    if defaults[k] == nil then error("generator: no option '" .. tostring(k) .. "'", 2) end
    o[k] = v
  end
  local C = o.centre
  local rad = math.rad
  local function at(r, degrees)
    return { C[1] + r * math.cos(rad(degrees)), C[2] + r * math.sin(rad(degrees)) }
  end
  local tip = o.spoke_inner + o.spoke_length

  -- The rotor is the motor's (mods/motor/rotor.lua), with the crank's
  -- inertia (it lies along the hub's face) in the bearing's drag rate.
  local crank_mass = kit.material("wood").density * o.crank_length * 0.01 * 0.005
  local _, inertia = require "motor.rotor" (o, crank_mass * o.crank_length ^ 2 / 12)
  kit.bar { name = "crank", material = "wood", at = C, length = o.crank_length, width = 0.01,
            depth = 0.005, angle = rad(22.5) }
  kit.glue { name = "crank_glue", a = "axle", b = "crank" }

  if o.weight then
    local steel = kit.material("steel").density
    local radius = (3 * o.weight_mass / (4 * math.pi * steel)) ^ (1 / 3)
    -- It hangs in front of the rotor (z = 3 cm), clear of the spokes' 1 cm depth.
    kit.disk { name = "weight", material = "steel", at = { C[1] - o.hub_radius, C[2] - o.weight_drop },
               radius = radius,
               props = { position = { C[1] - o.hub_radius, C[2] - o.weight_drop, 0.03 }, string_drum = "axle", string_radius = o.hub_radius,
                         string_stiffness = o.string_stiffness, string_damping = o.string_damping } }
  end

  -- The two coils, radial, inner faces towards the rotor.
  local r_coil = tip + o.coil_gap + o.coil_length / 2
  for _, c in ipairs({ { "upper_coil", o.coil_angle }, { "lower_coil", -o.coil_angle } }) do
    kit.coil { name = c[1], at = at(r_coil, c[2]), angle = rad(c[2]), length = o.coil_length,
               diameter = o.coil_diameter, turns = o.turns, wire_diameter = o.wire_diameter,
               core = o.core, core_diameter = o.core_diameter }
  end

  -- The lamp, above the rotor, and the loop through both coils.
  kit.lamp { name = "lamp", at = { C[1] + 0.05, C[2] + 0.16 }, resistance = o.lamp_resistance,
             efficacy = o.lamp_efficacy }
  kit.wire { name = "to_lamp", from = "upper_coil", from_terminal = 1, to = "lamp", to_terminal = 0 }
  kit.wire { name = "from_lamp", from = "lamp", from_terminal = 1, to = "lower_coil", to_terminal = 1 }
  kit.wire { name = "between_coils", from = "lower_coil", from_terminal = 0, to = "upper_coil", to_terminal = 0 }

  o.inertia, o.coil_radius = inertia, r_coil
  return o
end
