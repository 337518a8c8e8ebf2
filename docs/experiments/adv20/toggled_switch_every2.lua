-- adv20 (the rigid body every 2nd step): a battery, a switch and an air coil in one loop; a 0.1 kg magnet
-- flown at 0.5 m/s through the coil; the switch is toggled by the timeline
-- every 0.0125 s (3 steps at 1/240 s) for the whole run. No gravity.
world { dt = 1/240, seconds = 1.2, every = { rigid_body = 2 }, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 2000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 3.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "sw", switch_closed = true, resistance = 0.001 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "sw", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w2", wire_from = "sw", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w3", wire_from = "a", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.1,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
local closed = true
for k = 1, 95 do
  closed = not closed
  at(k * 0.0125, "sw", { switch_closed = closed })
end
