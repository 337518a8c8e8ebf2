-- expect: line 3: require "../../secrets": a module name is a mod name
-- Only mods by name: no paths.
local secrets = require "../../secrets"
