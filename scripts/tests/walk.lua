-- Walking: the procedural walking motor (thesis 2.6, 6.4.2).

local function flat_dist(p, x, z)
  return math.sqrt((p[1] - x)^2 + (p[3] - z)^2)
end

local function angle_diff(a, b)
  local d = (a - b) % (2 * math.pi)
  if d > math.pi then d = d - 2 * math.pi end
  return math.abs(d)
end

test("walk to a point: arrives within 5 cm, facing the way it walked", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ to = {2, 0, 3}, speed = 1.3 }
  expect(w.kind == "walk", "kind is walk")
  expect(run_until(function() return w.status == "completed" end, 15), "completed: " .. tostring(w.error))
  local p = ann:position()
  expect(flat_dist(p, 2, 3) < 0.05, string.format("stopped %.3f m away", flat_dist(p, 2, 3)))
  expect(angle_diff(ann:dof("root_yaw"), math.atan(2, 3)) < 0.05, "faces the travel direction")
  expect(math.abs(ann:dof("l_knee_flexion")) < 0.02, "stands with straight legs")
end)

test("walk to a point with a requested heading", function()
  local ann = troupe.actor{ name = "ann", at = {1, 0, 1}, facing = 180 }
  local w = ann:walk{ to = {-1, 0, 2}, heading = 90 }
  expect(run_until(function() return w.status == "completed" end, 15), "completed: " .. tostring(w.error))
  expect(flat_dist(ann:position(), -1, 2) < 0.05, "arrived")
  expect(angle_diff(ann:dof("root_yaw"), math.rad(90)) < 0.05, "faces +X")
end)

test("a walk refuses a scope without its root, pelvis and legs, and a heading it cannot use", function()
  local ann = troupe.actor{ name = "ann" }
  local ok, e = pcall(function() return ann:walk{ velocity = 1, duration = 1, scope = "head" } end)
  expect(not ok and tostring(e):find("the scope leaves out 23 DOF(s) a walk cannot do without (`root_x`", 1, true),
         "a head-only walk is refused, naming what it lacks: " .. tostring(e))
  ok, e = pcall(function() return ann:walk{ velocity = 1, duration = 1, scope = "global+legs" } end)
  expect(not ok and tostring(e):find("`sacroiliac_tilt`", 1, true), "the pelvis too: " .. tostring(e))
  local w = ann:walk{ velocity = 1, duration = 1, scope = "global+lower_body" }
  run(1.5)
  expect(ann:position()[3] > 0.3, "root, pelvis and legs are enough: " .. ann:position()[3])
  ok, e = pcall(function() return ann:walk{ velocity = 1, heading = 90 } end)
  expect(not ok and tostring(e):find("`heading` (the way to face on arrival) applies to `to` and `path` walks", 1, true),
         "a velocity walk's heading is refused: " .. tostring(e))
  expect(w.status ~= "failed", w.status)
  troupe.object{ name = "table", shape = "box", size = {1, 0.7, 0.5}, at = {2, 0.35, 2} }
  ok, e = pcall(function() return ann:walk{ to = "tabl" } end)
  expect(not ok and tostring(e):find("did you mean `table`", 1, true), "a name's slip: " .. tostring(e))
  ok, e = pcall(function() return ann:walk{ velocity = 0 / 0 } end)
  expect(not ok and tostring(e):find("got nan", 1, true), "nan as Lua writes it: " .. tostring(e))
end)

test("an arrived walk brings its feet together in a quick step and completes within 1.5 s", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ to = {0, 0, 4} }
  local near
  expect(run_until(function()
    local p = ann:position()
    if not near and math.abs(p[3] - 4) < 0.01 and math.abs(p[1]) < 0.01 then near = troupe.time() end
    return w.status == "completed" or w.status == "failed"
  end, 10), "the walk ended: " .. w.status)
  expect(w.status == "completed", w.status)
  -- The last steps at the cadence of the body's speed, falling to nothing, took 2 s.
  expect(troupe.time() - near < 1.5,
         string.format("completed %.2f s after the body reached its goal", troupe.time() - near))
end)

