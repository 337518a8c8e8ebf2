return {
  name = "two_engines",
  version = "0.1.0",
  description = "Two tables side by side, the left on ODE and the right on Box2D, and a ball rolling from one to the other",
  depends = { "kit" },
  scene = "scene.lua",
}
