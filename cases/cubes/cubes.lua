-- cubes.lua: the lettered cubes' geometry and what vision tells about them (mjcf/cubes/README.md).
-- Pure functions of values: no motion, no devices; word.lua uses them.
local M = {}

M.EDGE = 0.050            -- m, cube edge
M.MARKER_UP = -0.0078125  -- m, marker centre along the face's "up" from the face centre
M.LETTERS = "ABCDEF"      -- cube i (0-based) carries letter i+1; marker id = 6 i + face

-- per face 0-5: outward normal, the printed image's right and up (box frame; README table)
local FACES = {
  [0] = {n = vec3(1, 0, 0), right = vec3(0, 0, -1), up = vec3(0, 1, 0)},
  [1] = {n = vec3(-1, 0, 0), right = vec3(0, 0, 1), up = vec3(0, 1, 0)},
  [2] = {n = vec3(0, 1, 0), right = vec3(1, 0, 0), up = vec3(0, 0, -1)},
  [3] = {n = vec3(0, -1, 0), right = vec3(1, 0, 0), up = vec3(0, 0, 1)},
  [4] = {n = vec3(0, 0, 1), right = vec3(1, 0, 0), up = vec3(0, 1, 0)},
  [5] = {n = vec3(0, 0, -1), right = vec3(-1, 0, 0), up = vec3(0, 1, 0)},
}
M.FACES = FACES

-- the marker frame of face f in the cube frame: x = image right, y = image up, z = normal
function M.marker_in_cube(f)
  local F = FACES[f]
  local r, u, n = F.right, F.up, F.n
  local R = rotm{{r.x, u.x, n.x}, {r.y, u.y, n.y}, {r.z, u.z, n.z}}
  return frame(n * (M.EDGE / 2) + u * M.MARKER_UP, R)
end

-- letter of a marker id, its cube index and face; nil for an id that is no cube's
function M.decode(id)
  if id < 0 or id >= 6 * #M.LETTERS then return nil end
  local cube = id // 6
  return M.LETTERS:sub(cube + 1, cube + 1), cube, id % 6
end

local function deg(rad) return rad * 180 / math.pi end

-- wraps an angle to (-180, 180], deg
function M.wrap(a)
  a = math.fmod(a + 180, 360)
  if a <= 0 then a = a + 360 end
  return a - 180
end

-- Fuses the markers of one or more vision states into cube poses: every valid marker with a
-- world pose gives its whole cube (X_wc = X_wm X_cm^-1). Per letter: the centre is the mean
-- of the estimates weighted by 1 / (error + 0.1 px), the rotation that of the estimate with
-- the smallest reprojection error; `seen` counts the estimates.
function M.fuse(states)
  local acc = {}
  for _, s in ipairs(states) do
    for _, m in ipairs(s.markers) do
      local letter, _, face = M.decode(m.id)
      if letter and m.valid and m.world then
        local X = m.world * M.marker_in_cube(face):inv()
        local w = 1 / (m.error + 0.1)
        local a = acc[letter]
        if not a then
          a = {sum = vec3(0, 0, 0), weight = 0, seen = 0, best = math.huge}
          acc[letter] = a
        end
        a.sum = a.sum + X.pos * w
        a.weight = a.weight + w
        a.seen = a.seen + 1
        if m.error < a.best then a.best, a.rot = m.error, X.rot end
      end
    end
  end
  local cubes = {}
  for letter, a in pairs(acc) do
    cubes[letter] = M.describe(frame(a.sum / a.weight, a.rot))
    cubes[letter].seen = a.seen
  end
  return cubes
end

-- What a cube pose means for the task: the face on top, how far it tilts (deg), the yaw of
-- its letter's up (deg, world, about z: 0 = +x) and of its reading direction.
function M.describe(X)
  local best, top = -2, 0
  for f = 0, 5 do
    local z = (X.rot * FACES[f].n).z
    if z > best then best, top = z, f end
  end
  local up = X.rot * FACES[top].up
  local right = X.rot * FACES[top].right
  return {pose = X, pos = X.pos, top = top, tilt = deg(math.acos(math.min(1, best))),
          up_yaw = deg(math.atan(up.y, up.x)), right_yaw = deg(math.atan(right.y, right.x))}
end

-- The tool yaws (deg, the tool frame = rpy(180, 0, yaw): tool z down, jaws closing along
-- (sin yaw, -cos yaw, 0)) that grasp a cube with letter-up yaw `up_yaw` and set it down with
-- its letter-up at `goal_up_yaw`, the jaws closing along `place_jaw_yaws` there (deg, the
-- directions allowed at the slot). The cube turns with the tool: place = grasp + (goal - up).
-- Of the candidates, the one nearest `natural_pick` and `natural_place` (the yaws with the
-- wrist's last joint near 0).
function M.grasp_yaws(up_yaw, goal_up_yaw, natural_pick, natural_place, place_jaw_yaws)
  local turn = M.wrap(goal_up_yaw - up_yaw)
  local best, pick, place = math.huge, nil, nil
  for _, jaw in ipairs(place_jaw_yaws) do
    local p = M.wrap(jaw + 90)     -- tool yaw whose jaws close along `jaw`
    local g = M.wrap(p - turn)
    local cost = math.abs(M.wrap(g - natural_pick)) + math.abs(M.wrap(p - natural_place))
    if cost < best then best, pick, place = cost, g, p end
  end
  return pick, place, turn
end

return M
