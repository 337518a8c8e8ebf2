return {
  name = "motor",
  version = "0.1.0",
  description = "The paper's electric motor (4.2) from kit parts: a rotor of eight magnet spokes, a sliding contact, two electromagnets, a bias magnet",
  depends = { "kit" },
  scene = "scene.lua",
}
