return {
  name = "hoist",
  version = "0.1.0",
  description = "The motor (mods/motor) winds a string on its axle and lifts a load; the string is a part of its own",
  depends = { "kit", "motor" },
  main = "init.lua",        -- the string, a part for scenes
  runtime = "runtime.lua",  -- its physics: the winding, and the tension on its two ends
  scene = "scene.lua",
}
