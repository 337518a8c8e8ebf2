-- expect: line 4: object 'arm': unknown property 'mas' (did you mean 'mass'?)
-- A raw object with a misspelt property.

object { name = "arm", position = { 0, 1 }, shape = "box", size = { 1, 0.05, 0.05 }, mas = 2 }
