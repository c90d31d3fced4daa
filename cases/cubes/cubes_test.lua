-- cubes_test.lua: checks of cubes.lua against closed forms (run by cases/cubes/tests,
-- test cubes_lua: a program without a robot; an assert ends the run with exit 1).
local cubes = require("cubes")

local function near(a, b, tol, what) assert(math.abs(a - b) <= tol, string.format("%s: %.12g vs %.12g", what, a, b)) end
local function near_vec(a, b, tol, what) assert((a - b):norm() <= tol, what .. ": " .. tostring(a) .. " vs " .. tostring(b)) end

-- wrap to (-180, 180]
near(cubes.wrap(190), -170, 1e-12, "wrap 190")
near(cubes.wrap(-180), 180, 1e-12, "wrap -180")
near(cubes.wrap(540), 180, 1e-12, "wrap 540")
near(cubes.wrap(-30), -30, 1e-12, "wrap -30")

-- decode: id = 6 i + f
local l, i, f = cubes.decode(20)
assert(l == "D" and i == 3 and f == 2, "decode 20")
assert(cubes.decode(36) == nil and cubes.decode(-1) == nil, "ids outside the set")

-- marker frames: origin half an edge out along the normal and 7.8125 mm down the face's up;
-- z = the normal, x = the image right, y = the image up (right-handed)
for face = 0, 5 do
  local F = cubes.FACES[face]
  local X = cubes.marker_in_cube(face)
  near_vec(X.pos, F.n * 0.025 + F.up * -0.0078125, 1e-15, "marker origin " .. face)
  near_vec(X.rot * vec3(0, 0, 1), F.n, 1e-12, "marker z " .. face)
  near_vec(X.rot * vec3(1, 0, 0), F.right, 1e-12, "marker x " .. face)
  near_vec(F.right:cross(F.up), F.n, 1e-15, "right x up = normal " .. face)
end

