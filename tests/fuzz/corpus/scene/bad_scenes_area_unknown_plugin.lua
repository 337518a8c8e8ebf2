-- expect: line 2: world: area 'moon': unknown plugin 'gravity.uniforn' (did you mean 'gravity.uniform'?)
world { dt = 1 / 240, areas = { { name = "moon", radius = 2, plugins = { "gravity.uniforn" } } } }
