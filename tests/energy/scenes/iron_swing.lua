-- Soft iron in a permanent magnet's field, no coil and no gravity: an iron
-- bar hung on a hinge swings to a pinned magnet's north end and back
-- (tests/energy/energy_books_test.cpp, IronsPullComesOutOfItsStore). Every
-- joule the bar gains comes from the iron's co-energy in the magnet's field.
local kit = require "kit"

world { dt = 1 / 240, seconds = 2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }

kit.magnet { name = "magnet", at = { 0, 0 }, pinned = true }
-- The bar lies along x, 15 mm right of the magnet's +x end, and is hung from
-- a hinge 10 cm above its centre: the pull swings it in.
local at = { 0.025 + 0.015 + 0.025, 0 }
kit.armature { name = "bar", at = at, length = 0.05 }
kit.hinge { name = "hinge", a = "bar", anchor = { at[1], at[2] + 0.1 } }
