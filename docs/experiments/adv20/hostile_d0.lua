-- adv20 hostile: an air coil with pole_separation = 0 (a sheet of zero
-- length) on a 6 V battery; a 0.5 kg magnet flown at 0.5 m/s through it.
world { dt = 1/240, seconds = 1.6, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 500,
         coil_factor = 0.06, pole_separation = 0, inductance = 0.01, resistance = 3.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w2", wire_from = "a", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.5,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
