-- Stage 1 of the lettered-cubes task (cases/cubes/stage1.yaml): spell FACE with the cubes of
-- scenes/pa10_cubes_gripper.xml, B and D lying about as distractors.
require("word").run{
  word = "FACE",
  -- the scene's slot sites slot_1..slot_4: 70 mm apart along world +y at x 0.68, a cube's
  -- centre height, frame = the reading frame (x: reading direction +y, y: letter up -x)
  slots = {frame(0.68, -0.105, 0.225) * rotz(90), frame(0.68, -0.035, 0.225) * rotz(90),
           frame(0.68, 0.035, 0.225) * rotz(90), frame(0.68, 0.105, 0.225) * rotz(90)},
  park = {0, -40, 0, 110, 0, 110, 0},   -- deg: the scene's keyframe 'park'
  table_z = 0.20,                       -- m: the scene's table top
}
