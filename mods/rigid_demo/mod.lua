return {
  name = "rigid_demo",
  version = "0.1.0",
  description = "The rigid body in the 2D play area: a pendulum, disks rolling down a ramp, a bouncing ball, a pinned wheel",
  depends = { "kit" },
  scene = "scene.lua",
}
