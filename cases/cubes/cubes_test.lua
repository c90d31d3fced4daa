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
print("cubes_test: all checks passed")
