-- word.lua: spell a word with the lettered cubes (cases/cubes/README.md). A module: a stage
-- script sets the word and the slots and calls run{...} (spell.lua).
--   LOOK    the arm parked out of the webcam's picture; every visible marker of a few frames
--           fused into cube poses (any face's marker gives the whole cube)
--   PLAN    the letters in the word's order, each to its slot; the grasp yaw that sets the
--           letter down reading along the slot, with the jaws across the row
--   PICK    above the cube, straight down, close with a force, require `grasped` and an
--           opening of about a cube
--   PLACE   above the slot, turned, down to just above the table, open, up
--   TURN    (alphabet blocks) a letter that faces sideways or down is tumbled a quarter turn
--           about a horizontal axis, in place, once or twice, and looked at again
--   VERIFY  park, look again; a letter out of its slot or turned is picked and placed once more
local cubes = require("cubes")
local M = {}

local DOWN = rpy(180, 0, 0)

-- settings, with where each number comes from
local S = {
  tcp = 0.133,          -- m, gripper_tcp along the tool z (mjcf/gripper/README.md)
  open = 0.068,         -- m, the gripper's full opening (cube 50 mm: 9 mm per side)
  grip_force = 30,      -- N: 20-40 N holds 87.5 g with pads of friction 1.0 many times over
  grasp_min = 0.046,    -- m: opening on a held cube (50 mm squeezed 0.4 mm per pad at 72 N) -
  grasp_max = 0.053,    --    a cube grasped across, not on an edge or a corner (71 mm)
  lift = 0.12,          -- m above a cube's centre for travel: jaw tips 0.10 m above its top
  grasp_up = 0.003,     -- m: the TCP this far above the cube's centre (jaw tips 8 mm off the table)
  tumble_up = 0.010,    -- m: the TCP this far above the cube's centre with the tool tilted 45 deg: the
                        -- jaw's lower corner (20 mm beyond the TCP along the tool, 15 mm along the jaw's
                        -- width) lies 24.7 mm below the TCP, so 10 mm off the table; the housing face
                        -- (40 mm back along the tool) 12 mm clear of the cube's nearest edge
  place_up = 0.002,     -- m: set down with the cube's bottom this far above the table
  v = 0.30, w = 90,     -- m/s, deg/s on paths
  jv = 90, ja = 180,    -- deg/s, deg/s^2 joint moves: a PA10 device file's JointVelLimit 90,
                        -- JointAccLimit 180 (DATASHEET; under Choreonoid's 180 deg/s)
  v_near = 0.08,        -- m/s for the last 12 cm down and up
  frames = 3,           -- webcam frames fused per look
  frame_timeout = 2.0,  -- s of simulated time to wait for one
  -- VERIFY redoes a letter seen farther than these from its slot; each is its check's bound
  -- (stage1.yaml) less what the look may be off at the slot row (fused positions within 0.6 mm,
  -- reading directions within 0.6 deg there: README) and a margin
  pos_tolerance = 0.003,  -- m (check: 5 mm)
  yaw_tolerance = 3,      -- deg, reading direction (check: 5 deg)
  tilt_tolerance = 1.5,   -- deg, top face against level (check: 2 deg)
}
M.settings = S

local function say(...) print(string.format("[%7.2f s]", now()), ...) end

-- LOOK: park, then fuse `frames` webcam frames
local function look(vis, park)
  movej(park)
  local states = {}
  for i = 1, S.frames do
    -- a frame that never reaches the vision program (a real camera drops some) is an error
    -- after 10 s of wall time; the next frame will do
    local ok, m = pcall(vis.next, vis, S.frame_timeout)
    if not ok then
      say("look: " .. tostring(m) .. "; taking the next frame")
      m = vis:next(S.frame_timeout)
    end
    assert(m, "no markers from the vision program within " .. S.frame_timeout .. " s")
    states[#states + 1] = m
  end
  return cubes.fuse(states, M.table_z)   -- the cubes rest on the table: cubes.fuse's prior
end

-- a tool frame at `p` (vec3) with yaw `yaw` (deg), tool z down
local function at(p, yaw) return frame(p) * rotz(yaw) * DOWN end

-- turns the tool in place to `yaw` (deg) with the last wrist joint W2 alone: its axis is the
-- tool z (pointing down), so W2 + a turns the tool by -a about world z and the TCP stays put;
-- of the two ways round, the one that leaves W2 nearer 0 (range +-255 deg). Turning by
-- inverse kinematics instead spreads the turn over the roll joints S3 and E2 (the
-- minimum-norm step), and a few turns walk S3 into its limit.
local function turn_to(yaw)
  local _, _, now_yaw = pose():rpy()
  local d = cubes.wrap(yaw - now_yaw)
  local other = d > 0 and d - 360 or d + 360
  local q = joints()
  if math.abs(q[7] - other) < math.abs(q[7] - d) then d = other end
  q[7] = q[7] - d
  movej(q)
end

-- the arm's redundancy back to S3 = 0 with the tool held still (a null-space move): straight-line
-- paths solve the inverse kinematics by minimum-norm steps, which let the elbow drift about the
-- shoulder-wrist line; over a few letters S3 or S1 walked into its limit
local function relax()
  local s3 = joints()[3]
  if math.abs(s3) > 5 then selfmove{joint = 3, by = -s3, t = math.max(0.5, math.abs(s3) / 45)} end
end

-- waits until the jaws stand open (after g:open), at most 2 s
local function jaws_open(g) return wait(function() return g:opening() > S.open - 0.004 end, 2.0) end

-- closes the jaws on the cube between them with the grip force: true when they hold it
-- (`grasped` within 2 s, an opening of a cube held across two faces); else opens them again
-- and returns false and what it found
local function close_on_cube(g)
  g:close(S.grip_force)
  local held = wait(function() return g:grasped() end, 2.0)
  wait(0.2)
  local w = g:opening()
  if held and w >= S.grasp_min and w <= S.grasp_max then return true end
  g:open(S.open)
  jaws_open(g)
  return false, string.format("grasped %s, opening %.1f mm", tostring(held), w * 1000)
end

-- PICK: the cube `c` (from cubes.describe) with the tool at `yaw`
local function pick(g, c, yaw)
  local above = at(c.pos + vec3(0, 0, S.lift), yaw)
  local grasp = at(vec3(c.pos.x, c.pos.y, math.max(c.pos.z, M.table_z + cubes.EDGE / 2) + S.grasp_up), yaw)
  g:open(S.open)
  relax()
  turn_to(yaw)
  movel(above)
  jaws_open(g)
  movel(grasp, {v = S.v_near})
  local held, why = close_on_cube(g)
  movel(above, {v = S.v_near})
  if not held then return false, "no grasp (" .. why .. ")" end
  return true
end

-- PLACE: the held cube onto `slot` (a frame) with the tool at `yaw`
local function place(g, slot, yaw)
  local over = at(slot.pos + vec3(0, 0, S.lift), yaw)
  local down = at(vec3(slot.pos.x, slot.pos.y, M.table_z + cubes.EDGE / 2 + S.place_up + S.grasp_up), yaw)
  relax()
  turn_to(yaw)
  movel(over)
  movel(down, {v = S.v_near})
  g:open(S.open)
  jaws_open(g)
  movel(over, {v = S.v_near})
end

-- how far a seen cube is from its slot: xy distance (m) and reading-direction error (deg)
local function slot_error(c, slot)
  local d = c.pos - slot.pos
  local slot_up = slot.rot * vec3(0, 1, 0)
  local goal = math.atan(slot_up.y, slot_up.x) * 180 / math.pi
  return math.sqrt(d.x * d.x + d.y * d.y), math.abs(cubes.wrap(c.up_yaw - goal)), goal
end

-- one letter from where it is seen to its slot; true, or false and why
local function move_letter(g, letter, c, slot)
  local _, _, goal = slot_error(c, slot)
  local theta_c = math.atan(c.pos.y, c.pos.x) * 180 / math.pi
  local theta_s = math.atan(slot.pos.y, slot.pos.x) * 180 / math.pi
  -- jaws across the row at the slot: along the slot's letter-up axis (either sense)
  local jaw = goal
  local yaw_pick, yaw_place = cubes.grasp_yaws(c.up_yaw, goal, 180 + theta_c, 180 + theta_s, {jaw, jaw + 180})
  say(string.format("%s: at (%.3f, %.3f) top face %d, letter up %.0f deg: grasp yaw %.0f, place yaw %.0f",
                    letter, c.pos.x, c.pos.y, c.top, c.up_yaw, yaw_pick, yaw_place))
  local ok, why = pick(g, c, yaw_pick)
  if not ok then return false, why end
  place(g, slot, yaw_place)
  return true
end

-- TURN, a quarter turn (cubes.tumble_rotation): grasp the cube where it lies with the tool
-- tilted 45 deg over it from the side of the face at yaw `alpha` (jaws across the faces beside
-- it), lift it back along the tool, turn the last wrist joint half a turn (W2's axis is the tool
-- z, so the TCP stays put) and set it down where it was: that face ends on top. The TCP
-- `tumble_up` above the cube's centre, so that the jaws clear the table. True, or false and
-- why; the planner's error (out of reach, a joint limit) when the tilted pose cannot be
-- reached, raised before the cube is touched.
local function tumble(g, c, alpha)
  local centre = vec3(c.pos.x, c.pos.y, M.table_z + cubes.EDGE / 2 + S.tumble_up)
  local grasp = frame(centre, cubes.tumble_rotation(alpha))
  local back = trans(0, 0, -S.lift)   -- the approach: back along the tool's z
  g:open(S.open)
  relax()
  turn_to(alpha)
  movel(at(centre + vec3(0, 0, S.lift), alpha))
  movel(grasp * back)   -- the first tilted pose: a planning error here leaves the cube untouched
  jaws_open(g)
  movel(grasp, {v = S.v_near})
  local held, why = close_on_cube(g)
  movel(grasp * back, {v = S.v_near})
  if not held then return false, "no grasp to turn it (" .. why .. ")" end
  -- half a turn of W2, the way that leaves it nearer 0 (range +-255 deg)
  local q = joints()
  q[7] = (math.abs(q[7] + 180) < math.abs(q[7] - 180)) and q[7] + 180 or q[7] - 180
  movej(q)
  local set = frame(centre + vec3(0, 0, S.place_up), grasp.rot) * rotz(180)
  movel(set, {v = S.v_near})
  g:open(S.open)
  jaws_open(g)
  movel(set * back, {v = S.v_near})
  return true
end

-- the cube turned about the vertical (picked, and set down where it lies or at `dest`, a vec3)
-- so that its face at yaw `from` (deg) ends at yaw `to`; the jaws across a pair of its faces,
-- closing along one of `jaws` (deg, at the pick; default: any pair)
local function turn_in_place(g, c, from, to, dest, jaws)
  local here = frame(dest or vec3(c.pos.x, c.pos.y, c.pos.z))
  local theta = math.atan(c.pos.y, c.pos.x) * 180 / math.pi
  local turn = to - from
  local place_jaws = {}
  for _, j in ipairs(jaws or {from, from + 90, from + 180, from + 270}) do place_jaws[#place_jaws + 1] = j + turn end
  local yaw_pick, yaw_place = cubes.grasp_yaws(from, to, 180 + theta, 180 + theta, place_jaws)
  local ok, why = pick(g, c, yaw_pick)
  if not ok then return false, why end
  place(g, here, yaw_place)
  return true
end

-- TURN: until the letter is on top (at most three quarter turns and one turn in place, each
-- followed by a look). The tilted tool reaches a cube anywhere on the table when it leans from
-- a side across the line to the arm's base (yaw base +- 90 deg), a far cube also from the
-- side toward the base, and no cube from the side away from it (measured on a grid of the
-- placement region: the elbow E1 or the shoulder S2 at its limit, or out of reach). A letter
-- facing sideways is tumbled from its side; one facing away from the base (more than 135 deg
-- from the base's direction), or whose tumble is out of reach, is first turned in place to face
-- across. A letter facing down is tumbled from the side face nearest to base + 90 deg, which
-- leaves it facing the opposite way (within 45 deg of base - 90 deg), and then from there.
-- Returns the cube as seen with the letter on top.
local function upright(g, vis, park, letter, c)
  local turned_in_place = false
  for _ = 1, 4 do
    if c.face == c.top then return c end
    local base = math.atan(-c.pos.y, -c.pos.x) * 180 / math.pi   -- yaw from the cube toward the base
    local alpha
    if c.normal.z < -0.5 then
      -- from the side face whose normal is nearest to across (base + 90 deg): the jaws must
      -- close across a pair of faces
      local best = math.huge
      for f = 0, 5 do
        local n = c.pose.rot * cubes.FACES[f].n
        if math.abs(n.z) < 0.5 then
          local yaw = math.atan(n.y, n.x) * 180 / math.pi
          local off = math.abs(cubes.wrap(yaw - base - 90))
          if off < best then best, alpha = off, yaw end
        end
      end
    else
      alpha = math.atan(c.normal.y, c.normal.x) * 180 / math.pi
    end
    -- across: the nearer of base +- 90 deg
    local across = cubes.wrap(base + (cubes.wrap(alpha - base) >= 0 and 90 or -90))
    local ok, done, why = false, nil, "facing away from the arm"
    if math.abs(cubes.wrap(alpha - base)) <= 135 then
      say(string.format("%s: at (%.3f, %.3f) on face %d, face %d on top; tumbling it from yaw %.0f deg", letter,
                        c.pos.x, c.pos.y, c.face, c.top, alpha))
      ok, done, why = pcall(tumble, g, c, alpha)
      if not ok then why = tostring(done) end
    end
    if not ok then
      -- the tilted pose is out of reach (the cube untouched, the arm above it), or would be
      assert(not turned_in_place, letter .. ": cannot tumble it: " .. why)
      say(string.format("%s: cannot tumble it from yaw %.0f deg (%s); turning it in place to face %.0f deg",
                        letter, alpha, why, across))
      done, why = turn_in_place(g, c, alpha, across)
      turned_in_place = true
    end
    if not done then say(letter .. ": " .. why) end
    local seen = look(vis, park)
    c = assert(seen[letter], "letter " .. letter .. " not seen after turning its cube")
  end
  assert(c.face == c.top, letter .. ": still not on top after turning its cube")
  return c
end

-- run{word = "FACE", slots = {frame, ...}, park = {deg x 7}, table_z = m}: spells the word;
-- error (the run fails) when a letter is not seen or cannot be placed after one retry
function M.run(p)
  M.table_z = p.table_z
  if p.faces then cubes.set_faces(p.faces) end
  tool(trans(0, 0, S.tcp))
  speed(S.v, S.w)
  jspeed(S.jv, S.ja)
  local vis = markers(p.vision or "vision")
  local g = gripper(p.gripper or "gripper")
  assert(#p.slots >= #p.word, "the word '" .. p.word .. "' has more letters than there are slots")

  -- LOOK and PLAN: the word's letters in order, each to the slot of its position
  local seen = look(vis, p.park)
  local times = {}
  local origins = {}   -- per letter, where its cube was picked from
  for i = 1, #p.word do
    local letter = p.word:sub(i, i)
    local t0 = now()
    local c = seen[letter]
    if not c then
      -- hidden, or its markers too small or oblique to be valid: the letters moved since may
      -- have uncovered it
      say(letter .. ": not seen; looking again")
      seen = look(vis, p.park)
      c = seen[letter]
    end
    assert(c, "letter " .. letter .. " not seen by the webcam")
    c = upright(g, vis, p.park, letter, c)
    origins[letter] = vec3(c.pos.x, c.pos.y, c.pos.z)
    local ok, why = move_letter(g, letter, c, p.slots[i])
    if not ok then
      say(letter .. ": " .. why .. "; looking again")
      seen = look(vis, p.park)
      c = assert(seen[letter], "letter " .. letter .. " not seen after a failed grasp")
      c = upright(g, vis, p.park, letter, c)
      assert(move_letter(g, letter, c, p.slots[i]), letter .. ": no grasp after a second look")
    end
    times[#times + 1] = now() - t0
    say(string.format("%s placed in %.1f s", letter, now() - t0))
  end

  -- VERIFY: look again; redo a letter once
  seen = look(vis, p.park)
  local redo = false
  for i = 1, #p.word do
    local letter = p.word:sub(i, i)
    local c = seen[letter]
    local d, a = math.huge, math.huge
    if c then d, a = slot_error(c, p.slots[i]) end
    say(string.format("verify %s: %.1f mm, %.1f deg from slot %d", letter, d * 1000, a, i))
    if not c then
      say("verify " .. letter .. ": not seen (no valid marker); left as it is")
    elseif d > S.pos_tolerance or a > S.yaw_tolerance or c.tilt > S.tilt_tolerance or c.face ~= c.top then
      if c.face ~= c.top then
        -- the letter turned away in the slot: back where it came from (free since) to be turned
        -- there; a tumble in the row would reach into the neighbours' 20 mm gaps
        say(string.format("verify %s: on face %d, face %d on top; back to (%.3f, %.3f) to turn it", letter, c.face,
                          c.top, origins[letter].x, origins[letter].y))
        -- the jaws across the row (along the letter's up on the top face), as when it was placed
        assert(turn_in_place(g, c, c.up_yaw, c.up_yaw, origins[letter], {c.up_yaw, c.up_yaw + 180}),
               letter .. ": could not take it out of its slot")
        seen = look(vis, p.park)
        c = assert(seen[letter], "letter " .. letter .. " not seen after taking it out of its slot")
        c = upright(g, vis, p.park, letter, c)
      end
      assert(move_letter(g, letter, c, p.slots[i]), letter .. ": the retry could not grasp it")
      redo = true
    end
  end
  if redo then
    seen = look(vis, p.park)
    for i = 1, #p.word do
      local letter = p.word:sub(i, i)
      local c = seen[letter]
      if c then
        local d, a = slot_error(c, p.slots[i])
        say(string.format("after the retry %s: %.1f mm, %.1f deg", letter, d * 1000, a))
      else
        say("after the retry " .. letter .. ": not seen")
      end
    end
  end
  local total = 0
  for _, t in ipairs(times) do total = total + t end
  say(string.format("spelled %s: %.1f s per letter", p.word, total / #times))
  movej(p.park)
end

return M
