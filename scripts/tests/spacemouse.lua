-- A SpaceMouse moves an object: the example's recording (push right 2 s, twist 1 s, lift
-- 1 s, at 0.25 m/s and 90°/s at full deflection) replayed by scene time.

local rec = "../examples/spacemouse.rec"

test("the replayed SpaceMouse moves the crate 0.5 m right and 0.25 m up, then stops", function()
  local crate = troupe.object{ name = "crate", shape = "box", size = {0.3, 0.3, 0.3}, at = {0, 1, 0} }
  expect(troupe.devices.spacemouse{ object = crate, replay = rec, speed = 0.25, turn = 90 } == "spacemouse",
         "returns its name")
  expect(troupe.devices.health("spacemouse").spacemouse.state == "replay", "replay health")
  run_until(function() return troupe.time() >= 1.0 end, 2)
  local p = crate:position()
  expect(p[1] > 0.2 and p[1] < 0.3 and math.abs(p[2] - 1) < 1e-9, "moving right at 1 s: " .. p[1])
  run_until(function() return troupe.time() >= 5.0 end, 6)
  p = crate:position()
  expect(math.abs(p[1] - 0.5) < 1e-6 and math.abs(p[2] - 1.25) < 1e-6 and math.abs(p[3]) < 1e-6,
         string.format("crate at %.6f %.6f %.6f", p[1], p[2], p[3]))
end)
