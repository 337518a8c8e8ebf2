-- expect: line 3: mod 'sneaky' requires 'kit' but its mod.lua does not list it in depends
-- mods/sneaky uses the kit without declaring it.
local sneaky = require "sneaky"