test("a walk setting off 55° from where the body faces turns onto its way smoothly, a cup in hand", function()
  -- Below 60° the walk sets off without turning on the spot, and the planted feet hold
  -- the body's turn (31.5° from a planted foot) until one lifts. The body then turned
  -- the rest at 6 rad/s, 3.4° in a tick, and the cup in its hand moved 35 mm in one.
  local ann = troupe.actor{ name = "ann", at = {0, 0, 0}, facing = 41 }
  troupe.object{ name = "stand", shape = "cylinder", radius = 0.1, height = 0.95, at = {0.45, 0.475, 0.25}, mass = 10, obstacle = false }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1, at = {0.45, 1.0, 0.25}, mass = 0.3 }
  local g = ann:grasp{ object = cup, hand = "right" }
  run_until(function() return g.status ~= "active" and g.status ~= "pending" end, 10)
  expect(g.status == "completed", "the grasp: " .. g.status)
  local h, p = math.rad(96), ann:position()
  local w = ann:walk{ to = {p[1] + 1.97 * math.sin(h), 0, p[3] + 1.97 * math.cos(h)}, speed = 1.2 }
  local yaw, at = ann:dof("root_yaw"), cup:position()
  local fastest_turn, fastest_cup = 0, 0
  run_until(function()
    local y, c = ann:dof("root_yaw"), cup:position()
    fastest_turn = math.max(fastest_turn, math.abs(y - yaw) * troupe.rate())
    fastest_cup = math.max(fastest_cup, math.sqrt((c[1] - at[1])^2 + (c[2] - at[2])^2 + (c[3] - at[3])^2))
    yaw, at = y, c
    return w.status == "completed"
  end, 10)
  print(string.format("setting off 55° aside: fastest turn %.2f rad/s, cup's largest move %.1f mm in a tick",
    fastest_turn, fastest_cup * 1000))
  expect(w.status == "completed", "the walk: " .. w.status)
  expect(fastest_turn < 2.5, string.format("the body turned %.2f rad/s", fastest_turn))
  expect(fastest_cup < 0.025, string.format("the cup moved %.1f mm in a tick", fastest_cup * 1000))
end)

test("walk a path of floor points; feet stay on or above the floor", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ path = {{0, 2}, {1.5, 3}, {2, 1}}, speed = 1.1 }
  local lowest = 1
  local ok = run_until(function()
    for _, j in ipairs({ "l_metatarsal", "r_metatarsal", "l_ankle", "r_ankle" }) do
      lowest = math.min(lowest, ann:joint_position(j)[2])
    end
    return w.status == "completed"
  end, 20)
  expect(ok, "completed: " .. tostring(w.error))
  expect(flat_dist(ann:position(), 2, 1) < 0.05, "at the last point")
  expect(lowest > 0, "a foot joint went below the floor: " .. lowest)
end)

test("velocity walk: a function of time for a duration, then it stops", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ velocity = function(t) if t < 2 then return 0.8 else return 1.4 end end, duration = 5 }
  expect(run_until(function() return w.status == "completed" end, 10), "completed: " .. tostring(w.error))
  local z = ann:position()[3]
  -- About 0.8·2 + 1.4·3 m, less the smooth start and stop.
  expect(z > 3.5 and z < 5.8, "walked " .. z .. " m forward")
end)

test("a followed path whose root_yaw turns the body round as it walks on moves it smoothly", function()
  -- Walking on 3 m while turning to face back (or all the way round): held by its planted
  -- feet, the walk's clock was pushed on along the way the body faced, not the way it
  -- went, and the body jumped 0.13 m (0.22 m turning all the way round) in a tick.
  for i, turn in ipairs({ math.pi, 2 * math.pi }) do
    local ann = troupe.actor{ name = "ann" .. i, at = {4 * i, 0, 0} }
    local w = ann:walk{ follow = troupe.sequence{ root_x = {{0, 0}, {4, 0}}, root_z = {{0, 0}, {4, 3}},
                                                  root_yaw = {{0, 0}, {4, turn}} } }
    local last, fastest = ann:position(), 0
    expect(run_until(function()
      local p = ann:position()
      fastest = math.max(fastest, math.sqrt((p[1] - last[1])^2 + (p[3] - last[3])^2))
      last = p
      return w.status ~= "active" and w.status ~= "pending"
    end, 10), "ended")
    print(string.format("a followed path turning %.0f°: the root moved %.1f mm in a tick at most", math.deg(turn), fastest * 1000))
    expect(w.status == "completed", "completed: " .. w.status .. " " .. tostring(w.error))
    expect(fastest < 0.02, string.format("the root moved %.1f mm in a tick", fastest * 1000))
    expect(flat_dist(ann:position(), 4 * i, 3) < 0.05, "at the path's end")
  end
end)

test("a velocity walk asked to stand still for 11 s beside a wall is standing, not stuck", function()
  -- A velocity or a followed walk held back for 10 s fails as stuck (docs/navigation.md);
  -- one whose own speed is 0 meanwhile stands by request.
  local ann = troupe.actor{ name = "ann" }
  troupe.wall{ from = {-2, 0.6}, to = {2, 0.6}, thickness = 0.2, height = 2 }
  local w = ann:walk{ velocity = function(t) if t < 11 then return 0 else return 0.5 end end, duration = 14 }
  run_until(function() return w.status ~= "active" and w.status ~= "pending" end, 12)
  expect(w.status == "active", "still walking at 12 s: " .. w.status .. " " .. tostring(w.error))
  expect(run_until(function() return w.status == "failed" end, 13),
         "then held by the wall for 10 s it fails: " .. w.status)
  expect(tostring(w.error):find("stuck for 10 s, held by wall 1", 1, true), tostring(w.error))
end)

