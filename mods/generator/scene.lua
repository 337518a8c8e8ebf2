-- The generator: a hand turns the crank with a steady 20 mN m from 0.2 s;
-- the rotor speeds up until the bearing and the lamp take all of it, and the
-- lamp glows brighter as it goes. At 6 s the hand lets go: the rotor runs
-- down, and the lamp with it. `alloy run mods/generator` reports the speed
-- and the lamp's power; docs/light.md says what to look for.
world {
  name = "generator",
  description = "the motor's rotor turned by a hand on a crank lights a lamp through its coils",
  dt = 1 / 240,
  seconds = 10,
  report = { "axle.angular_velocity.z@1", "lamp.radiant_power@1" },
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

require "generator.layout" ()

at(0.2, "crank", { drive_torque = { 0, 0, 0.02 } })
at(6, "crank", { drive_torque = { 0, 0, 0 } })
