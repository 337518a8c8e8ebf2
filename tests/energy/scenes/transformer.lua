-- Two coaxial coils 12 cm apart (a transformer on the pole model; adversary
-- adv13's F8): the primary (500 turns, 20 mH, 2 ohm) on a 6 V battery of
-- 0.5 ohm from t = 0, the secondary (300 turns, 10 mH, 1 ohm) shorted.
-- Nothing moves: the books close to rounding, from the first step.
world { dt = 1/240, seconds = 0.05 }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 500,
         coil_factor = 0.2, pole_separation = 0.04, inductance = 0.02, resistance = 2.0 }
object { name = "b", position = {0.12, 0, 0}, magnet = "electromagnet", turns = 300,
         coil_factor = 0.2, pole_separation = 0.04, inductance = 0.01, resistance = 1.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "a",
         wire_to_terminal = 0, resistance = 0 }
object { name = "w2", wire_from = "a", wire_from_terminal = 1, wire_to = "bat",
         wire_to_terminal = 0, resistance = 0 }
object { name = "w3", wire_from = "b", wire_from_terminal = 1, wire_to = "b",
         wire_to_terminal = 0, resistance = 0 }
