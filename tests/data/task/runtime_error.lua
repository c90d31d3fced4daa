-- fails at line 5 after 0.5 s
local function deeper(t)
  wait(0.5)
  local f = frame(0.5, 0, 0.5)
  return f * t.missing
end
deeper({})
