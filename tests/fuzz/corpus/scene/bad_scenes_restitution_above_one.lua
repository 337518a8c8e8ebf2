-- expect: line 3: object 'ball': 'restitution' must lie between 0 and 1, got 1.5
-- A ball that gains energy at every bounce.
object { name = "ball", position = { 0, 1 }, shape = "sphere", radius = 0.1, mass = 1, restitution = 1.5 }
