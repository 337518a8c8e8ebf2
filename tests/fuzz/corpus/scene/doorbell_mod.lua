return {
  name = "doorbell",
  version = "0.1.0",
  description = "The paper's doorbell (4.1) from kit parts: battery, switch, electromagnet, interrupter striker, bell",
  depends = { "kit" },
  scene = "scene.lua",
}
