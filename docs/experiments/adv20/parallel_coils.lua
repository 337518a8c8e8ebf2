-- adv20: two air coils in parallel on one 6 V battery; a 0.1 kg magnet is
-- flown at 0.5 m/s along the axis of coil a, through it (near field on by
-- default); coil b sits 0.3 m aside. No gravity.
world { dt = 1/240, seconds = 1.2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 2000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 3.0 }
object { name = "b", position = {0, 0.3, 0}, magnet = "electromagnet", turns = 2000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 3.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w2", wire_from = "a", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w3", wire_from = "bat", wire_from_terminal = 1, wire_to = "b", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w4", wire_from = "b", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.1,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
