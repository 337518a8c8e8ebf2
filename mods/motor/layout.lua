-- The electric motor of the paper (section 4.2, figure 4), built from kit
-- parts only: a rotor of eight permanent-magnet spokes glued to an axle that
-- is pinned to the play area, a brass sliding contact hinged to the left of
-- the rotor that falls onto the spokes, two electromagnets to the right, a
-- bias magnet below, a battery and wires. Nothing here knows what a motor
-- is: each part is what it is made of, the wires say what is connected to
-- what, and the physics does the rest (docs/motor.md).
--
--   require "motor.layout" (options)   builds it and returns the numbers
--   used; any default below can be overridden by name (variants, tests).
--
-- How it turns. The spokes are neodymium bar magnets lying along their
-- radius, north out and south out in turn; they are nickel-plated and so
-- conduct. The slider rests on the spokes' outer ends; the spoke it touches
-- closes a circuit: battery + -> slider -> spoke -> (its wire) -> a coil ->
-- battery -. The four north spokes are wired to the upper coil, the four
-- south spokes to the lower one. Both coils are wired so that the end facing
-- the rotor is a north pole, and they stand 45 degrees apart (+-22.5 degrees
-- about the horizontal): since the rotor's poles alternate every 45 degrees,
-- a north pole at -22.5 degrees acts on the rotor exactly as a south pole at
-- +22.5 degrees would, so the pair is the paper's "single electromagnet of
-- changing polarity" at +22.5 degrees. While the slider touches a north
-- spoke (from 112.5 to 157.5 degrees, upper left) the north spoke nearest
-- the upper coil is just above it and is pushed on, and the south spoke just
-- below it is pulled up (paper, figure 6); when the slider reaches the next
-- spoke, a south one, the other coil takes over and the push goes on. The
-- slider's contact line is tangent to the circle of the spokes' ends at 135
-- degrees, so the hand-over comes exactly when the torque of the coil that
-- is on would turn round.
--
-- Coordinates: metres, y up, z = 0 the play area; angles in degrees from +x,
-- anticlockwise, about the axle.
local kit = require "kit"

