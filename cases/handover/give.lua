-- Arm A of the handover: picks the cube from the table, carries it to the handover pose,
-- offers it (signal "offered"), lets go once arm B holds it ("taken") and retreats
-- ("released"). Parameters: the cell's fixtures (handover.lua, M.fixtures).
local H = require("handover")
local F = H.fixtures(PARAMS)
local g = H.setup(PARAMS.gripper or "gripper_a")

local function at(p, yaw) return frame(p) * rotz(yaw) * H.DOWN end   -- tool down, turned by yaw (deg)

-- from wherever the arm starts, to the known park pose first
g:open(H.OPEN)
movej(H.PARK)

-- the cube lies within a few mm and degrees of its nominal place: a first grasp with the jaws
-- across world x centres it in x (and squares its yaw), a second across world y in y, so that
-- it ends centred between the pads in both, whatever its start
local grasp = F.cube + vec3(0, 0, H.OFFSET)   -- the TCP 10 mm above its centre
movej(at(grasp + vec3(0, 0, H.LIFT), 90))
assert(H.jaws_open(g), "gripper A did not open")
movel(at(grasp, 90), {v = H.V_NEAR})
-- centring needs both pads on the cube, not a square hold: a cube turned 10 deg may still
-- stand slanted between them (its opening then above the square hold's 53 mm)
g:close(H.GRIP)
assert(wait(function() return g:grasped() end, 2.0), "A: the jaws did not close on the cube to centre it")
wait(0.2)
g:open(H.OPEN)
assert(H.jaws_open(g), "gripper A did not open")
-- a quarter turn of the tool about its axis, 5 cm up: the open pads (34 mm from the axis)
-- would sweep through the cube's vertical edges (35.4 mm from its centre) at grasp height
local clear = vec3(0, 0, 0.05)
movel(at(grasp + clear, 90), {v = H.V_NEAR})
movel(at(grasp + clear, 0))
movel(at(grasp, 0), {v = H.V_NEAR})
local ok, why = H.close_on_cube(g)
assert(ok, "A: no grasp (" .. tostring(why) .. ")")
print("A: holding the cube")
movel(at(grasp + vec3(0, 0, H.LIFT), 0), {v = H.V_NEAR})

-- to the handover: the tool horizontal toward arm B (tool z = world +x), the jaws still across
-- world y; the cube's centre OFFSET ahead of the TCP, at the handover point
local give = frame(F.hand - vec3(H.OFFSET, 0, 0), roty(-90) * H.DOWN)
movej(give * trans(0, 0, -H.LIFT))
movel(give)
signal("offered")
print("A: offered")

assert(wait_signal("taken", 30), "A: arm B did not take the cube within 30 s")
g:open(H.OPEN)
assert(H.jaws_open(g), "gripper A did not open")
movel(give * trans(0, 0, -H.LIFT), {v = H.V_NEAR})   -- straight back along its tool
signal("released")
print("A: released")
movej(H.PARK)
