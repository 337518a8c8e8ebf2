-- Parts from another mod: objects made inside the helper mod belong to the
-- lines of this file that called it.
local helper = require "helper"
local kit = require "kit"

kit.floor { name = "floor", at = { 0, -0.05 }, size = { 2, 0.1 } }
helper.pendulum("p", { 0, 1 }, 0.5)
kit.lever { name = "lever", at = { 1, 1 } }
