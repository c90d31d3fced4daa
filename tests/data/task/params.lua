-- PARAMS reach a script the same way in process (params.yaml: the program's `params`) and
-- standalone (vlab task --param): prints them typed; checked by tests/task/task_cli_test.cc
for name, value in pairs(PARAMS) do print("param", name, math.type(value) or type(value), value) end
assert(PARAMS.word == "FACE" and PARAMS.letters == 4 and PARAMS.pitch == 0.07 and PARAMS.verify == true)
