-- square.lua: the PA10 traces a 0.20 m square in a horizontal plane, tool
-- pointing down, turning its tool by 45 deg on one side; then a circular arc
-- and back home. Runs unchanged in the lab (scenes/pa10_task.yaml), under
-- vlab run as an external controller (scenes/pa10_task_external.yaml) and
-- against vlab-kinsim (vlab task ... --arm HOST:PORT).
local home = joints()                          -- the start posture, deg
print("start at", pose())
speed(0.2)                                     -- m/s along straight lines
local down = rpy(180, 0, 0)                    -- tool z pointing down
local corner = frame(0.50, -0.10, 0.55) * down
movej(corner)                                  -- joint interpolation to a frame (IK)
movel(frame(0.50, 0.10, 0.55) * down * rotz(45))   -- straight line, SLERP to 45 deg
movel(frame(0.60, 0.10, 0.55) * down)
movel(frame(0.60, -0.10, 0.55) * down)
movel(corner)
local arc_end = frame(0.50, 0.10, 0.55) * down
movec(vec3(0.55, 0.0, 0.60), arc_end)          -- circular arc through a via point
local reached = wait(function() return (pose().pos - arc_end.pos):norm() < 0.002 end, 2.0)
assert(reached, "the arm did not reach the arc's end")
shared.done = true
movej(home)
print("done at", pose())
