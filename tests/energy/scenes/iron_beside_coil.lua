-- A magnet spun past a pinned iron bar that lies on the axis of a closed air
-- coil, no gravity (session 21, docs/magnetism.md "Induction through soft
-- iron"; tests/energy/energy_books_test.cpp's
-- FreeIronsChangingMomentInducesTheCoilsEmf closes the loop through 10 kOhm
-- instead, for Faraday's law). As the magnet turns the bar's
-- induced moment turns over, its flux through the coil with it, and the
-- coil's current magnetises the bar too. The bar's near face is 1 cm from
-- the coil's pole: the pole model's near field (the moment solved from the
-- mean field of its samples, its forces and flux on its faces) shows in the
-- books here, flat with the step: `alloy run
-- tests/energy/scenes/iron_beside_coil.lua --energy --dt DT`. The magnet is
-- a heavy part on an axle through its centre, so it turns about 10 rad/s
-- all the while.
world { dt = 1 / 240, seconds = 2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "coil", position = { 0, 0, 0 }, magnet = "electromagnet", turns = 3000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.05, resistance = 1.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
-- The bar: 6 cm of soft iron from 3 to 9 cm along the coil's axis.
object { name = "bar", shape = "box", size = { 0.06, 0.01, 0.01 }, position = { 0.06, 0, 0 },
         magnet = "soft_iron", susceptibility = 5000, static = true }
-- The magnet turns about its centre 3 cm beyond the bar's end.
object { name = "mag", shape = "box", size = { 0.02, 0.01, 0.01 }, mass = 20.0, planar = true,
         magnet = "permanent", pole_strength = 100, position = { 0.12, 0, 0 },
         angular_velocity = { 0, 0, 10 } }
object { name = "axle", joint = "hinge", body_a = "mag", anchor = { 0.12, 0, 0 }, axis = { 0, 0, 1 } }
