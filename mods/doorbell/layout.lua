-- The doorbell of the paper (section 4.1, figure 1), built from kit parts
-- only: a battery, a switch (two contacts and a bar held above them), an
-- electromagnet, an interrupter striker and a bell. Nothing here knows what a
-- doorbell is: each part is what it is made of, the wires say what is
-- connected to what, and the physics does the rest.
--
--   require "doorbell.layout" (options)   builds it and returns the numbers
--   used; any default below can be overridden by name (variants, tests).
--
-- The striker is a wooden lever hinged at its left end. It rests on a felt
-- pad; a soft-iron armature stands on it under the coil, a steel hammer sits
-- on its tip under the bell. Hinged under it is a contact finger, a strip of
-- brass whose tip rests by its own weight on the interrupter contact: the
-- circuit is closed through the striker. When the coil pulls the armature up,
-- the finger's tip stays on the contact for the first millimetres of the
-- stroke (the finger turns on its hinge, its tip sliding) until the finger
-- reaches its stop; then it is lifted off, the circuit opens, the magnet
-- dies, and the striker flies on into the bell. Gravity brings it back onto
-- its pad, the finger lands on the contact, and it starts again. This travel
-- is what the spring contact of a real bell gives: the coil pulls over a
-- distance set by geometry, not over a number of time steps
-- (docs/doorbell.md, "Why the contact finger").
--
-- Coordinates: metres, y up, z = 0 the play area.
local kit = require "kit"

local defaults = {
  -- Supply: a pack of eight fresh alkaline D cells in series, 12 V, 0.075
  -- ohm each. It was 0.1 ohm each (the kit battery's figure) while the
  -- coupling's force current ran half a step ahead of its kick (induction
  -- order 1): that lead pulled harder than the coil does, and rang 16 steps
  -- apart (142 strikes in 10 s at 1/240 s). With the second-order coupling
  -- (session 17) the same bell rings every 17 steps at 1/240 s, as its
  -- converged period of 0.070 s (1/1920 s) says it should; a fresh pack's
  -- 0.6 ohm brings back 16 steps and 142 strikes (converged: 0.068 s at
  -- 1/1920 s), steadily at 1/240 and 1/480 s and with 10 % more or less emf
  -- (0.5 ohm rings 141, 0.4 and 0.7 ohm 133: the period locks to whole
  -- steps). The battery gives 99 J in 10 s instead of 85 J.
  emf = 12, internal_resistance = 0.6,
  -- The switch: its bar is held this far above the two contacts.
  switch_gap = 0.004,
  -- The striker: a wooden lever (130 x 6 x 12 mm) hinged at its left end.
  hinge = { 0.17, 0.10 }, arm_length = 0.13, arm_width = 0.006, arm_depth = 0.012,
  pad_at = 0.035,          -- felt pad under the lever, from the hinge
  armature_at = 0.065,     -- soft-iron armature (25 x 10 x 10 mm) standing on the lever
  armature_length = 0.025, armature_width = 0.01,
  hammer_radius = 0.005,   -- steel ball on the tip
  -- The contact finger: a brass strip 16 x 3 x 8 mm hinged under the lever,
  -- leaning towards the hinge. Angles from the vertical, radians.
  finger_at = 0.09, finger_length = 0.016, finger_width = 0.003, finger_depth = 0.008,
  finger_rest = 1.2,       -- its lean with the lever on its pad and its tip on the contact
  finger_stop = 1.05,      -- its hinge stops it here: the end of the contact's travel
  finger_drop = 1.25,      -- and here when it hangs free
  -- A sliding contact is made to slide (silver-faced or carbon): friction
  -- ~0.1 rather than brass on brass.
  finger_friction = 0.1,
  -- The electromagnet above the armature: 950 turns of 0.5 mm enamelled
  -- copper on a 50 x 30 mm bobbin with an iron core (960 fit). Since the
  -- core is soft iron to the armature too (it and the armature magnetise
  -- each other), 800 turns pulled so hard that 10 % more battery made the
  -- strikes uneven; 950 turns draw less current for the same ampere-turns
  -- at the stall (N I = V N / R, and R grows with N): the same strike
  -- period, 0.0667 s, for 85 J from the battery in 10 s against 104 J.
  -- Since the armature's induced poles sit on its faces (session 16) it is
  -- pulled harder across the gap: at 5 mm the strikes came unevenly (spread
  -- 21 % of the period); 6 mm rings as before (142 strikes at 16 steps,
  -- spread 0, 85.2 J).
  coil_gap = 0.006, coil_length = 0.05, coil_diameter = 0.03, turns = 950, wire_diameter = 0.5e-3,
  -- The bell above the hammer: a bronze dome of 30 mm radius. Its notes ring
  -- for seconds and it is struck thirteen times a second: they pile up to
  -- twice full scale at loudness 1; 0.4 keeps the recording unclipped.
  bell_gap = 0.0065, bell_radius = 0.03, loudness = 0.4,
}

