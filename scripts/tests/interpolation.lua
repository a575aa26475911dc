-- Keyframe interpolation: keys hold their range unless slopes are given (issue 16, item 6).
local function peak(seq, dof, from, to)
  local best = -math.huge
  for i = 0, 200 do
    best = math.max(best, seq:value(dof, from + (to - from) * i / 200))
  end
  return best
end

test("a hold between two keys stays a hold by default", function()
  local keys = { {0, 0}, {1, 1}, {2, 1}, {3, 0} }
  local cubic = troupe.sequence{ r_elbow_flexion = keys }
  local hermite = troupe.sequence{ r_elbow_flexion = keys, interpolation = "hermite" }
  expect(cubic:interpolation("r_elbow_flexion") == "cubic", "cubic is the default")
  expect(peak(cubic, "r_elbow_flexion", 0, 3) == 1.0, "peaks at its key, got " .. peak(cubic, "r_elbow_flexion", 0, 3))
  expect(peak(hermite, "r_elbow_flexion", 0, 3) > 1.1, "the thesis slopes overshoot")
  -- Played on an actor, the elbow never passes the key either.
  local ann = troupe.actor{ name = "ann" }
  ann:play(cubic)
  local most = 0
  for _ = 1, 300 do
    run(0.01)
    most = math.max(most, ann:dof("r_elbow_flexion"))
  end
  expect(most <= 1.0, "the played elbow stays at or under 1.0, got " .. most)
  expect(most > 0.99, "and reaches it")
end)

test("the bundled wave stays within its keys", function()
  local wave = troupe.sequence("../examples/wave.trk")
  expect(peak(wave, "r_shoulder_abduction", 0, 3) <= 1.9, "shoulder at most 1.9 rad")
  local old = troupe.sequence("../examples/wave.trk", { interpolation = "hermite" })
  expect(peak(old, "r_shoulder_abduction", 0, 3) > 2.2, "the old slopes swung to about 2.28 rad")
end)

test("given slopes are exact; linear and step ignore them", function()
  local s = troupe.sequence{ x = { {0, 0, 2}, {1, 1, 2} } }
  -- Hermite with slopes 2 and 2 from 0 to 1: at 0.25, 2·s³ − 3·s² + 1 … = 0.34375.
  expect(math.abs(s:value("x", 0.25) - 0.34375) < 1e-12, "exact Hermite, got " .. s:value("x", 0.25))
  local linear = troupe.sequence{ x = { {0, 0, 2}, {1, 1, 2} }, interpolation = "linear" }
  expect(linear:value("x", 0.25) == 0.25, "a straight line")
  local step = troupe.sequence{ x = { {0, 0}, {1, 1}, {2, 3} }, interpolation = "step" }
  expect(step:value("x", 0.99) == 0 and step:value("x", 1.5) == 1, "holds the earlier key")
end)

test("an unknown interpolation or track is an error naming it", function()
  local ok, err = pcall(troupe.sequence, { x = { {0, 0} }, interpolation = "spline" })
  expect(not ok and tostring(err):find("unknown interpolation `spline`"), tostring(err))
  ok, err = pcall(troupe.sequence, "../examples/wave.trk", { interp = "linear" })
  expect(not ok and tostring(err):find("interp"), tostring(err))
  ok, err = pcall(function() return troupe.sequence{ x = { {0, 0} } }:value("y", 0) end)
  expect(not ok and tostring(err):find("no track for `y`"), tostring(err))
end)
