-- The doorbell rung for a while: the switch bar drops at t = 0.5 s, and at
-- t = 3 s a hand lifts it 2 cm off the contacts and holds it there. The
-- circuit opens and the bell falls silent (the striker comes to rest on its
-- pad, the bell's last note dies away).
world {
  name = "doorbell_switch_lifted",
  description = "the doorbell rung from 0.5 s to 3 s, then the switch bar is lifted away",
  dt = 1 / 240,
  seconds = 6,
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
at(3.0, "switch_bar", { pinned = true, position = { 0.07, 0.15 }, velocity = { 0, 0 }, angular_velocity = { 0, 0, 0 },
                        orientation = { 1, 0, 0, 0 } })