return function(options)
  local o = {}
  for k, v in pairs(defaults) do o[k] = v end
  for k, v in pairs(options or {}) do
    if defaults[k] == nil then error("doorbell: no option '" .. tostring(k) .. "'", 2) end
    o[k] = v
  end
  local P = o.hinge
  local half = o.arm_width / 2

  -- The supply and the switch, left of the striker.
  kit.battery { name = "battery", at = { 0.07, 0.04 }, emf = o.emf, internal_resistance = o.internal_resistance }
  kit.contact { name = "contact_1", at = { 0.03, 0.12 } }
  kit.contact { name = "contact_2", at = { 0.11, 0.12 } }
  kit.bar { name = "switch_bar", material = "brass", at = { 0.07, 0.125 + 0.004 + o.switch_gap },
            length = 0.11, width = 0.008, depth = 0.01, pinned = true }

  -- The striker: lever, felt pad (and the felt rest it lands on), armature, hammer.
  kit.bar { name = "arm", material = "wood", at = { P[1] + o.arm_length / 2, P[2] },
            length = o.arm_length, width = o.arm_width, depth = o.arm_depth }
  kit.hinge { name = "pivot", a = "arm", anchor = P }
  kit.bar { name = "pad", material = "felt", at = { P[1] + o.pad_at, P[2] - half - 0.0015 },
            length = 0.008, width = 0.003, depth = 0.01 }
  kit.glue { name = "pad_glue", a = "arm", b = "pad" }
  kit.floor { name = "rest", material = "felt", at = { P[1] + o.pad_at, P[2] - half - 0.003 - 0.005 },
              size = { 0.012, 0.01 }, depth = 0.02 }
  local armature = { P[1] + o.armature_at, P[2] + half + o.armature_length / 2 }
  kit.armature { name = "armature", at = armature, length = o.armature_length,
                 width = o.armature_width, angle = math.pi / 2 }
  kit.glue { name = "armature_glue", a = "arm", b = "armature" }
  local hammer = { P[1] + o.arm_length - o.hammer_radius, P[2] + half + o.hammer_radius }
  kit.disk { name = "hammer", material = "steel", at = hammer, radius = o.hammer_radius }
  kit.glue { name = "hammer_glue", a = "arm", b = "hammer" }

  -- The contact finger and the interrupter contact its tip rests on. A thin
  -- strip bends rather than bounces, and the contact is sprung: restitution 0
  -- for both (the rigid body takes the larger of a pair's two values).
  local pivot = { P[1] + o.finger_at, P[2] - half }
  local down = { -math.sin(o.finger_rest), -math.cos(o.finger_rest) }
  local L = o.finger_length
  kit.bar { name = "finger", material = "brass", at = { pivot[1] + down[1] * L / 2, pivot[2] + down[2] * L / 2 },
            length = L, width = o.finger_width, depth = o.finger_depth, angle = -(math.pi / 2 + o.finger_rest),
            props = { restitution = 0, friction = o.finger_friction } }
  -- A hinge's angle is part a's relative to part b: here -(pi/2 + lean).
  kit.hinge { name = "finger_hinge", a = "finger", b = "arm", anchor = pivot,
              limits = { -(math.pi / 2 + o.finger_drop), -(math.pi / 2 + o.finger_stop) } }
  local tip = { pivot[1] + down[1] * L, pivot[2] + down[2] * L - o.finger_width / 2 * math.sin(o.finger_rest) }
  kit.contact { name = "interrupter", at = { tip[1], tip[2] - 0.005 }, size = { 0.02, 0.01 },
                props = { restitution = 0 } }

  -- The electromagnet above the armature, on its axis; the bell above the hammer.
  kit.coil { name = "coil", at = { armature[1], armature[2] + o.armature_length / 2 + o.coil_gap + o.coil_length / 2 },
             angle = math.pi / 2, length = o.coil_length, diameter = o.coil_diameter, turns = o.turns,
             wire_diameter = o.wire_diameter }
  kit.bell { name = "bell", at = { hammer[1], hammer[2] + o.hammer_radius + o.bell_gap + o.bell_radius },
             radius = o.bell_radius, loudness = o.loudness }

  -- The circuit: battery + -> switch -> coil -> finger -> interrupter -> battery -.
  kit.wire { name = "wire_1", from = "battery", from_terminal = 1, to = "contact_2" }
  kit.wire { name = "wire_2", from = "contact_1", to = "coil", to_terminal = 0 }
  kit.wire { name = "wire_3", from = "coil", from_terminal = 1, to = "finger" }
  kit.wire { name = "wire_4", from = "interrupter", to = "battery", to_terminal = 0 }
  return o
end
