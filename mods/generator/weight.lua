-- The generator driven by a falling weight: a 100 g steel ball on a string
-- wound on the rotor's hub. Let go at 0.2 s, it falls, turns the rotor, and
-- the lamp lights; the lamp's load is what keeps the fall slow.
-- `alloy run mods/generator/weight.lua`.
world {
  name = "generator_weight",
  description = "the motor's rotor turned by a falling weight on a string lights a lamp",
  dt = 1 / 240,
  seconds = 8,
  report = { "axle.angular_velocity.z@1", "weight.velocity.y@1", "lamp.radiant_power@1" },
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    -- Second-order induction (the EMF from the motion's present velocity and
    -- acceleration, docs/electricity.md "Induction"), named here so that the
    -- figures in docs/motor.md are the ones this scene runs with.
    electricity = { induction_order = 2 },
    -- The coils are air-cored, so magnetic_forces would take them as
    -- current sheets (near_field, on by default since session 20); the
    -- spokes' poles pass their faces 1.5 mm off, by the sheet's rim, where
    -- its field turns within millimetres: at 1/240 s the coupling's books
    -- then miss 0.157 J of 3.59 J over 10 s (0.062 J at 1/480 s, 0.021 J at
    -- 1/960 s). The pole pair until the scene is retuned for that
    -- (docs/magnetism.md "A coil's near field").
    magnetic_forces = { near_field = false },
  },
}

require "generator.layout" { weight = true }
