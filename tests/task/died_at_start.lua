-- prints, then dies in its first period (tests/task/task_output_cli_test.cc)
print("starting")
local q = joints()
movej({q[1], q[2], q[3], q[4], q[5], q[6], q[7]}, {w = 0.5})  -- movej takes v, a or t, not w
