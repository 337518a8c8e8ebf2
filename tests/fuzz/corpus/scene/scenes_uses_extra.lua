-- Needs the mod "extra", found only through LoadOptions::mod_paths.
local extra = require "extra"
object { name = "thing", position = { 0, extra.height }, shape = "sphere", radius = 0.1, mass = 1 }
