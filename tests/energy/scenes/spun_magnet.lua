-- A magnet spun past a closed coil on a heavy wheel (a generator with one
-- pole pair; adv F9): the scene of tests/resolvers/magnetism/induction_test.cpp
-- at the world's step, for `alloy run tests/energy/scenes/spun_magnet.lua --energy
-- --dt DT` (docs/energy.md "Session 20": its books at the coarse step).
world { dt = 1 / 240, seconds = 0.5, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
        magnetic_forces = { near_field = true } } }
object { name = "coil", position = {0, 0, 0}, magnet = "electromagnet", turns = 500,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 1e-3, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 1.0, planar = true,
         magnet = "permanent", pole_strength = 100, position = {0.06, 0, 0},
         angular_velocity = {0, 0, 100} }
object { name = "axle", joint = "hinge", body_a = "mag", anchor = {0.06, 0, 0}, axis = {0, 0, 1} }
