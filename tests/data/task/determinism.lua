-- Visits string-keyed waypoints in pairs() order, with a random pause between
-- them: the log is the same byte for byte only if pairs' order and
-- math.random are the same from run to run (notes/task-language.md).
local down = rpy(180, 0, 0)
local points = {west = vec3(0.60, 0.10, 0.50), east = vec3(0.60, -0.10, 0.50),
                north = vec3(0.70, 0.0, 0.50), south = vec3(0.50, 0.0, 0.50),
                up = vec3(0.60, 0.0, 0.58)}
speed(0.3, 90)
for name, p in pairs(points) do
  movel(frame(p) * down)
  wait(math.random() * 0.1)
end
