-- The lettered-cubes task of every stage (cases/cubes/README.md): spell a word with the cubes
-- of scenes/pa10_cubes_gripper.xml (stage 1: FACE; stage 3 the same against vlab-kinsim) or the
-- alphabet blocks of scenes/pa10_blocks_gripper.xml (stage 2: WORD), the other cubes lying
-- about as distractors. The word, the slots and the cubes' letters are the scenario's (its
-- controller command: vlab task --param word=FACE --param slots_x=... --param slots_y=...
-- --param slots_z=... [--param faces=AGMSY4,...]): PARAMS.
local function numbers(text)
  local out = {}
  for item in string.gmatch(text, "[^,]+") do out[#out + 1] = assert(tonumber(item), "not a number: " .. item) end
  return out
end
local word = assert(PARAMS.word, "PARAMS.word: the word to spell (--param word=FACE)")
local ys = numbers(assert(PARAMS.slots_y, "PARAMS.slots_y: the slots' y, comma separated"))
assert(#ys == #word, "PARAMS.slots_y: " .. #ys .. " slots for the " .. #word .. " letters of " .. word)
-- the letters on faces 0-5 of each cube, cube by cube (marker id = 6 cube + face): the alphabet
-- blocks' (mjcf/cubes/blocks/README.md); without it, the lettered cubes A-F (a letter on every face)
local faces = nil
if PARAMS.faces then
  faces = {}
  for item in string.gmatch(PARAMS.faces, "[^,]+") do faces[#faces + 1] = item end
end
local slots = {}
-- the scene's slot sites slot_1..slot_4: 70 mm apart along world +y at x 0.68, a cube's
-- centre height, frame = the reading frame (x: reading direction +y, y: letter up -x)
for i, y in ipairs(ys) do slots[i] = frame(PARAMS.slots_x, y, PARAMS.slots_z) * rotz(90) end
require("word").run{
  word = word,
  slots = slots,
  faces = faces,
  park = {0, -40, 0, 110, 0, 110, 0},   -- deg: the scene's keyframe 'park'
  table_z = 0.20,                       -- m: the scene's table top
}
