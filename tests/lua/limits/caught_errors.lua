-- Ten thousand errors, each caught by the scene's own pcall: a few
-- instructions each to the count hook, microseconds each to the host. The
-- host charges a caught error as 2,000 instructions, so a budget of 10
-- million stops this scene (without the charge it would finish).
local n = 0
for i = 1, 10000 do
  pcall(function() n = n + undefined_global end)
  xpcall(function() error("again") end, function(m) return m end)
end
world { dt = 1 / 100 }
