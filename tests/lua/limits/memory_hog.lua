-- A scene that allocates without end: the host's memory budget must stop it
-- with an InputError, not the machine.
local hoard = {}
local i = 0
while true do
  i = i + 1
  hoard[i] = { i, i, i, i }
end
