-- A scene that runs out of memory inside its own pcall and tries to go on:
-- the refused allocation still refuses the scene.
local ok = pcall(function()
  local s = "x"
  while true do s = s .. s end
end)
world { dt = 1 / 100 }
return ok