local defaults = {
  centre = { 0.24, 0.20 },  -- the axle
  -- Supply: the kit's 6 V lantern battery (four alkaline cells, 0.5 ohm).
  emf = 6, internal_resistance = 0.5,
  -- The rotor: eight 50 x 10 x 10 mm sintered NdFeB bars (the kit's default
  -- magnet, 37.5 g, q = 112 A m), inner ends 24 mm from the axle, on a wooden
  -- hub (insulating: the spokes touch nothing but the slider).
  spoke_length = 0.05, spoke_width = 0.01, spoke_inner = 0.024, hub_radius = 0.022,
  -- The bearing: a 10 mm steel axle in an oiled bronze bush. Dry friction
  -- (N m) and the oil's viscous drag (N m s: Petroff's law, 2 pi eta r^3 l /
  -- c, is 9.0e-5 for a light oil of 0.1 Pa s, r = 5 mm, l = 23 mm, c = 20
  -- um). The drag is small: the back-EMF sets the steady speed (docs/motor.md,
  -- "What sets the speed").
  axle_friction = 0.002, bearing_drag = 9e-5,
  -- The sliding contact: a brass rod 170 x 4 x 4 mm hinged 4 mm from its
  -- left end. Its underside lies on the tangent to the circle of the spokes'
  -- ends at contact_angle, the hinge hinge_distance down that line. It is
  -- held raised by slider_lift (rad) until slider_release (s), then falls.
  -- A sliding contact is made to slide and not to bounce: friction 0.15
  -- (a silver-graphite face), restitution 0 on both sides of the pair (the
  -- rigid body takes the larger of a pair's two values, so the spokes' ends
  -- are dead too).
  contact_angle = 135, hinge_distance = 0.13, slider_length = 0.17, slider_width = 0.004,
  slider_lift = 0.4, slider_release = 0.1, slider_friction = 0.15, spoke_restitution = 0,
  -- The electromagnets: the kit's coil wound for this motor, 6000 turns of
  -- 0.27 mm enamelled copper on a 50 mm long bobbin 56 mm across with an iron
  -- core (248 ohm, 4.9 H), radial, their inner faces coil_gap outside the
  -- spokes' ends. So many turns make the back-EMF constant k about 1 V s,
  -- and the electrical damping k^2 / R = 4e-3 N m s is 50 times the oil's:
  -- the rotor turns where the back-EMF nearly cancels the battery (the kit's
  -- default coil, 500 turns of 0.5 mm wire, gives k = 0.03 V s, and then the
  -- bearing sets the speed).
  coil_angle = 22.5, coil_gap = 0.004, coil_length = 0.05, coil_diameter = 0.056, turns = 6000,
  wire_diameter = 0.27e-3,
  -- The cores amplify the coils' own field but are not magnetised by the
  -- spokes (core_pulled = false): with them pulled, the spokes' field at a
  -- core (about 5 times the coil's own NI / L here) cogs the rotor into
  -- detents 22.5 degrees from where the bias magnet holds it, which are the
  -- commutation's dead points, and the rotor stalls (docs/motor.md, "Iron
  -- cores"). A retune that runs with pulled cores is not found yet: session
  -- 17 searched the bias magnet, the coils' gap and their spacing; some
  -- variants run from the bundled start, none starts from every put-down
  -- (docs/motor.md, "Iron cores", the table and why). Session 20's two-phase
  -- motor (live_cores = true, below) runs with them pulled but misses the
  -- DC model ("Session 20: live cores").
  core_pulled = false,
  -- The coils' core: "iron" (the scene's) or "air" (a coreless coil, as
  -- session 18's search and the generator use), and the core's or bore's
  -- diameter (false: the kit's, 0.6 of the coil's diameter).
  core = "iron", core_diameter = false,
  -- The bias magnet: a 30 x 10 x 10 mm ferrite bar (q = 37 A m) standing
  -- below the axle, north up; it pulls a south spoke to the bottom, which
  -- puts a north spoke under the slider, where the torque is largest.
  bias_distance = 0.12, bias_grade = "ferrite", bias_length = 0.03, bias_width = 0.01,
  -- false: no bias magnet.
  bias = true,
  -- A second phase (commutators = 2): a second ring of contacts on the axle
  -- (brass bars, commutator_z out of the spokes' plane, turned by
  -- commutator_offset degrees from the spokes), its own sliding contact
  -- there, and two more coils: coil_b1 at phase_b_angle, fed by the ring's
  -- bars that follow a north spoke, and coil_b2 45 degrees clockwise of it,
  -- fed by the others; both face the rotor with north, as the first pair.
  commutators = 1, commutator_z = 0.05, commutator_depth = 0.004, commutator_offset = 22.5, phase_b_angle = 270,
  -- The battery's centre from the axle, m.
  battery_at = { -0.115, -0.125 },
  -- The rotor as it is put down, turned by this many degrees from where the
  -- bias magnet holds it (tests: it settles back before the slider lands).
  rotor_angle = 0,
  -- true: session 20's two-phase motor with live cores (below, `live`).
  live_cores = false,
}

-- live_cores = true: session 20's study of a motor whose coils keep the
-- kit's live cores (docs/motor.md, "Session 20: live cores"). Two phases:
-- the spokes' pair of coils as above and a second pair at 270 and 225
-- degrees, fed through a second commutator ring 22.5 degrees (half a spoke
-- pitch) on, so that the four cores' 45-degree detents cancel (two cores
-- stand 22.5 degrees, mod 45, from the other two) and the drive never falls
-- to nothing at a hand-over: no bias magnet. The coils farther out (16 mm)
-- and longer (70 mm, 8400 turns of the same wire) so that the drive beats
-- what is left of the cogging. These values replace the defaults above; any
-- option given still wins. Not the bundled motor: it misses the DC model
-- (the docs say by how much and why).
local live = {
  commutators = 2, core_pulled = true, bias = false, battery_at = { 0.17, -0.15 },
  coil_gap = 0.016, coil_length = 0.07, turns = 8400,
}

