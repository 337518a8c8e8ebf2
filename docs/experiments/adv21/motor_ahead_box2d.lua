-- adv21: on Box2D (use). The bundled motor (mods/motor) with electricity_from_collisions' `ahead`
-- on: a spoke that reaches the slider within half a step is connected at the
-- step before the collisions set sees it (docs/electricity.md "Contacts
-- between steps"). SceneRestore.MotorWithContactsAhead restores it mid-run.
world {
  name = "motor_contacts_ahead",
  dt = 1 / 240, use = { rigid_body = "rigid_body.box2d" },
  seconds = 10,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 2 },
    electricity_from_collisions = { ahead = true },
  },
}

local motor = require "motor.layout" ()
for _, slider in ipairs(motor.sliders) do at(motor.slider_release, slider, { pinned = false }) end
