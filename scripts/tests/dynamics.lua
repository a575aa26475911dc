-- Dynamics: inverse and forward dynamics functions, simulate, servo, track.

local function near(a, b, tol) return math.abs(a - b) <= tol end

test("inverse then forward dynamics gives the accelerations back", function()
  local ann = troupe.actor{ name = "ann" }
  local q = { root_y = 0.1, r_shoulder_flexion = 0.8, l_elbow_flexion = 0.5, vt6_flexion = 0.2 }
  local qd = { r_shoulder_flexion = 1.0, l_knee_flexion = -0.5 }
  local qdd = { r_elbow_flexion = 2.0, l_hip_flexion = -1.0, root_x = 0.3 }
  for _, fixed in ipairs{ false, true } do
    local tau = ann:inverse_dynamics{ q = q, qd = qd, qdd = qdd, fixed_root = fixed }
    local back = ann:forward_dynamics{ q = q, qd = qd, tau = tau, fixed_root = fixed }
    for _, name in ipairs(ann:dofs("all")) do
      local want = qdd[name] or 0
      if fixed and name:sub(1, 5) == "root_" then want = 0 end
      expect(near(back[name], want, 1e-7), name .. ": " .. back[name] .. " vs " .. want)
    end
  end
end)

test("holding still needs the weight at the root", function()
  local ann = troupe.actor{ name = "ann" }
  local tau = ann:inverse_dynamics{ fixed_root = true }
  -- 70 kg of solids and the 86 one-gram beads on the links no solid rides on (the
  -- same model as the exported URDF).
  expect(near(tau.root_y, 70.086 * 9.81, 1e-6), "root_y carries the weight: " .. tau.root_y)
  local free = ann:forward_dynamics{ tau = {} }
  expect(near(free.root_y, -9.81, 1e-9), "free fall: " .. free.root_y)
  local ok, e = pcall(function() return ann:inverse_dynamics{ q = { r_elbow_flexion = 0/0 } } end)
  expect(not ok and tostring(e):find("r_elbow_flexion"), "NaN is refused: " .. tostring(e))
  ok, e = pcall(function() return ann:forward_dynamics{ torque = {} } end)
  expect(not ok and tostring(e):find("unknown field `torque`"), tostring(e))
  -- A step so short that a tick would never end is refused, not run.
  ok, e = pcall(function() return ann:simulate{ small_time_step = 1e-9 } end)
  expect(not ok and tostring(e):find("small_time_step", 1, true) and tostring(e):find("at least 1e-5 s", 1, true),
         tostring(e))
end)

test("a released body falls and comes to rest on the floor", function()
  local ann = troupe.actor{ name = "ann" }
  ann:pose{ root_pitch = 0.1 }
  local fall = ann:simulate{}
  expect(run_until(function() return fall.status == "completed" end, 8), "comes to rest: " .. fall.status)
  local p = ann:position()
  expect(p[2] < 0.4, "lies on the floor: root at " .. p[2])
  expect(p[2] > 0.0, "not below it")
end)

test("a push at the centre of mass makes a jump", function()
  local ann = troupe.actor{ name = "ann" }
  local y0 = ann:position()[2]
  local top = y0
  ann:simulate{ duration = 1.0, push = { force = {0, 2 * 70 * 9.81, 0}, duration = 0.2 } }
  for _ = 1, 100 do run(0.01); top = math.max(top, ann:position()[2]) end
  expect(top - y0 > 0.2, "jumped " .. (top - y0) .. " m")
end)

test("a servoed actor reaches another actor's posture", function()
  local model = troupe.actor{ name = "model", at = {2, 0, 0} }
  model:pose{ r_shoulder_flexion = 1.2, l_shoulder_abduction = 0.8, r_elbow_flexion = 1.0, vt6_flexion = 0.2, skullbase_torsion = 0.4 }
  local bob = troupe.actor{ name = "bob" }
  local s = bob:servo{ target = model, scope = "upper_body", duration = 3 }
  run(2.5)
  for _, name in ipairs(bob:dofs("upper_body")) do
    expect(math.abs(bob:dof(name) - model:dof(name)) < math.rad(2), name .. " within 2°")
  end
  expect(s.status == "active", s.status)
end)

test("closed-loop tracking follows a sequence", function()
  local ann = troupe.actor{ name = "ann" }
  local seq = troupe.sequence{ r_shoulder_flexion = { {0, 0}, {1, 1.2}, {2, 1.2} },
                               r_elbow_flexion = { {0, 0}, {1, 0.8}, {2, 0.8} } }
  local a = ann:track{ sequence = seq }
  expect(run_until(function() return a.status == "completed" end, 5), "completes: " .. a.status)
  expect(math.abs(ann:dof("r_shoulder_flexion") - 1.2) < math.rad(1), "shoulder " .. ann:dof("r_shoulder_flexion"))
  expect(math.abs(ann:dof("r_elbow_flexion") - 0.8) < math.rad(1), "elbow " .. ann:dof("r_elbow_flexion"))
end)

test("a diverging simulation fails and the actor keeps its last valid posture", function()
  local ann = troupe.actor{ name = "ann" }
  ann:pose{ r_elbow_flexion = 0.5 }
  local a = ann:simulate{ small_time_step = 0.01, time_step = 0.01, push = { torque = {0, 1e6, 0}, duration = 1 } }
  local function posture()
    local p = ann:position()
    local v = { p[1], p[2], p[3] }
    for _, name in ipairs(ann:dofs("all")) do v[#v + 1] = ann:dof(name) end
    return v
  end
  local before, after
  for _ = 1, 200 do
    before = posture()
    run(0.01)
    if a.status == "failed" then after = posture(); break end
  end
  expect(after ~= nil, "fails: " .. a.status)
  expect(a.error:find("diverged") ~= nil, a.error)
  for i = 1, #before do
    expect(after[i] == before[i], "keeps the last valid posture: value " .. i .. " went from " .. before[i] .. " to " .. after[i])
    expect(after[i] == after[i] and math.abs(after[i]) < 1e6, "finite")
  end
  local ok, e = pcall(function() return ann:servo{ target = { r_elbow_flexion = "bent" } } end)
  expect(not ok, "bad target refused")
end)

test("servo follows an actor given by name; an unknown name or a root target says why", function()
  -- `target = "ann"` was refused ("must be a posture table or an actor, got string")
  -- where walk, give and grasp take names; `target = {root_x = …}` said "servo action:
  -- scope is empty".
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {2, 0, 0} }
  ann:pose{ r_elbow_flexion = 1.0 }
  local f = bob:servo{ target = "ann", scope = "right_arm", duration = 1 }
  expect(f:wait() == "completed", "completed: " .. tostring(f.error))
  expect(math.abs(bob:dof("r_elbow_flexion") - 1.0) < 0.1, "followed: " .. bob:dof("r_elbow_flexion"))
  local ok, e = pcall(function() return bob:servo{ target = "anne" } end)
  expect(not ok and tostring(e):find("servo: unknown actor `anne`; did you mean `ann`?", 1, true), tostring(e))
  ok, e = pcall(function() return bob:servo{ target = { root_x = 0.5 } } end)
  expect(not ok and tostring(e):find("servo: the target names only root DOFs, and the root is never servoed", 1, true), tostring(e))
end)
