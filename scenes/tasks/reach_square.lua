-- reach_square.lua: the path of scenes/pa10_reach.yaml (built-in task_space
-- controller) written in the task language: the same waypoints and segment
-- times, after the same 0.5 s hold. vlab bench task compares the two.
wait(0.5)
movel(frame(0.50, -0.15, 0.50) * rpy(180, 0, 0), {t = 2.0})
movel(frame(0.50, 0.15, 0.50) * rpy(180, 0, 45), {t = 2.5})
movel(frame(0.50, 0.15, 0.75) * rpy(180, 0, 45), {t = 2.5})
movel(frame(0.50, -0.15, 0.75) * rpy(160, 0, 0), {t = 2.5})
movel(frame(0.50, -0.15, 0.50) * rpy(180, 0, 0), {t = 2.5})
