-- A guarded move: straight down toward the table at 10 mm/s until the JR3
-- feels 10 N more than at the start (force-controlled touch), then hold.
local start = pose()
local outcome = movel(start * trans(0, 0, 0.06), {v = 0.01, force = 10})  -- tool z points down
print(outcome, "stopped", (pose().pos - start.pos):norm() * 1000, "mm below the start")
assert(outcome == "contact", "no contact: the table was not found")
shared.touched = pose().z
wait(0.5)