-- fuse: markers made from a known pose give that pose back, whichever faces are seen
local X = frame(0.61, -0.12, 0.2245) * rpy(90, 0, 37)   -- face 3 (-Y) down, yaw 37 deg
local markers = {}
for face = 0, 5 do
  markers[#markers + 1] = {id = 6 * 2 + face, valid = true, error = 0.1 * (face + 1), world = X * cubes.marker_in_cube(face)}
end
markers[#markers + 1] = {id = 6 * 4 + 1, valid = false, error = 9, world = frame(0, 0, 0)}  -- invalid: ignored
markers[#markers + 1] = {id = 40, valid = true, error = 0.1, world = frame(0, 0, 0)}        -- not a cube's: ignored
local seen = cubes.fuse({{markers = markers}})
assert(seen.C and not seen.E and seen.C.seen == 6, "fuse: cube C from six markers, nothing else")
near_vec(seen.C.pos, X.pos, 1e-12, "fused centre")
near(seen.C.pose.rot:angle(X.rot), 0, 1e-6, "fused rotation")
-- the face on top is +Y (face 2), opposite the one down; its letter's up is the cube's -Z
assert(seen.C.top == 2, "top face " .. seen.C.top)
near(seen.C.tilt, 0, 1e-6, "tilt")
local up = X.rot * vec3(0, 0, -1)
near(seen.C.up_yaw, math.atan(up.y, up.x) * 180 / math.pi, 1e-9, "letter-up yaw")

-- a cube lying as in its model frame: +Z on top, letter up = +Y (yaw 90), right = +X (yaw 0)
local d = cubes.describe(frame(0.5, 0, 0.2245))
assert(d.top == 4, "top of the model frame")
near(d.up_yaw, 90, 1e-9, "up yaw")
near(d.right_yaw, 0, 1e-9, "right yaw")

-- grasp and place yaws: the tool turns by exactly the letter's turn to the goal, the jaws close
-- across the slot row at the place (tool yaw -+90 for jaws along world x) and along a cube
-- axis at the pick (jaw direction = tool yaw - 90, a multiple of 90 deg from the letter's up)
for _, phi in ipairs({-170, -91, -45, 0, 12.5, 90, 179}) do
  local pick, place, turn = cubes.grasp_yaws(phi, 180, 180, 180, {180, 0})
  near(cubes.wrap(place - pick - (180 - phi)), 0, 1e-9, "turn " .. phi)
  near(turn, cubes.wrap(180 - phi), 1e-12, "turn value " .. phi)
  assert(math.abs(math.abs(place) - 90) < 1e-9, "place yaw " .. place)
  local k = (pick - 90 - phi) / 90
  near(k, math.floor(k + 0.5), 1e-9, "jaws along a cube axis at " .. phi)
end
-- the resting prior (fuse with the table top): a webcam at (1.15, 0, 0.90) looking down at the
-- table (the scene's), cubes resting on a 0.20 m table (centres at 0.225 m)
local REST = 0.20
local CAM = frame(1.15, 0, 0.90) * rpy(0, 141.8, 0)   -- any rotation: only its origin matters here
local function seen_from(world)   -- a marker state as vlab vision gives it: world and camera frames
  return world, CAM:inv() * world
end
local function marker(id, valid, err, world)
  local w, c = seen_from(world)
  return {id = id, valid = valid, error = err, world = w, camera = c}
end
local Y = frame(0.55, 0.2, 0.225) * rotz(30)          -- resting, face 4 (+Z) on top
local top = Y * cubes.marker_in_cube(4)

-- a valid marker 17 mm too deep along the camera's ray and tilted 3 deg: moved back along the
-- ray to the resting height, its rotation snapped flat; the cube exactly where it is
local ray = (top.pos - CAM.pos):normalized()
local off = frame(top.pos + ray * 0.017) * angleaxis(3, vec3(1, 0, 0)) * frame(top.rot)
seen = cubes.fuse({{markers = {marker(6 * 0 + 4, true, 0.2, off)}}}, REST)
near_vec(seen.A.pos, Y.pos, 1e-9, "depth corrected along the ray")
near(seen.A.pose.rot:angle(Y.rot), 0, 1e-6, "rotation snapped flat")
-- without the table: the estimate as measured
seen = cubes.fuse({{markers = {marker(6 * 0 + 4, true, 0.2, off)}}})
assert((seen.A.pos - Y.pos):norm() > 0.010, "no prior without the table top")

-- markers flagged invalid: a cube with no valid marker is found from those whose fit is
-- within MAX_ERROR and whose face lies flat at the resting height; ignored: a mirrored pose
-- (normal 70 deg off), a bad fit, a side face's mirror that looks like a top face (normal
-- vertical, centre 25 mm low), and any invalid marker of a cube that has a valid one
local side = Y * cubes.marker_in_cube(0)   -- face 0, normal horizontal
local side_as_top = frame(side.pos, top.rot)
seen = cubes.fuse({{markers = {
  marker(6 * 0 + 4, false, 0.3, top),                                              -- A: flat, used
  marker(6 * 1 + 4, false, 0.3, Y * cubes.marker_in_cube(4) * roty(70)),            -- B: mirrored, ignored
  marker(6 * 2 + 4, false, 1.5, top),                                              -- C: bad fit, ignored
  marker(6 * 3 + 4, true, 0.2, top),                                               -- D: valid ...
  marker(6 * 3 + 0, false, 0.1, frame(0.9, 0.9, 0.225) * cubes.marker_in_cube(0)), -- ... its invalid one ignored
  marker(6 * 4 + 0, false, 0.1, side_as_top),                                      -- E: a side face as a top: ignored
}}}, REST)
assert(seen.A and seen.A.ambiguous and not seen.B and not seen.C and seen.D and not seen.D.ambiguous and not seen.E,
       "invalid markers")
near_vec(seen.A.pos, Y.pos, 1e-9, "cube from a flat invalid marker")
near_vec(seen.D.pos, Y.pos, 1e-9, "a valid marker's cube ignores its invalid ones")

-- alphabet blocks (mjcf/cubes/blocks/README.md): the letter of a marker is its face's
cubes.set_faces({"AGMSY4", "BHNTZ5", "CIOU06", "DJPV17", "EKQW28", "FLRX39"})
local l2, i2, f2 = cubes.decode(6 * 3 + 2)
assert(l2 == "P" and i2 == 3 and f2 == 2, "decode a block's face: " .. tostring(l2))
assert(not pcall(cubes.set_faces, {"ABCDEF", "AGHIJK"}), "a letter on two blocks is refused")
-- every letter of a seen block, with the face that carries it and that face's world normal:
-- block 4 (DJPV17) at X (face 3, letter V, down; face 2, letter P, on top)
markers = {}
for face = 0, 5 do
  markers[#markers + 1] = {id = 6 * 3 + face, valid = true, error = 0.2, world = X * cubes.marker_in_cube(face)}
end
seen = cubes.fuse({{markers = markers}})
assert(seen.D and seen.J and seen.P and seen.V and seen["1"] and seen["7"] and not seen.A, "fuse: the six letters of block 4")
assert(seen.P.face == 2 and seen.P.top == 2 and seen.V.face == 3 and seen.D.face == 0, "faces of the letters")
near_vec(seen.V.normal, vec3(0, 0, -1), 1e-9, "V faces down")
near_vec(seen.P.normal, vec3(0, 0, 1), 1e-9, "P faces up")
near_vec(seen.D.normal, X.rot * vec3(1, 0, 0), 1e-12, "D faces along the block's +X")
cubes.set_faces({"AAAAAA", "BBBBBB", "CCCCCC", "DDDDDD", "EEEEEE", "FFFFFF"})

-- tumbles: the face at yaw alpha goes up, the top face to yaw alpha, the bottom to alpha + 180;
-- the jaws (tool y) close along the horizontal axis at alpha + 90 deg; the tool z leans toward
-- the cube from the side of the face at alpha (direction (-cos alpha, -sin alpha) horizontally)
for _, alpha in ipairs({-135, -30, 0, 77, 180}) do
  local r = cubes.tumble_rotation(alpha)
  local turn = r * rotz(180) * r:inv()
  local a = alpha * math.pi / 180
  local side = vec3(math.cos(a), math.sin(a), 0)
  near_vec(turn * side, vec3(0, 0, 1), 1e-12, "side face up, alpha " .. alpha)
  near_vec(turn * vec3(0, 0, 1), side, 1e-12, "top face to alpha, alpha " .. alpha)
  near_vec(turn * vec3(0, 0, -1), side * -1, 1e-12, "bottom face to alpha + 180, alpha " .. alpha)
  local axis = vec3(-math.sin(a), math.cos(a), 0)
  near(math.abs((r * vec3(0, 1, 0)):dot(axis)), 1, 1e-12, "jaws along the axis, alpha " .. alpha)
  local z = r * vec3(0, 0, 1)
  near(z.z, -math.cos(math.pi / 4), 1e-12, "tilt, alpha " .. alpha)
  near(z:dot(side), -math.sin(math.pi / 4), 1e-12, "leans from the face's side, alpha " .. alpha)
end
print("cubes_test: all checks passed")
