-- A scene that never ends, even when its own pcall catches the budget's
-- error: the host's instruction budget must stop it.
local n = 0
while true do
  pcall(function()
    while true do n = n + 1 end
  end)
end
