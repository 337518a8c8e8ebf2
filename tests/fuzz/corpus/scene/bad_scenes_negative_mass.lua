-- expect: line 5: object 'ball': 'mass' must be greater than 0, got -2
world { seconds = 1 }

object { name = "floor", position = { 0, 0 }, shape = "box", size = { 4, 0.1, 1 }, static = true }
object { name = "ball", position = { 0, 1 }, shape = "sphere", radius = 0.1, mass = -2 }
