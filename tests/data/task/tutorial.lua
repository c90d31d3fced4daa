-- docs/tasks.md, tutorial steps 1-4 as they are written there
print("tool at", pose())
print("joints", table.concat(joints(), ", "))
local down = rpy(180, 0, 0)
local pick = frame(0.60, -0.15, 0.425) * down
local place = frame(0.60, 0.15, 0.425) * down * rotz(90)
local above = trans(0, 0, -0.10)
speed(0.2)
movej(pick * above)
movel(pick)
movel(pick * above)
if movel(pick * trans(0, 0, 0.05), {v = 0.03, force = 10}) == "contact" then
  local touched = pose()
  print("touched at", touched.pos)
  movel(touched * trans(0, 0, -0.005))
end
movel(place * above)
