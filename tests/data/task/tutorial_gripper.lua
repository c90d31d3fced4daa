-- docs/tasks.md's tutorial, steps 1-6, on the PA10 with the JR3 and the parallel gripper
-- (scenes/pa10_gripper.xml, keyframe home): the TCP is the gripper's, 0.133 m beyond the
-- tool site (mjcf/gripper/README.md)
tool(trans(0, 0, 0.133))
-- 1
print("tool at", pose())
print("joints", table.concat(joints(), ", "))
-- 2
local down = rpy(180, 0, 0)
local pick = frame(0.60, -0.15, 0.425) * down
local place = frame(0.60, 0.15, 0.425) * down * rotz(90)
local above = trans(0, 0, -0.10)
-- 3
speed(0.2)
movej(pick * above)
movel(pick)
movel(pick * above)
-- 4
if movel(pick * trans(0, 0, 0.05), {v = 0.03, force = 10}) == "contact" then
  local touched = pose()
  print("touched at", touched.pos)
  movel(touched * trans(0, 0, -0.005))
end
-- 5
local g = gripper("gripper")
g:open(0.068)
wait(function() return g:opening() > 0.065 end, 2.0)
movel(pick)
g:close(30)
assert(wait(function() return g:grasped() end, 2.0), "no grasp")
movel(pick * above)
-- 6
movel(place * above)
movel(place)
g:open(0.068)
wait(0.5)
movel(place * above)
shared.placed = place
signal("placed")
print("placed at", now())
