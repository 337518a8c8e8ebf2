-- expect: line 3: object 'ghost': a moving body needs a 'mass'
-- A dynamic sphere with no mass and no density.
object { name = "ghost", position = { 0, 1 }, shape = "sphere", radius = 0.1 }
