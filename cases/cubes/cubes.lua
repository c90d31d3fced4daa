-- cubes.lua: the lettered cubes' geometry and what vision tells about them (mjcf/cubes/README.md).
-- Pure functions of values: no motion, no devices; word.lua uses them.
local M = {}

M.EDGE = 0.050            -- m, cube edge
M.MARKER_UP = -0.0078125  -- m, marker centre along the face's "up" from the face centre
-- the letters on faces 0-5 of each cube (cube i, 0-based, is entry i + 1; marker id = 6 i + face):
-- by default the lettered cubes A-F of mjcf/cubes (a cube's letter on every face); M.set_faces
-- for the alphabet blocks of mjcf/cubes/blocks (a different letter on every face)
M.CUBE_FACES = {"AAAAAA", "BBBBBB", "CCCCCC", "DDDDDD", "EEEEEE", "FFFFFF"}

-- faces: a list of six-letter strings, one per cube, the letters of its faces 0-5 (the
-- blocks' README table, the text `<body>.faces` of their assets); a letter on two cubes is an error
function M.set_faces(faces)
  local where = {}
  for i, f in ipairs(faces) do
    assert(#f == 6, "cube " .. i .. ": '" .. f .. "' is not six letters (faces 0-5)")
    for k = 1, 6 do
      local letter = f:sub(k, k)
      assert(where[letter] == nil or where[letter] == i, "letter " .. letter .. " on cubes " .. tostring(where[letter]) .. " and " .. i)
      where[letter] = i
    end
  end
  M.CUBE_FACES = faces
end

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

-- letter of a marker id (the letter on the marker's face), its cube index and face; nil for
-- an id that is no cube's
function M.decode(id)
  if id < 0 or id >= 6 * #M.CUBE_FACES then return nil end
  local cube, face = id // 6, id % 6
  return M.CUBE_FACES[cube + 1]:sub(face + 1, face + 1), cube, face
end

local function deg(rad) return rad * 180 / math.pi end

-- wraps an angle to (-180, 180], deg
function M.wrap(a)
  a = math.fmod(a + 180, 360)
  if a <= 0 then a = a + 360 end
  return a - 180
end

-- Fuses the markers of one or more vision states into cube poses: every valid marker with a
-- world pose gives its whole cube (X_wc = X_wm X_cm^-1). Per cube: the centre is the mean
-- of the estimates weighted by 1 / (error + 0.1 px), the rotation that of the estimate with
-- the smallest reprojection error; `seen` counts the estimates. The result is keyed by
-- letter: every letter of a seen cube, with the face that carries it (`face`; on a cube with
-- its letter on every face, the face on top).
--
-- With `rest_z` (the table top, m), cubes are known to rest on it, and that prior is used:
-- * A marker whose face lies flat (its normal within FLAT_DEG of vertical or of horizontal)
--   and whose cube centre comes out within HEIGHT_TOL of its resting height has its rotation
--   snapped to exactly flat (the smallest turn) and its position moved along the camera's
--   ray through it to where the cube centre lies at its resting height. The depth of a
--   small marker is its least certain coordinate (1-2 % of the range from its apparent
--   size: a 16 px marker 0.9 m away measured 17 mm deep along the ray, 12 mm in x); the
--   ray's direction is certain to a fraction of a pixel.
-- * A cube with no valid marker may still be found from markers that vlab vision flags
--   invalid only because the two poses a square admits fit about equally well (small,
--   distant markers: docs/vision.md), if their fit is within MAX_ERROR and the reported pose
--   passes the same test. The other pose is the first mirrored about the line of sight, its
--   normal turned by about twice the viewing angle (35-55 deg from a resting cube's faces to
--   this webcam): a top face's mirror lies near horizontal, a side face's near vertical, but
--   then the cube's centre comes out 25-33 mm off its resting height, which the test refuses.
M.MAX_ERROR = 1.0     -- px: vlab vision's default --max-error
M.FLAT_DEG = 15       -- deg
M.HEIGHT_TOL = 0.018  -- m: a depth error of 2 % at 0.9 m moves the centre 12 mm in height
local function flat_normal(n)
  if math.abs(n.z) >= math.cos(M.FLAT_DEG * math.pi / 180) then return vec3(0, 0, n.z > 0 and 1 or -1) end
  if math.abs(n.z) <= math.sin(M.FLAT_DEG * math.pi / 180) then return vec3(n.x, n.y, 0):normalized() end
  return nil
end

-- the cube pose from marker m on `face`, resting on rest_z: nil when its face does not lie
-- flat or its centre is not near the resting height
local function resting_cube(m, face, rest_z)
  local X_cm_inv = M.marker_in_cube(face):inv()
  local raw = m.world * X_cm_inv
  local n = m.world.rot * vec3(0, 0, 1)
  local target = flat_normal(n)
  local centre_z = rest_z + M.EDGE / 2
  if not target or math.abs(raw.pos.z - centre_z) > M.HEIGHT_TOL then return nil end
  local turned = frame(m.world.rot)
  local axis = n:cross(target)
  if axis:norm() > 1e-12 then
    turned = angleaxis(math.deg(math.atan(axis:norm(), n:dot(target))), axis:normalized()) * turned
  end
  local rot = turned.rot
  local v = rot * X_cm_inv.pos                 -- marker centre -> cube centre, world
  local cam = (m.world * m.camera:inv()).pos   -- the camera's origin
  local d = m.world.pos - cam
  local s = (centre_z - v.z - cam.z) / d.z
  return frame(cam + d * s + v, rot * X_cm_inv.rot)
end

function M.fuse(states, rest_z)
  local acc, prior = {}, {}
  local function add(into, cube, X, err)
    local w = 1 / (err + 0.1)
    local a = into[cube]
    if not a then
      a = {sum = vec3(0, 0, 0), weight = 0, seen = 0, best = math.huge}
      into[cube] = a
    end
    a.sum = a.sum + X.pos * w
    a.weight = a.weight + w
    a.seen = a.seen + 1
    if err < a.best then a.best, a.rot = err, X.rot end
  end
  for _, s in ipairs(states) do
    for _, m in ipairs(s.markers) do
      local letter, cube, face = M.decode(m.id)
      if letter and m.world then
        local resting = rest_z and m.camera and resting_cube(m, face, rest_z)
        if m.valid then
          add(acc, cube, resting or m.world * M.marker_in_cube(face):inv(), m.error)
        elseif resting and m.error <= M.MAX_ERROR then
          add(prior, cube, resting, m.error)
        end
      end
    end
  end
  for cube, a in pairs(prior) do
    if not acc[cube] then
      acc[cube] = a
      a.ambiguous = true
    end
  end
  local cubes = {}
  for cube, a in pairs(acc) do
    local faces = M.CUBE_FACES[cube + 1]
    for f = 0, 5 do
      local letter = faces:sub(f + 1, f + 1)
      if not cubes[letter] then
        -- a letter on every face: the one on top; else the face that carries it
        local every = faces == letter:rep(6)
        cubes[letter] = M.describe(frame(a.sum / a.weight, a.rot), not every and f or nil)
        cubes[letter].seen = a.seen
        cubes[letter].cube = cube
        cubes[letter].ambiguous = a.ambiguous or false
      end
    end
  end
  return cubes
end

-- What a cube pose means for the task: the face on top, how far it tilts (deg), the yaw of
-- its letter's up (deg, world, about z: 0 = +x) and of its reading direction; the face that
-- carries the letter (`face`, default the top) and its outward normal in the world (`normal`).
function M.describe(X, face)
  local best, top = -2, 0
  for f = 0, 5 do
    local z = (X.rot * FACES[f].n).z
    if z > best then best, top = z, f end
  end
  local up = X.rot * FACES[top].up
  local right = X.rot * FACES[top].right
  face = face or top
  return {pose = X, pos = X.pos, top = top, tilt = deg(math.acos(math.min(1, best))),
          up_yaw = deg(math.atan(up.y, up.x)), right_yaw = deg(math.atan(right.y, right.x)),
          face = face, normal = X.rot * FACES[face].n}
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

-- A tumble turns a cube a quarter turn about a horizontal axis, so that its face whose outward
-- normal points along yaw `alpha` (deg, world) ends on top: grasped with the jaws closing along
-- that axis (across the faces at alpha +- 90 deg) and the tool tilted 45 deg over the cube from
-- the side of that face, lifted back along the tool, turned half a turn about the tool's own
-- axis (the last wrist joint alone) and set down where it was. The tool rotation at the grasp
-- (tool z = its approach direction; jaws closing along the tool y, as in grasp_yaws):
--   R = Rz(alpha) Ry(45) Rx(180)
-- and the held cube turns by R Rz(180) R^-1, half a turn about the tilted tool axis u: v goes to
-- 2 (u.v) u - v, so the face at yaw alpha goes up, the face on top to yaw alpha, the face down
-- to yaw alpha + 180. The tool keeps its lean: where the grasp reaches, so does the set-down.
M.TUMBLE_TILT = 45   -- deg: the tool's tilt from straight down
function M.tumble_rotation(alpha)
  return rotz(alpha) * roty(M.TUMBLE_TILT) * rpy(180, 0, 0)
end

return M
