-- expect: line 3: object 'ball': 'radius' expects a number, got the string "big"
-- A raw object: a string where a number belongs.
object { name = "ball", position = { 0, 1 }, shape = "sphere", radius = "big", mass = 1 }