test("follow a keyframed Global_motion path", function()
  local ann = troupe.actor{ name = "ann" }
  local path = troupe.sequence{
    root_x = { {0, 0}, {2, 0.5}, {4, 2} },
    root_z = { {0, 0}, {2, 2}, {4, 3} },
  }
  local w = ann:walk{ follow = path }
  expect(run_until(function() return w.status == "completed" end, 10), "completed: " .. tostring(w.error))
  expect(flat_dist(ann:position(), 2, 3) < 0.05, "at the end of the keyframed path")
end)

test("a weighted wave on the right arm runs while walking; the head stays free", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ to = {0, 0, 4} }
  local wave = ann:play("../examples/wave.trk", { mode = "weighted", weight = 0.8, scope = "right_arm" })
  local look = ann:look_at{ target = {2, 1.6, 2}, duration = 2 }
  run(0.5)
  expect(wave.status == "active" or wave.status == "initiating", "wave runs alongside: " .. wave.status)
  expect(look.status == "active", "look_at runs alongside: " .. look.status)
  expect(w.status == "active", "walk runs: " .. w.status)
  expect(run_until(function() return w.status == "completed" end, 15), "walk completed")
end)

test("personification options change the gait", function()
  local a = troupe.actor{ name = "a" }
  local b = troupe.actor{ name = "b", at = {2, 0, 0} }
  a:walk{ velocity = 1.2, duration = 4 }
  b:walk{ velocity = 1.2, duration = 4, run = 0.8, arm_swing = 2, pelvis = 2 }
  local knee_a, knee_b, elbow_a, elbow_b = 0, 0, 0, 0
  run_until(function()
    knee_a = math.max(knee_a, a:dof("l_knee_flexion"))
    knee_b = math.max(knee_b, b:dof("l_knee_flexion"))
    elbow_a = math.max(elbow_a, a:dof("r_elbow_flexion"))
    elbow_b = math.max(elbow_b, b:dof("r_elbow_flexion"))
    return troupe.time() > 3
  end, 5)
  expect(knee_b > knee_a, "run-like bends the knees more")
  expect(elbow_b > elbow_a + 0.5, "run-like flexes the elbows")
end)

test("bad input is a clear error", function()
  local ann = troupe.actor{ name = "ann" }
  local function err(opts)
    local ok, e = pcall(function() return ann:walk(opts) end)
    expect(not ok, "expected an error for " .. tostring(opts))
    return tostring(e)
  end
  expect(err{ to = {0/0, 0, 1} }:find("not finite") ~= nil, "NaN target")
  expect(err{ to = {1, 2, 1} }:find("unreachable") ~= nil, "target off the floor")
  expect(err{ to = {1, 0, 1}, speed = 0 }:find("speed") ~= nil, "zero speed")
  expect(err{ to = {1, 0, 1}, speed = -1 }:find("> 0") ~= nil, "negative speed")
  expect(err{ path = {} }:find("empty") ~= nil, "empty path")
  expect(err{ path = {{1, 1}, {1, "x"}} }:find("path%[2%]") ~= nil, "bad path point")
  expect(err{ velocity = 0 }:find("velocity") ~= nil, "zero velocity")
  expect(err{ velocity = function(t) return 1 end }:find("duration") ~= nil, "function without duration")
  expect(err{ velocity = function(t) return -1 end, duration = 1 }:find("t = 0.00") ~= nil, "negative velocity at t")
  expect(err{ to = {1, 0, 1}, path = {{1, 1}} }:find("exactly one") ~= nil, "two routes")
  expect(err{ to = {1, 0, 1}, run = 3 }:find("run") ~= nil, "run out of range")
  expect(err{ to = {1, 0, 1}, stride = 2 }:find("unknown option") ~= nil, "unknown option")
  expect(err{ to = {1, 0, 1}, patience = 0 }:find("`patience` must be a number of seconds above 0, got 0", 1, true) ~= nil, "no patience")
  expect(err{ velocity = 1, patience = 5 }:find("`patience` (how long to wait for those in the way) applies to `to` and `path` walks", 1, true) ~= nil, "a velocity walk's patience")
  expect(err{ follow = troupe.sequence{ l_knee_flexion = {{0, 0}, {1, 1}} } }:find("root_x") ~= nil, "follow without root track")
end)

test("a walk starts on its feet: from a body lying where it fell it fails, saying so", function()
  local ann = troupe.actor{ name = "ann" }
  expect(ann:simulate{ duration = 3 }:wait() == "completed", "fell")
  local w = ann:walk{ to = {2, 0, 2} }
  expect(w:wait() == "failed", "refused: " .. w.status)
  expect(tostring(w.error):find("^walk: the body is not on its feet %(tilted") ~= nil, tostring(w.error))
  -- Nothing snapped: the body still lies where it fell.
  expect(math.abs(ann:dof("root_roll")) + math.abs(ann:dof("root_pitch")) > 0.6, "still lying")
end)
