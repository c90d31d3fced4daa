-- Marker poses from a script: reads the vision program's markers of a camera frame,
-- prints every valid one (the test compares them with the cubes' true poses), and
-- moves the tool above the first valid marker of cube C, so that what vision saw
-- steers the arm (and shows in the log).
wait(0.6)                                   -- the cubes settle in 0.5 s (docs/vision.md)
local vis = markers("vision")
local function show(m)
  print(string.format("frame %d %.6f %d %d", m.seq, m.time, #m.markers, m.described))
  for _, k in ipairs(m.markers) do
    if k.valid and k.world then
      local p, q = k.world.pos, k.world.rot
      print(string.format("marker %s %d %.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.4f", k.dictionary, k.id, m.time,
                          p.x, p.y, p.z, q.w, q.x, q.y, q.z, k.error))
    end
  end
end
local t0 = now()
local m = vis:next(1.0)
assert(m, "no markers state within 1 s")
assert(m.time >= t0, "a frame exposed before the call")
show(m)
local target
for _, k in ipairs(m.markers) do
  if k.valid and k.world and k.id >= 12 and k.id < 18 and not target then target = k end   -- cube C: ids 12-17
end
assert(target, "no valid marker of cube C")
jspeed(60)
movej(frame(target.world.pos + vec3(0, 0, 0.10)) * rpy(180, 0, 180))
print(string.format("above cube C at t = %.3f s", now()))
local l = vis:latest()
assert(l and l.time >= m.time, "latest(): older than the frame next() returned")
show(vis:next())                            -- the next frame, from above cube C
