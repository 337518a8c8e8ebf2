-- Magnetic parts of the kit: coils (electromagnets), permanent magnets and
-- soft-iron armatures. The magnetism resolver (docs/magnetism.md) models
-- each as two poles on the part's x axis, 0.85 of its length apart; these
-- parts turn sizes, windings and materials into its pole strengths.
local geometry = require "kit.geometry"
local physics = require "kit.physics"
local mount = require "kit.mount"

local magnetic = {}

local pi = math.pi

magnetic.coil = {
  doc = "a coil of enamelled copper wire on an iron core (an electromagnet), lying along its x axis: terminal 0 at its -x end, 1 at +x",
  args = mount.args({
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "length", "positive", default = 0.05, doc = "along the axis, m" },
    { "diameter", "positive", default = 0.03, doc = "outside the winding, m" },
    { "turns", "positive", default = 500 },
    -- 0.5 mm enamelled copper (24 AWG), usual for 6-12 V bell coils.
    { "wire_diameter", "positive", default = 0.5e-3, doc = "m" },
    { "core", "string", default = "iron", doc = "\"iron\" (a soft-iron rod inside the winding) or \"air\"" },
    { "core_diameter", "positive", doc = "m; default 0.6 x the diameter" },
    { "core_pulled", "boolean", default = true,
      doc = "an iron core is magnetised by the other parts' fields too (pulled by a magnet, cogging); false: only the coil's own current magnetises it (the model before session 15, kept by the motor and the hoist until a retune meets the DC-motor model: docs/motor.md, \"Iron cores\")" },
  }),
  build = function(a, kit)
    local L, D, N, dw = a.length, a.diameter, a.turns, a.wire_diameter
    local dc = a.core_diameter or 0.6 * D
    if a.core ~= "iron" and a.core ~= "air" then
      error("kit.coil 'core' must be \"iron\" or \"air\", got \"" .. a.core .. "\"", 0)
    end
    if not (dc < D) then error("kit.coil 'core_diameter' must be less than the diameter", 0) end
    -- The winding fills the ring between the core and the outside: does it fit?
    -- Round wire packs to about 0.8 of the window in practice.
    local window = (D - dc) / 2 * L
    local fits = math.floor(0.8 * window / (dw * dw))
    if N > fits then
      error(string.format("kit.coil: %g turns of %g mm wire do not fit on a %g x %g mm coil (at most %d)",
        N, dw * 1e3, L * 1e3, D * 1e3, fits), 0)
    end
    local ri, ro = dc / 2, D / 2
    -- Turns spread evenly from ri to ro: their mean enclosed area and length.
    local mean_area = pi * (ro ^ 3 - ri ^ 3) / (3 * (ro - ri))
    local mean_turn = pi * (ri + ro)
    local copper, iron = kit.material("copper"), kit.material("iron")
    local resistance = physics.wire_resistance(copper.resistivity, N * mean_turn, dw)
    -- An iron rod in the coil's field H = N I / L is magnetised to
    -- chi_app H (its shape limits chi_app): the coil's moment per ampere-turn
    -- is the air's mean area plus chi_app times the core's section.
    local core_area, chi_app = pi * dc * dc / 4, 0
    if a.core == "iron" then chi_app = physics.apparent_susceptibility(iron.susceptibility, L / dc) end
    local effective_area = mean_area + chi_app * core_area
    local separation = physics.magnetic_length_ratio * L
    local mass = copper.density * N * mean_turn * pi * dw * dw / 4
    if a.core == "iron" then mass = mass + iron.density * core_area * L end
    local p = {
      shape = "box",
      size = { L, D, D },
      magnet = "electromagnet",
      turns = N,
      -- q = coil_factor N I, with q = moment / pole separation.
      coil_factor = effective_area / separation,
      -- Long-solenoid flux linkage, mu0 N^2 A_eff / L: an overestimate for a
      -- short coil (Wheeler's end correction would take ~20 % off here).
      inductance = physics.mu0 * N * N * effective_area / L,
      resistance = resistance,
      friction = 0.4,
      restitution = 0.3,
    }
    if a.core == "iron" and a.core_pulled then
      -- The core is soft iron to the other parts too: a magnet's field, or
      -- another coil's, magnetises it along the coil's axis (the resolver's
      -- cored electromagnet, docs/magnetism.md "Soft iron"), so an unpowered
      -- coil is pulled by a magnet and a powered one pulls harder on iron
      -- than its own moment alone would. Its own current's share is already
      -- in coil_factor above.
      p.susceptibility = iron.susceptibility
      p.core_diameter = dc
      p.saturation_pole = iron.saturation_magnetization * core_area * L / separation
    end
    return mount.place(a, p, mass)
  end,
}

-- Remanence Br (T) and density (kg/m^3) of magnet grades: sintered NdFeB
-- N35 1.17-1.21 T, 7500; sintered ferrite (Y30) 0.38-0.40 T, 4900.
-- Sources: Arnold Magnetic Technologies and TDK data sheets.
-- Conduction: sintered NdFeB is a metal (about 1.5e-6 ohm m) and is sold
-- nickel-plated (Ni-Cu-Ni), so a neodymium magnet conducts like any metal
-- part; sintered ferrite is a ceramic (1e4 ohm m and more): an insulator.
local grades = {
  neodymium = { remanence = 1.2, density = 7500, conductive = true },
  ferrite = { remanence = 0.4, density = 4900, conductive = false },
}

magnetic.magnet = {
  doc = "a permanent bar magnet magnetised along its length",
  args = {
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "length", "positive", default = 0.05, doc = "m" },
    { "width", "positive", default = 0.01, doc = "m" },
    { "depth", "positive", doc = "m; default: the width" },
    { "grade", "string", default = "neodymium", doc = "\"neodymium\" or \"ferrite\"" },
    { "remanence", "positive", doc = "T; default: the grade's" },
    { "north", "string", default = "+x", doc = "\"+x\" or \"-x\": which end of the bar is north" },
    { "angle", "number", default = 0, doc = "rotation about +z, rad" },
    { "pinned", "boolean", default = false, doc = "held in place on the play area" },
    { "conductive", "boolean", doc = "conducts (touching parts connect); default: the grade's (neodymium, plated, yes; ferrite no)" },
  },
  build = function(a)
    local g = grades[a.grade]
    if not g then error("kit.magnet 'grade' must be \"neodymium\" or \"ferrite\", got \"" .. a.grade .. "\"", 0) end
    if a.north ~= "+x" and a.north ~= "-x" then
      error("kit.magnet 'north' must be \"+x\" or \"-x\", got \"" .. a.north .. "\"", 0)
    end
    local size = { a.length, a.width, a.depth or a.width }
    -- M = Br / mu0; the moment M V carried by poles 0.85 L apart.
    local magnetisation = (a.remanence or g.remanence) / physics.mu0
    local q = magnetisation * size[2] * size[3] / physics.magnetic_length_ratio
    local p = {
      shape = "box",
      size = size,
      magnet = "permanent",
      pole_strength = a.north == "+x" and q or -q,
      position = a.at,
      orientation = geometry.quat_z(a.angle),
      density = g.density,
      mass = g.density * geometry.box_volume(size),
      friction = 0.4,
      restitution = 0.4,
      planar = true,
    }
    if a.pinned then p.pinned = true end
    local conductive = a.conductive
    if conductive == nil then conductive = g.conductive end
    if conductive then p.conductive = true end
    return p
  end,
}

-- The kit's own: other mods use these parts through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return magnetic end
end)
