-- Reaching, inverse kinematics and looking.

local solids = require("support.solids")

local function dist(a, b)
  return math.sqrt((a[1] - b[1])^2 + (a[2] - b[2])^2 + (a[3] - b[3])^2)
end

test("reach a cup: the hand ends on it and the action completes", function()
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1,
                             at = {-0.25, 1.1, 0.4} }
  local ann = troupe.actor{ name = "ann" }
  local r
  ann:behave(function(self)
    r = self:reach{ hand = "right", target = cup, duration = 1 }
    r:wait()
  end)
  expect(run_until(function() return r ~= nil and r.status == "completed" end, 3), "completed: " .. tostring(r and r.error))
  expect(r.kind == "reach", "kind is reach")
end)

test("reach with via points and an orientation", function()
  local ann = troupe.actor{ name = "ann" }
  local r = ann:reach{ hand = "left", target = {0.25, 1.2, 0.35}, via = {{0.4, 1.0, 0.2}},
                       orientation = {-90, 0, 0}, duration = 1.2 }
  expect(run_until(function() return r.status == "completed" end, 3), "completed: " .. tostring(r.error))
end)

test("a reach too quick for its arm catches up instead of jumping at the end", function()
  -- An arm raised overhead in 0.4 s: held to 8 rad/s it lags, and on its last tick it
  -- jumped onto the target (the shoulder's abduction at 75 rad/s). It now goes on until
  -- it has caught up, and still ends on the target.
  local ann = troupe.actor{ name = "ann" }
  local target = {-0.2, 1.9, 0.1}
  local r = ann:reach{ hand = "right", target = target, duration = 0.4 }
  local fastest, where = solids.fastest_dof(ann, "right_arm", r, true)
  print(string.format("quick reach overhead: fastest DOF %.2f rad/s (%s), ended at %.2f s",
    fastest, where, troupe.time()))
  expect(r.status == "completed", "completed: " .. tostring(r.error))
  expect(dist(ann:joint_position("r_wrist"), target) < 0.1, "the hand is up there")
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
  expect(troupe.time() <= 0.4 + 0.5 + 0.015, "caught up within 0.5 s")
end)

test("a reach shorter than a tick aims at its target and catches up", function()
  -- Its only tick was also its first: it solved for the path's start, 0.51 m short, and
  -- failed, where 0.01 s completed.
  local ann = troupe.actor{ name = "ann" }
  local target = {-0.25, 1.1, 0.4}
  local r = ann:reach{ hand = "right", target = target, duration = 0.005 }
  expect(run_until(function() return r.status ~= "active" end, 1), "ended")
  expect(r.status == "completed", r.status .. ": " .. tostring(r.error))
  expect(troupe.time() <= 0.5 + 0.02, "caught up within 0.5 s: " .. troupe.time())
end)

test("an unreachable target fails with the distance in error", function()
  local ann = troupe.actor{ name = "ann" }
  local r = ann:reach{ target = {0, 1.2, 3}, duration = 0.5 }
  expect(run_until(function() return r.status == "failed" end, 2), "failed")
  expect(r.error:find("m from it") ~= nil, r.error)
end)

test("ik moves any joint: the left index tip to a point", function()
  local ann = troupe.actor{ name = "ann" }
  local goal = {0.2, 1.3, 0.3}
  local a = ann:ik{ effector = "l_index3", target = goal, scope = "left_arm+spine", duration = 0.8 }
  expect(run_until(function() return a.status == "completed" end, 2), "completed: " .. tostring(a.error))
  expect(dist(ann:joint_position("l_index3"), goal) < 0.001, "within a millimetre")
end)

test("reach another actor's hand", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.7}, facing = 180 }
  bob:pose{ l_shoulder_flexion = 1.2 }
  local r = ann:reach{ target = { actor = bob, joint = "l_wrist" }, duration = 1 }
  expect(run_until(function() return r.status == "completed" end, 3), "completed: " .. tostring(r.error))
end)

test("look_at turns the head toward a point and keeps running", function()
  local ann = troupe.actor{ name = "ann" }
  local l = ann:look_at{ target = {1, 1.6, 1} }
  run(1.5)
  expect(l.status == "active", "still active")
  expect(ann:dof("skullbase_torsion") > 0.1, "head turned left")
  l:cancel()
  expect(run_until(function() return l.status == "cancelled" end, 1), "cancelled")
end)

test("look_at refuses a scope without the head or eyes, and looks with the eyes alone", function()
  -- `scope = "right_arm"` ran to completion having moved nothing (every write refused,
  -- with a log warning); `scope = "eyes"` aimed the eyes as if the head had turned too.
  local ann = troupe.actor{ name = "ann" }
  local ok, err = pcall(function() return ann:look_at{ target = {0, 1.6, 2}, scope = "right_arm" } end)
  expect(not ok, "refused")
  err = tostring(err)
  expect(err:find("look_at: option `scope` must hold a DOF that moves the head or the eyes", 1, true) ~= nil, err)
  expect(err:find("reach.lua:", 1, true) ~= nil, "says where: " .. err)
  local l = ann:look_at{ target = {0.3, 1.6, 2}, scope = "eyes" }
  run(1)
  expect(l.status == "active", "runs: " .. l.status .. " " .. tostring(l.error))
  expect(ann:dof("skullbase_torsion") == 0, "the head stays")
  local pan = ann:dof("l_eyeball_pan")
  expect(pan > 0.1, "the eyes alone turn toward the target: pan " .. pan)
end)

test("self-collision is a per-actor setting", function()
  local ann = troupe.actor{ name = "ann" }
  ann:set{ self_collision = false }
  local ok, err = pcall(function() ann:set{ self_colision = true } end)
  expect(not ok and tostring(err):find("unknown setting `self_colision`") ~= nil, tostring(err))
  ok, err = pcall(function() ann:set{ self_collision = "yes" } end)
  expect(not ok and tostring(err):find("boolean") ~= nil, tostring(err))
end)

test("bad targets are errors, not crashes", function()
  local ann = troupe.actor{ name = "ann" }
  local function fails(f, needle)
    local ok, err = pcall(f)
    expect(not ok, "should fail: " .. needle)
    expect(tostring(err):find(needle, 1, true) ~= nil, "error mentions `" .. needle .. "`: " .. tostring(err))
  end
  fails(function() ann:reach{ target = {0/0, 1, 0} } end, "finite")
  fails(function() ann:reach{ } end, "`target` is required")
  fails(function() ann:reach{ hand = "middle", target = {0, 1, 0} } end, "hand")
  fails(function() ann:ik{ effector = "tail", target = {0, 1, 0} } end, "unknown joint `tail`")
  fails(function() ann:look_at{ target = { actor = "nobody", joint = "skullbase" } } end, "nobody")
  fails(function() ann:look_at{ target = { actor = ann, joint = "antenna" } } end, "antenna")
  fails(function() ann:reach{ target = {0, 1, 0}, via = {{1, 2}} } end, "via[1]")
end)
