-- Rune stones: a physics that is not real and still cooperates with the real
-- ones. Mana flows between touching stones like a current; a lift rune that
-- has filled up lights and floats until it has spent its mana, then falls
-- back and charges again.
return {
  name = "magic",
  version = "0.1.0",
  description = "Rune stones: mana flows between touching stones; charged lift runes float",
  depends = { "kit" },
  main = "init.lua",        -- the parts (kit.define), for scenes
  runtime = "runtime.lua",  -- the physics (property types, resolver, derived set, interactions)
  scene = "scene.lua",
}