return function(options)
  local o = {}
  for k, v in pairs(defaults) do o[k] = v end
  if options and options.live_cores then
    for k, v in pairs(live) do o[k] = v end
  end
  for k, v in pairs(options or {}) do
    if defaults[k] == nil then error("motor: no option '" .. tostring(k) .. "'", 2) end
    o[k] = v
  end
  local C = o.centre
  local rad = math.rad
  local function at(r, degrees)
    return { C[1] + r * math.cos(rad(degrees)), C[2] + r * math.sin(rad(degrees)) }
  end
  local tip = o.spoke_inner + o.spoke_length  -- radius of the spokes' outer ends

  -- The rotor (mods/motor/rotor.lua): spoke i at -90 + 45 i degrees (the
  -- bottom first, going anticlockwise), south out for even i: S1 N1 S2 N2
  -- S3 N3 S4 N4, on a hub pinned by an oiled bearing.
  if o.commutators ~= 1 and o.commutators ~= 2 then
    error("motor: 'commutators' must be 1 or 2, got " .. tostring(o.commutators), 2)
  end
  o.commutator_z = o.commutators == 2 and o.commutator_z or nil
  local spokes, inertia, segments = require "motor.rotor" (o)

  -- The sliding contact, raised and held until it is let go (and the second
  -- phase's, the same, commutator_z out of the plane).
  local p = rad(o.contact_angle)
  local along = { math.cos(p - math.pi / 2), math.sin(p - math.pi / 2) }  -- the tangent, rising to the right
  local out = { math.cos(p), math.sin(p) }
  local half = o.slider_width / 2
  local hinge = { C[1] + tip * out[1] - o.hinge_distance * along[1] + half * out[1],
                  C[2] + tip * out[2] - o.hinge_distance * along[2] + half * out[2] }
  local lean = math.atan2(along[2], along[1]) + o.slider_lift
  local inset = 0.004
  local from_hinge = o.slider_length / 2 - inset
  local function slider(name, z)
    -- (Out of the plane, z ~= 0, it is held there by its hinge, not by the
    -- play area's plane, which runs through z = 0.)
    kit.bar { name = name, material = "brass", length = o.slider_length, width = o.slider_width,
              at = { hinge[1] + from_hinge * math.cos(lean), hinge[2] + from_hinge * math.sin(lean), z },
              angle = lean, pinned = o.slider_release > 0,
              props = { friction = o.slider_friction, restitution = 0, planar = z == 0 } }
    kit.hinge { name = name .. "_hinge", a = name, anchor = { hinge[1], hinge[2], z } }
  end
  slider("slider", 0)
  if o.commutators == 2 then slider("slider_b", o.commutator_z) end

  -- The two electromagnets, radial, inner faces towards the rotor.
  local r_coil = tip + o.coil_gap + o.coil_length / 2
  local coils = { { "upper_coil", o.coil_angle }, { "lower_coil", -o.coil_angle } }
  if o.commutators == 2 then
    coils[3] = { "coil_b1", o.phase_b_angle }
    coils[4] = { "coil_b2", o.phase_b_angle - 45 }
  end
  for _, c in ipairs(coils) do
    kit.coil { name = c[1], at = at(r_coil, c[2]), angle = rad(c[2]), length = o.coil_length,
               diameter = o.coil_diameter, turns = o.turns,
               wire_diameter = o.wire_diameter, core = o.core, core_diameter = o.core_diameter or nil,
               core_pulled = o.core_pulled }
  end

  -- The bias magnet, standing below the axle, north up.
  if o.bias then kit.magnet { name = "bias", at = at(o.bias_distance, -90), angle = math.pi / 2, length = o.bias_length,
               width = o.bias_width, grade = o.bias_grade, north = "+x", pinned = true } end

  -- The battery, below and to the left, and the wires. A coil's current
  -- from its terminal 1 to 0 makes its -x end (the one facing the rotor) a
  -- north pole.
  kit.battery { name = "battery", at = { C[1] + o.battery_at[1], C[2] + o.battery_at[2] }, emf = o.emf,
                internal_resistance = o.internal_resistance }
  -- One phase: the battery's + to its slider, each contact the slider
  -- touches to the coil it feeds (north: the first), both coils back to -.
  local function phase(lead, slider, contacts, coil_n, coil_s, return_n, return_s)
    kit.wire { name = lead, from = "battery", from_terminal = 1, to = slider }
    for _, s in ipairs(contacts) do
      kit.wire { name = s.name .. "_wire", from = s.name, to = s.north and coil_n or coil_s, to_terminal = 1 }
    end
    kit.wire { name = return_n, from = coil_n, from_terminal = 0, to = "battery", to_terminal = 0 }
    kit.wire { name = return_s, from = coil_s, from_terminal = 0, to = "battery", to_terminal = 0 }
  end
  phase("lead", "slider", spokes, "upper_coil", "lower_coil", "upper_return", "lower_return")
  if o.commutators == 2 then
    phase("lead_b", "slider_b", segments, "coil_b1", "coil_b2", "b1_return", "b2_return")
  end

  o.hinge, o.tip, o.inertia, o.coil_radius = hinge, tip, inertia, r_coil
  -- The sliding contacts a scene lets go at slider_release.
  o.sliders = o.commutators == 2 and { "slider", "slider_b" } or { "slider" }
  return o
end
