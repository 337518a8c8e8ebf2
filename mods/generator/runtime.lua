-- A hand on a crank, as a stage of the world: a part that carries
-- `drive_torque` is turned by that torque, every step, for as long as it
-- carries it (the scene's timeline sets it, changes it, takes it away).
-- Nothing here knows what the part is connected to: on the generator's
-- crank it turns a rotor of magnets past two coils, and the lamp lights
-- because of the induction, not because of anything said here.

mod.property { name = "drive_torque", kind = "vec3", unit = "N m",
               doc = "a torque applied to this part every step (a hand on a crank), world frame" }

mod.interaction {
  name = "rigid_body_from_drive",
  doc = "a part carrying drive_torque is turned by it",
  reads = { "drive_torque" },
  needs = { "drive_torque" },
  target = "rigid_body",
  apply = function(w)
    local torque = w:read("drive_torque")
    for i in torque:each() do w.target.add_torque(i, torque[i]) end
  end,
}
