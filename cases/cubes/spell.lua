-- Stage 1 of the lettered-cubes task (cases/cubes/stage1.yaml): spell a word (FACE there) with
-- the cubes of scenes/pa10_cubes_gripper.xml, the other cubes lying about as distractors.
-- The word and the slots are the scenario's (its controller command: vlab task --param
-- word=FACE --param slots_x=... --param slots_y=... --param slots_z=...): PARAMS.
local function numbers(text)
  local out = {}
  for item in string.gmatch(text, "[^,]+") do out[#out + 1] = assert(tonumber(item), "not a number: " .. item) end
  return out
end
local word = assert(PARAMS.word, "PARAMS.word: the word to spell (--param word=FACE)")
local ys = numbers(assert(PARAMS.slots_y, "PARAMS.slots_y: the slots' y, comma separated"))
assert(#ys == #word, "PARAMS.slots_y: " .. #ys .. " slots for the " .. #word .. " letters of " .. word)
local slots = {}
-- the scene's slot sites slot_1..slot_4: 70 mm apart along world +y at x 0.68, a cube's
-- centre height, frame = the reading frame (x: reading direction +y, y: letter up -x)
for i, y in ipairs(ys) do slots[i] = frame(PARAMS.slots_x, y, PARAMS.slots_z) * rotz(90) end
require("word").run{
  word = word,
  slots = slots,
  park = {0, -40, 0, 110, 0, 110, 0},   -- deg: the scene's keyframe 'park'
  table_z = 0.20,                       -- m: the scene's table top
}
