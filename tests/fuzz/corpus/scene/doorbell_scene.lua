-- The doorbell: at t = 0.5 s the pin holding the switch bar is pulled and the
-- bar drops across the two switch contacts; from then on it rings, for as
-- long as the bar closes the switch. `alloy run mods/doorbell` narrates it;
-- `--audio bell.wav` records it.
world {
  name = "doorbell",
  description = "the paper's doorbell (4.1): a switch bar drops, the bell rings",
  dt = 1 / 240,
  seconds = 10,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    -- ODE's exact solver: a light contact finger on a hinge with stops,
    -- against a heavy lever, is what the iterative one handles worst (at
    -- rest the finger creeps off its contact).
    rigid_body = { solver = "step" },
  },
}

require "doorbell.layout" ()

at(0.5, "switch_bar", { pinned = false })
