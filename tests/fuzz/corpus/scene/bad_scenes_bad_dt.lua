-- expect: line 2: world: 'dt' must be a positive number of seconds, got 0
world { dt = 0, seconds = 1 }
