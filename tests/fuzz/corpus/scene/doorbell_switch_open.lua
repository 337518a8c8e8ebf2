-- The doorbell with the switch left open: the bar stays on its pin above the
-- contacts, no current can flow, and nothing rings.
world {
  name = "doorbell_switch_open",
  description = "the doorbell with its switch bar never let go: silence",
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
