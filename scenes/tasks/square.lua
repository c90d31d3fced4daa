-- square.lua: the PA10 traces a 0.20 m square in a horizontal plane, tool
-- pointing down, turning its tool by 45 deg on one side; then a circular arc,
-- a self-motion of the elbow with the tool held, and back home. In the lab:
-- scenes/pa10_task.yaml; over UDP: vlab task scenes/tasks/square.lua --arm
-- HOST:PORT --scene scenes/pa10.xml --tip tool.
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
wait(0.5)                                      -- let the servo settle after the arc
local held = pose()
selfmove{joint = 3, by = 40, t = 3}                 -- S3 by 40 deg: the elbow swings, the tool stays
print("tool moved", (pose().pos - held.pos):norm() * 1000, "mm during selfmove")
assert((pose().pos - held.pos):norm() < 1e-4, "selfmove: the tool moved 0.1 mm or more")
assert(pose().rot:angle(held.rot) < 0.0573, "selfmove: the tool turned 1 mrad (0.0573 deg) or more")
movej(home)
print("done at", pose())
