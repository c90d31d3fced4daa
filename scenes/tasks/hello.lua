-- hello.lua: a short task for the PA10 that runs the same way in the lab
-- (scenes/pa10_task_hello.yaml), under vlab run as an external controller
-- (scenes/pa10_task_hello_external.yaml) and against vlab-kinsim:
--   build/vlab-kinsim --scene scenes/pa10.xml --port 50100 &
--   build/vlab task scenes/tasks/hello.lua --arm 127.0.0.1:50100 --scene scenes/pa10.xml --tip tool
local start = pose()                            -- the tool frame, measured
print("start", start)
speed(0.25, 90)                                 -- 0.25 m/s and 90 deg/s on paths
local goal = frame(0.60, 0.10, 0.45) * rpy(180, 0, 150)
movel(goal)                                     -- straight line, orientation by SLERP
local near = wait(function() return (pose().pos - goal.pos):norm() < 0.001 end, 1.0)
assert(near, "the tool did not settle within 1 mm of the goal")
movec(vec3(0.65, 0.0, 0.50), start)             -- back to the start on a circular arc
wait(0.1)
print("back", pose(), "error (mm):", (pose().pos - start.pos):norm() * 1000)
assert((pose().pos - start.pos):norm() < 0.002, "not back within 2 mm")
