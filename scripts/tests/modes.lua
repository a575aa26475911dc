-- Every priority mode, driven from Lua.
local function hold(value, dof)
  return troupe.sequence{ [dof or "r_elbow_flexion"] = { {0, value}, {0.5, value} } }
end

test("default waits for the overlapping action and starts the tick after", function()
  local ann = troupe.actor{ name = "ann" }
  local first = ann:play(hold(0.5), { duration = 0.2 })
  local second = ann:play(hold(1.0))
  run(0.05)
  expect(first.status == "active", "first runs")
  expect(second.status == "pending", "second waits, got " .. second.status)
  run_until(function() return first.status == "completed" end, 1)
  local done_at = troupe.tick()
  run_until(function() return second.status ~= "pending" end, 1)
  expect(troupe.tick() == done_at + 1, "second starts the tick after the first stops")
  run(0.1)
  expect(math.abs(ann:dof("r_elbow_flexion") - 1.0) < 1e-9, "second drives the DOF")
end)

test("weighted actions blend by weight", function()
  local ann = troupe.actor{ name = "ann" }
  ann:play(hold(1.0), { mode = "weighted", weight = 0.7 })
  run(0.05)
  expect(math.abs(ann:dof("r_elbow_flexion") - 0.7) < 1e-9, "alone: 70 % from the held value")
  ann:play(hold(2.0), { mode = "weighted", weight = 0.6 })
  run(0.05)
  local expected = (0.7 * 1.0 + 0.6 * 2.0) / 1.3
  expect(math.abs(ann:dof("r_elbow_flexion") - expected) < 1e-9, "together: normalised")
end)

test("exclusive pre-empts and the pre-empted action ends cancelled", function()
  local ann = troupe.actor{ name = "ann" }
  local old = ann:play(hold(0.5), { scope = "right_arm", ease_out = 0.1 })
  local other = ann:play(hold(0.3, "l_elbow_flexion"))
  run(0.2)
  local new = ann:play(hold(1.5), { mode = "exclusive", ease_in = 0.1 })
  expect(new:wait() == "completed", "exclusive completes")
  expect(old.status == "cancelled", "pre-empted action is cancelled, got " .. old.status)
  expect(old.error:find("pre%-empted") ~= nil, "the reason says pre-empted: " .. tostring(old.error))
  expect(other.status == "completed", "disjoint action untouched, got " .. other.status)
end)

test("clearing stops every action of the actor", function()
  local ann = troupe.actor{ name = "ann" }
  local arm = ann:play(hold(0.5), { duration = 5 })
  local leg = ann:play(hold(0.4, "l_knee_flexion"), { mode = "weighted", weight = 0.5, duration = 5 })
  run(0.1)
  local clear = ann:play(hold(0.2, "skullbase_flexion"), { mode = "clearing" })
  run(0.05)
  expect(arm.status == "cancelled" and leg.status == "cancelled", "all others cancelled")
  expect(clear.status == "active", "clearing runs")
end)

test("disjoint scopes run together", function()
  local ann = troupe.actor{ name = "ann" }
  local a = ann:play(hold(0.5), { scope = "right_arm" })
  local b = ann:play(hold(0.5, "l_elbow_flexion"), { scope = "left_arm" })
  run(0.05)
  expect(a.status == "active" and b.status == "active", "both active")
end)
