-- Electrical parts of the kit: batteries, contacts, wires, resistors,
-- capacitors, switches, lamps and photocells. The electricity
-- resolver (docs/electricity.md) reads what they carry: a battery is an emf
-- with an internal resistance between terminal 0 (-, its -x end) and terminal
-- 1 (+, its +x end); conductive parts that touch connect; a wire is a
-- resistance between two parts' terminals.
local physics = require "kit.physics"
local mount = require "kit.mount"
local mount_args, mounted = mount.args, mount.place

local electric = {}

electric.battery = {
  doc = "a battery lying along its x axis: terminal 0 (-) at its -x end, terminal 1 (+) at its +x end",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    -- A 6 V lantern battery (IEC 4R25: four cells in series, 67 x 67 x 115 mm,
    -- about 0.6 kg), the classic doorbell supply.
    { "emf", "number", default = 6, doc = "V, from terminal 0 to terminal 1" },
    -- Fresh alkaline cells are 0.1-0.2 ohm each at an ampere; zinc-carbon
    -- ones two or three times that (Energizer and Duracell data sheets,
    -- "internal resistance" application notes). Four alkaline cells: ~0.5 ohm.
    { "internal_resistance", "nonnegative", default = 0.5, doc = "ohm" },
    { "size", "extent", default = { 0.115, 0.067 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.067, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.6, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    local p = {
      shape = "box",
      size = { a.size[1], a.size[2], a.size[3] or a.depth },
      emf = a.emf,
      internal_resistance = a.internal_resistance,
      -- Its terminal caps conduct: a bar laid on an end touches that terminal.
      conductive = true,
      friction = 0.4,
      restitution = 0.3,
    }
    return mounted(a, p, a.mass)
  end,
}

electric.contact = {
  doc = "a conductive block fixed to the board (a switch contact, an interrupter's contact screw)",
  args = mount_args({
    { "material", "material", default = "brass" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "size", "extent", default = { 0.02, 0.01 }, doc = "{width, height} in the plane, m" },
    { "depth", "positive", default = 0.02, doc = "out of the plane, m" },
  }),
  build = function(a)
    local m = a.material
    if not m.conductive then error("a contact must be of a conductive material ('" .. (m.name or "this material") .. "' is not)", 0) end
    local size = { a.size[1], a.size[2], a.size[3] or a.depth }
    local p = {
      shape = "box",
      size = size,
      conductive = true,
      friction = m.friction,
      restitution = m.restitution,
    }
    return mounted(a, p, m.density * size[1] * size[2] * size[3])
  end,
}

electric.wire = {
  doc = "an insulated wire from a terminal of one part to a terminal of another",
  args = {
    { "from", "object", required = true, doc = "the part one end is attached to" },
    { "to", "object", required = true, doc = "the part the other end is attached to" },
    { "from_terminal", "nonnegative", default = 0,
      doc = "0 or 1: a battery's - or +, a coil's -x or +x end; any for a bar or contact" },
    { "to_terminal", "nonnegative", default = 0, doc = "0 or 1" },
    { "length", "positive", doc = "m; default: 1.5 x the distance between the two parts' centres, for slack" },
    -- 0.5 mm copper (24 AWG), bell wire's usual size.
    { "diameter", "positive", default = 0.5e-3, doc = "of the conductor, m" },
    { "material", "material", default = "copper" },
  },
  build = function(a, kit)
    for _, key in ipairs({ "from_terminal", "to_terminal" }) do
      if a[key] ~= 0 and a[key] ~= 1 then error("kit.wire '" .. key .. "' must be 0 or 1, got " .. tostring(a[key]), 0) end
    end
    local m = a.material
    if not m.resistivity then error("a wire must be of a material with a resistivity ('" .. (m.name or "this material") .. "' has none)", 0) end
    local len = a.length
    if not len then
      local p, q = kit.placed(a.from), kit.placed(a.to)
      if not (p and q) then
        error("kit.wire needs 'length': '" .. (p and a.to or a.from) .. "' was not made by the kit, so where it is is unknown", 0)
      end
      len = 1.5 * math.sqrt((p[1] - q[1]) ^ 2 + (p[2] - q[2]) ^ 2 + (p[3] - q[3]) ^ 2)
    end
    return {
      wire_from = a.from,
      wire_to = a.to,
      wire_from_terminal = a.from_terminal,
      wire_to_terminal = a.to_terminal,
      resistance = physics.wire_resistance(m.resistivity, len, a.diameter),
    }
  end,
}

-- A small mounted two-terminal box: terminal 0 at its -x end, 1 at its +x
-- end. Its body conducts, as a battery's caps do, so a bar laid on an end
-- touches that terminal.
local function two_terminal(a, p, mass)
  p.shape = "box"
  p.size = { a.size[1], a.size[2], a.size[3] or a.depth }
  p.conductive = true
  p.friction = 0.4
  p.restitution = 0.3
  return mounted(a, p, mass)
end

electric.resistor = {
  doc = "a resistor lying along its x axis: terminal 0 at its -x end, terminal 1 at its +x end",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "resistance", "nonnegative", default = 10, doc = "ohm, between terminals 0 and 1" },
    -- A 5 W wirewound power resistor in a ceramic case (22 x 10 x 9 mm, ~6 g).
    { "size", "extent", default = { 0.022, 0.01 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.009, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.006, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    return two_terminal(a, { resistance = a.resistance }, a.mass)
  end,
}

electric.junction = {
  doc = "a brass terminal block lying along its x axis: its two ends are joined by a brass bar, "
    .. "so every wire that ends on it meets the others at one node",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    -- A two-way brass terminal strip (20 x 10 x 10 mm, ~8 g): a fraction of
    -- a milliohm from end to end.
    { "resistance", "nonnegative", default = 0.0005, doc = "ohm, between its two ends" },
    { "size", "extent", default = { 0.02, 0.01 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.01, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.008, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    return two_terminal(a, { resistance = a.resistance }, a.mass)
  end,
}

electric.capacitor = {
  doc = "a capacitor lying along its x axis: terminal 0 at its -x end, terminal 1 at its +x end; "
    .. "`charge` is on terminal 0's plate and is kept while the circuit around it changes",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    -- A 10 mF, 16 V aluminium electrolytic can (35 mm across, 50 mm long,
    -- ~60 g); such cans have an equivalent series resistance of some tens of
    -- milliohms (manufacturers' data sheets, "ESR at 100 Hz").
    { "capacitance", "positive", default = 0.01, doc = "F" },
    { "charge", "number", default = 0, doc = "C on terminal 0's plate at the start (V(0) - V(1) = charge / capacitance)" },
    { "resistance", "nonnegative", default = 0.03, doc = "equivalent series resistance, ohm" },
    { "size", "extent", default = { 0.05, 0.035 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.035, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.06, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    return two_terminal(a, { capacitance = a.capacitance, plate_charge = a.charge, resistance = a.resistance }, a.mass)
  end,
}

electric.switch = {
  doc = "a knife switch lying along its x axis: joins terminal 0 (-x end) and 1 (+x end) while "
    .. "`switch_closed` is true; a timeline, a mod or the viewer sets it",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "closed", "boolean", default = false, doc = "whether it starts closed" },
    -- A small brass knife switch: about a milliohm across its blade and jaws.
    { "resistance", "nonnegative", default = 0.001, doc = "ohm, while closed" },
    { "size", "extent", default = { 0.06, 0.015 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.025, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.05, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    return two_terminal(a, { switch_closed = a.closed, resistance = a.resistance }, a.mass)
  end,
}

electric.lamp = {
  doc = "a filament lamp lying along its x axis: a resistor (terminal 0 at -x, 1 at +x) whose "
    .. "electrical power becomes light (the light resolver, docs/light.md)",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    -- A 6 V, 0.5 A torch bulb (3 W): 12 ohm with its filament hot. The
    -- resistance is taken as constant (the cold filament's tenth of it, and
    -- the inrush it makes, are not modelled).
    { "resistance", "positive", default = 12, doc = "ohm, the hot filament" },
    -- Small tungsten bulbs give 8 to 12 lumens per watt (manufacturers'
    -- catalogues of miniature lamps); a 3 W one about 30 lm.
    { "efficacy", "nonnegative", default = 10, doc = "lm per W of electrical power" },
    -- The bulb in its holder: 30 x 20 x 20 mm, about 10 g.
    { "size", "extent", default = { 0.03, 0.02 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.02, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.01, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    return two_terminal(a, { resistance = a.resistance, luminous_efficacy = a.efficacy }, a.mass)
  end,
}

electric.photocell = {
  doc = "a photocell (light-dependent resistor) lying along its x axis, its face up (+y): "
    .. "terminal 0 at -x, 1 at +x; R = dark (E / E0)^-gamma, at least lit_resistance",
  args = mount_args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    -- A CdS cell like the GL5528 (5 mm): 1 Mohm in the dark, 8-20 kohm at
    -- 10 lux, gamma about 0.7 (its data sheet); E0 = 0.0139 lux puts 10 kohm
    -- at 10 lux on this law; in bright light such cells level off near 100 ohm.
    { "dark_resistance", "positive", default = 1e6, doc = "ohm" },
    { "dark_illuminance", "positive", default = 0.0139, doc = "lux: E0, up to which it stays dark" },
    { "gamma", "nonnegative", default = 0.7, doc = "the law's exponent" },
    { "lit_resistance", "positive", default = 100, doc = "ohm, the least (full light)" },
    { "size", "extent", default = { 0.012, 0.005 }, doc = "{length, height} in the plane, m" },
    { "depth", "positive", default = 0.005, doc = "out of the plane, m" },
    { "mass", "positive", default = 0.001, doc = "kg (used when pinned)" },
  }),
  build = function(a)
    if a.lit_resistance > a.dark_resistance then
      error("kit.photocell 'lit_resistance' (" .. a.lit_resistance .. " ohm) must not exceed 'dark_resistance' ("
        .. a.dark_resistance .. " ohm)", 0)
    end
    -- `resistance` is what the circuit sees until the light reaches it: the dark value.
    return two_terminal(a, { resistance = a.dark_resistance, light_receiver = true,
                             dark_resistance = a.dark_resistance, dark_illuminance = a.dark_illuminance,
                             photo_gamma = a.gamma, lit_resistance = a.lit_resistance }, a.mass)
  end,
}

-- The kit's own: other mods use these parts through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return electric end
end)
