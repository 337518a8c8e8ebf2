-- adv20: tests/energy/scenes/transformer.lua (primary on a 6 V battery, the
-- secondary shorted, 12 cm apart on one axis) with a 0.1 kg magnet flown at
-- 0.5 m/s along the common axis, through the primary, then the secondary.
world { dt = 1/240, seconds = 1.2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 500,
         coil_factor = 0.2, pole_separation = 0.04, inductance = 0.02, resistance = 2.0 }
object { name = "b", position = {0.12, 0, 0}, magnet = "electromagnet", turns = 300,
         coil_factor = 0.2, pole_separation = 0.04, inductance = 0.01, resistance = 1.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0 }
object { name = "w2", wire_from = "a", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0 }
object { name = "w3", wire_from = "b", wire_from_terminal = 1, wire_to = "b", wire_to_terminal = 0, resistance = 0 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.1,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.3, 0, 0}, velocity = {0.5, 0, 0} }
