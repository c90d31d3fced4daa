print("never runs")
for i = 1, 3 do
  movel(frame(0.5, 0, 0.5)
end
