-- expect: line 3: world has no field 'second' (did you mean 'seconds'?)

world { dt = 1 / 240, second = 5 }
