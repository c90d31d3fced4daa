-- Force mode: find the table, press it with PARAMS.force N (default 10) and move 5 cm
-- along it. The tool's z points down (the ready pose), so pressing down is +fz.
local F = PARAMS.force or 10
force_zero()                                             -- out of contact: the tool's weight is the zero
local outcome, touched = search(vec3(0, 0, -1), {force = 2, max = 0.06, v = 0.01})
assert(outcome == "contact", "no table below the tool")
print(string.format("touched the table at z = %.6f m", touched.z))
force_mode({fz = F})                                     -- press: along the tool's z
wait(1.0)                                                -- the force settles (phase: settle)
movel_rel(trans(0.05, 0, 0), {rel = "base", v = 0.01, a = 0.02})  -- 5 cm along the table (phase: slide)
wait(0.5)                                                -- (phase: hold)
end_force_mode()
movel_rel(trans(0, 0, 0.03), {rel = "base"})             -- off the table
