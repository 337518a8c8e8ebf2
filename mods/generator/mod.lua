return {
  name = "generator",
  version = "0.1.0",
  description = "The motor's rotor turned by a hand on a crank: its magnets induce a current in the coils that lights a lamp",
  depends = { "kit", "motor" },  -- the motor's rotor (motor.rotor)
  runtime = "runtime.lua",  -- a hand on a crank: a torque on a part (drive_torque)
  scene = "scene.lua",
}
