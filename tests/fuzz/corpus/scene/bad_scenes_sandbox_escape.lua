-- expect: line 3: attempt to index global 'io' (a nil value)
-- Scenes cannot reach files.
local f = io.open("/etc/passwd")
