return {
  name = "space",
  version = "0.1.0",
  description = "The paper's planet and orbit: uniform gravity on a launch tower, N-body gravity in orbit",
  depends = { "kit" },
  scene = "scene.lua",
}
