-- A 0.2 m box resting on a static floor (kit_scenes_test: swaps begin and end no contact).
world { name = "rest_on_floor", dt = 1/240, seconds = 1,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } } }
object { name = "floor", position = { 0, -0.05 }, shape = "box", size = { 6, 0.1, 0.1 }, static = true, friction = 0.3 }
object { name = "block", position = { 0, 0.1 }, shape = "box", size = { 0.2, 0.2, 0.2 }, mass = 1, friction = 0.3, planar = true }
