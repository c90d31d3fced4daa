-- Arm B of the handover: waits at its approach pose until arm A offers the cube ("offered"),
-- grasps it across the faces A leaves free, says so ("taken"), waits until A has let go and
-- backed off ("released"), and sets the cube down at the goal. Parameters: the cell's
-- fixtures (handover.lua, M.fixtures).
local H = require("handover")
local F = H.fixtures(PARAMS)
local g = H.setup(PARAMS.gripper or "gripper_b")

-- B's tool at the handover: z along world -x (toward arm A), y along world z, so its jaws
-- close across the cube's top and bottom faces while A's hold the two faces across world y
local FACING_A = rotm{{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}
local take = frame(F.hand + vec3(H.OFFSET, 0, 0), FACING_A)

g:open(H.OPEN)
movej(H.PARK)
movej(take * trans(0, 0, -H.LIFT))
assert(H.jaws_open(g), "gripper B did not open")

assert(wait_signal("offered", 60), "B: arm A offered nothing within 60 s")
movel(take, {v = H.V_NEAR})
local ok, why = H.close_on_cube(g)
assert(ok, "B: no grasp at the handover (" .. tostring(why) .. ")")
signal("taken")
print("B: taken")

assert(wait_signal("released", 30), "B: arm A did not let go within 30 s")
-- tool down over the goal: the same turn as A's, the other way (a quarter turn about world y);
-- the cube's centre OFFSET below the TCP, set down 2 mm above the table
local DOWN_B = roty(-90) * FACING_A
local place = frame(F.goal + vec3(0, 0, H.OFFSET + 0.002), DOWN_B)
movel(take * trans(0, 0, -0.05), {v = H.V_NEAR})   -- back along its tool, out of A's way
movej(place * trans(0, 0, -H.LIFT))
movel(place, {v = H.V_NEAR})
g:open(H.OPEN)
assert(H.jaws_open(g), "gripper B did not open")
movel(place * trans(0, 0, -H.LIFT), {v = H.V_NEAR})
print("B: placed")
movej(H.PARK)
