-- payload(): set and read back the same way in process (payload.yaml) and over UDP (vlab task
-- --arm against vlab-kinsim); bad arguments are errors naming the argument.
-- Checked by tests/task/task_cli_test.cc
local p = payload()
print("payload before", p.mass, #p.com, #p.inertia)
payload(1.25, {com = {0, 0, 0.1}, inertia = {0.01, 0.01, 0.005}})
p = payload()
print("payload after", p.mass, p.com[3], p.inertia[1], p.inertia[3], p.inertia[4])
for _, bad in ipairs({{-1}, {"heavy"}, {1, {com = {0, 0}}}, {1, {inertia = {0.01, 0.01, 0.03}}}, {1, {mass = 2}}}) do
  local ok, err = pcall(payload, table.unpack(bad))
  print("payload refused", ok, err)
end
