-- What both programs of the handover share: the cell's fixtures (from PARAMS, as a real cell
-- knows them: no ground truth), the gripper's numbers and the tool frames. README.md has the
-- geometry and where each number comes from.
local M = {}

M.TCP = 0.133          -- m: the grasp centre between the pads beyond the tool site (mjcf/gripper/README.md)
M.EDGE = 0.050         -- m: the cube's edge (scenes/pa10_handover.xml)
M.OPEN = 0.068         -- m: the jaws fully open (2 x 34 mm stroke, mjcf/gripper/README.md)
M.GRIP = 30            -- N on each pad (the cubes task's grip, cases/cubes/word.lua)
M.GRASP_MIN, M.GRASP_MAX = 0.046, 0.053   -- m: an opening that holds the cube across two faces
M.LIFT = 0.12          -- m: approach and retreat distances, along the tool
M.V_NEAR = 0.08        -- m/s: the last 12 cm of every approach and the first of every retreat
M.OFFSET = 0.010       -- m: each TCP stays this far short of the cube's centre along its tool z,
                       -- so that the two grippers' jaws overlap the cube without meeting
M.PARK = {0, -40, 0, 110, 0, 110, 0}   -- deg: folded back and up, tool down (both arms' start region)

-- tool z straight down, tool x along world x: the jaws close along world y
M.DOWN = rpy(180, 0, 0)

-- the cell's frames (world, m) from the program's parameters
function M.fixtures(p)
  local need = function(k) return assert(p[k], "missing parameter " .. k .. " (scenario: programs[].params)") end
  return {
    cube = vec3(need("cube_x"), need("cube_y"), need("table_z") + M.EDGE / 2),   -- nominal start
    goal = vec3(need("goal_x"), need("goal_y"), need("table_z") + M.EDGE / 2),   -- B sets it here
    hand = vec3(need("hand_x"), need("hand_y"), need("hand_z")),                   -- handover: its centre
  }
end

-- the arm's settings: the gripper's TCP as the tool, the speeds of the cubes task
function M.setup(name)
  tool(trans(0, 0, M.TCP))
  speed(0.25, 90)
  jspeed(60, 120)
  return gripper(name)
end

-- waits until the jaws stand open, at most 2 s
function M.jaws_open(g)
  return wait(function() return g:opening() > M.OPEN - 0.004 end, 2.0)
end

-- closes on the cube between the jaws; true when they hold it across two faces (the
-- gripper's own `grasped` within 2 s, then its opening), else false and what it found
function M.close_on_cube(g)
  g:close(M.GRIP)
  local held = wait(function() return g:grasped() end, 2.0)
  wait(0.2)
  local w = g:opening()
  if held and w >= M.GRASP_MIN and w <= M.GRASP_MAX then return true end
  return false, string.format("grasped %s, opening %.1f mm", tostring(held), w * 1000)
end

return M
