-- Whole-body reach (issue 16): grasp, receive and plan_grasp lean with the spine and, for
-- low targets, bend the knees (the heels rising once the ankles bend no further, the toes
-- on the floor), keeping the centre of mass over the feet, before they call a target out
-- of reach. Each case prints how far the body leans
-- (the trunk's vl5 → vt1 axis, degrees) and how far the pelvis is lowered.

local function report(name, plan)
  print(string.format("%s: lean %.1f°, crouch %.2f m", name, math.deg(plan.lean), plan.crouch))
end

local function grasped(ann, obj, opts)
  opts.object = obj
  local g = ann:grasp(opts)
  expect(g:wait() == "completed", "grasp " .. obj.name .. ": " .. g.status .. " " .. tostring(g.error))
  expect(obj.holder == ann, "holds " .. obj.name)
end

-- The balls of the feet (the metatarsal joints, which a rising heel rolls on) where they
-- were standing, within 1 cm.
local function balls_stay(ann, before)
  for i, j in ipairs({ "l_metatarsal", "r_metatarsal" }) do
    local p = ann:joint_position(j)
    local d = math.sqrt((p[1] - before[i][1])^2 + (p[2] - before[i][2])^2 + (p[3] - before[i][3])^2)
    expect(d < 0.01, string.format("%s moved %.3f m", j, d))
  end
end

-- The template's foot, in ankle-to-ball lengths: the heel's back end 0.29 behind the
-- ankle, the tip of the toes 0.23 ahead of the ball (metatarsal) joint.
local HEEL, TOES = 0.29, 0.23

-- `actor`'s ankles and balls of the feet as it stands flat on the floor: the feet's shape
-- for `lowest_sole`.
local function feet_standing(actor)
  local feet = {}
  for _, s in ipairs({ "l_", "r_" }) do
    feet[#feet + 1] = { side = s, ankle = actor:joint_position(s .. "ankle"),
                        ball = actor:joint_position(s .. "metatarsal") }
  end
  return feet
end

-- The pitch (radians, toes up positive) of the line from `a` to `b`.
local function pitch(a, b)
  return math.atan(b[2] - a[2], math.sqrt((b[1] - a[1])^2 + (b[3] - a[3])^2))
end

-- The height (m) of the lowest point of `actor`'s soles, below the floor if negative: per
-- foot, the heel, the sole under the ball joint and under the tip of the toes, placed by
-- the ankle and ball joints, the foot's pitch from them and the toes' own flexion.
local function lowest_sole(actor, standing)
  local low = math.huge
  for _, f in ipairs(standing) do
    local a, b = actor:joint_position(f.side .. "ankle"), actor:joint_position(f.side .. "metatarsal")
    local len = math.sqrt((f.ball[1] - f.ankle[1])^2 + (f.ball[3] - f.ankle[3])^2)
    local ya, yb = f.ankle[2], f.ball[2]
    local foot = pitch(a, b) - pitch(f.ankle, f.ball)
    local toes = foot - actor:dof(f.side .. "metatarsal_flexion")
    low = math.min(low,
      a[2] - HEEL * len * math.sin(foot) - ya * math.cos(foot),
      b[2] - yb * math.cos(foot),
      b[2] + TOES * len * math.sin(toes) - yb * math.cos(toes))
  end
  return low
end

-- The lowest point of `actor`'s soles over every tick until `done()` is true (or `seconds`).
local function lowest_sole_until(actor, standing, done, seconds)
  local lowest = 1
  run_until(function()
    lowest = math.min(lowest, lowest_sole(actor, standing))
    return done()
  end, seconds)
  return lowest
end

-- A cup standing on a 0.9 m table top, 0.30 m in front of `actor`'s right wrist.
local function cup_before_wrist(actor, name)
  local w = actor:joint_position("r_wrist")
  return troupe.object{ name = name, shape = "cylinder", radius = 0.035, height = 0.1,
                        at = {w[1], 0.95, w[3] + 0.30} }
end

test("a cup on a 0.9 m table 0.30 m in front of the wrist: leans", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:joint_position("r_wrist")
  troupe.object{ name = "table", shape = "box", size = {0.6, 0.9, 0.5}, at = {w[1], 0.45, w[3] + 0.5} }
  local cup = cup_before_wrist(ann, "cup")
  local arm_only, why = troupe.plan_grasp(ann, cup, { hand = "right", scope = "right_arm+right_hand" })
  expect(arm_only == nil and why:find("out of reach") ~= nil, "the arm alone cannot: " .. tostring(why))
  local plan = troupe.plan_grasp(ann, cup, { hand = "right" })
  expect(plan ~= nil and plan.lean > 0.02 and plan.crouch == 0, "planned by leaning")
  report("cup on a 0.9 m table", plan)
  grasped(ann, cup, { hand = "right" })
  expect(ann:dof("vl5_flexion") ~= 0 or ann:dof("vt12_flexion") ~= 0, "the spine moved")
end)

test("the scope is honoured: right_arm+right_hand+spine leans, right_arm+right_hand does not", function()
  local ann = troupe.actor{ name = "ann" }
  local cup = cup_before_wrist(ann, "cup")
  local g = ann:grasp{ object = cup, hand = "right", scope = "right_arm+right_hand+spine" }
  expect(g:wait() == "completed", "with the spine: " .. tostring(g.error))
  local bob = troupe.actor{ name = "bob", at = {3, 0, 0} }
  local cup2 = cup_before_wrist(bob, "cup2")
  local arm = bob:grasp{ object = cup2, hand = "right", scope = "right_arm+right_hand" }
  expect(arm:wait() == "failed" and arm.error:find("out of reach") ~= nil, "arm only: " .. tostring(arm.error))
end)

test("a cup on a 0.75 m café table 0.45 m in front of the shoulder", function()
  local ann = troupe.actor{ name = "ann" }
  local s = ann:joint_position("r_shoulder")
  troupe.object{ name = "table", shape = "box", size = {0.7, 0.75, 0.5}, at = {s[1], 0.375, s[3] + 0.62} }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {s[1], 0.80, s[3] + 0.45} }
  local plan = troupe.plan_grasp(ann, cup, { hand = "right" })
  expect(plan ~= nil, "planned")
  report("cup on a 0.75 m café table", plan)
  grasped(ann, cup, { hand = "right" })
end)

test("a ball on the floor 0.4 m ahead: bends the knees, on the balls of the feet", function()
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.1, at = {0, 0.1, 0.4} }
  local plan = troupe.plan_grasp(ann, ball)
  expect(plan ~= nil and plan.crouch > 0, "planned by crouching")
  report("ball on the floor", plan)
  local ankle = ann:joint_position("l_ankle")[2]
  local balls = { ann:joint_position("l_metatarsal"), ann:joint_position("r_metatarsal") }
  local standing = feet_standing(ann)
  grasped(ann, ball, {})
  expect(ann:position()[2] < 0.9, "the pelvis went down: " .. ann:position()[2])
  expect(ann:dof("l_knee_flexion") > 0.3, "knees bent: " .. ann:dof("l_knee_flexion"))
  balls_stay(ann, balls)
  expect(ann:joint_position("l_ankle")[2] > ankle + 0.03, "the heels rose: ankle " .. ann:joint_position("l_ankle")[2])
  -- Walking off with the ball, the body rises smoothly and the soles stay on the floor:
  -- the raised heels come down as the pelvis rises (put down at once, they bent the
  -- ankles past their limit and the toes went 8 cm into the floor).
  local w = ann:walk{ to = {0, 0, 1.5}, speed = 0.8 }
  local y, jump, lowest = ann:position()[2], 0, 1
  expect(run_until(function()
    local now = ann:position()[2]
    jump = math.max(jump, math.abs(now - y))
    y = now
    lowest = math.min(lowest, lowest_sole(ann, standing))
    return w.status ~= "active"
  end, 8), "walked")
  print(string.format("walking off from the crouch: pelvis up at most %.3f m a tick, lowest sole %.1f mm",
    jump, lowest * 1000))
  expect(w.status == "completed", "walk: " .. w.status .. " " .. tostring(w.error))
  expect(jump < 0.03, string.format("the pelvis rose by at most %.3f m a tick", jump))
  expect(lowest > -0.005, string.format("a sole %.1f mm into the floor", -lowest * 1000))
  expect(ball.holder == ann, "still holds the ball")
end)

test("a ball on the floor by a table: the crouch keeps the knees off it, or says it cannot", function()
  -- The knees come forwards as the pelvis goes down: walked to a ball 5 cm out from a
  -- café table's edge, the crouch put a thigh 48 mm into the table.
  local results = {}
  for i, out in ipairs({ 0.05, 0.15 }) do
    local x = 10 * i
    troupe.object{ name = "table" .. i, shape = "box", size = {0.84, 0.75, 0.87}, at = {x - 1.425, 0.375, -0.934}, mass = 20 }
    local ball = troupe.object{ name = "ball" .. i, shape = "sphere", radius = 0.08, at = {x - 1.007 + out, 0.08, -0.85},
                                mass = 0.4, obstacle = false }
    local p1 = troupe.actor{ name = "p" .. i, height = 1.797, at = {x - 0.5, 0, 0.6}, facing = 180 }
    local w = p1:walk{ to = ball }
    expect(run_until(function() return w.status ~= "active" and w.status ~= "pending" end, 10), "walked")
    local g = p1:grasp{ object = ball }
    local deepest = 0
    run_until(function()
      deepest = math.max(deepest, (troupe.deepest_overlap()))
      return g.status ~= "active" and g.status ~= "pending"
    end, 6)
    results[i] = { g = g, deepest = deepest }
    print(string.format("a ball %.2f m out from a table's edge: grasp %s (%s); deepest %.4f m",
      out, g.status, tostring(g.error), deepest))
    expect(deepest <= 0.01, string.format("%.3f m into the table", deepest))
  end
  expect(results[1].g.status == "completed"
         or tostring(results[1].g.error):find("the knees clear of `table1`", 1, true),
         "by the edge: grasped, or refused naming the table: " .. tostring(results[1].g.error))
  expect(results[2].g.status == "completed", "15 cm out: grasped: " .. tostring(results[2].g.error))
end)

test("a 0.4 m ball at 1.0 m, 0.45 m ahead, with both hands", function()
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "big", shape = "sphere", radius = 0.2, at = {0, 1.0, 0.45}, mass = 0.5 }
  local plan = troupe.plan_grasp(ann, ball, { hand = "both" })
  expect(plan ~= nil and plan.hand_count == 2, "planned with both hands")
  report("0.4 m ball with both hands", plan)
  grasped(ann, ball, { hand = "both" })
end)

test("a hand-over between two actors 0.9 m apart, received with the left hand", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  grasped(ann, cup, { hand = "right" })
  local give = ann:give{ object = cup, to = bob, hand = "left" }
  local receive = bob:actions()[1]
  expect(give:wait() == "completed", "give: " .. tostring(give.error) .. " / receive: " .. tostring(receive.error))
  expect(cup.holder == bob, "bob holds it")
  local spine = 0
  for _, d in ipairs({ "vl5_flexion", "vt12_flexion", "vt6_flexion", "vt1_flexion" }) do spine = spine + bob:dof(d) end
  print(string.format("hand-over at 0.9 m: bob's spine flexes %.1f° in all, his pelvis %.2f m down",
                      math.deg(spine), 0.962 - bob:position()[2]))
end)

test("out of reach still says so, naming what was tried", function()
  local ann = troupe.actor{ name = "ann" }
  local far = troupe.object{ name = "far", shape = "sphere", radius = 0.04, at = {0, 1, 1.5} }
  local plan, why = troupe.plan_grasp(ann, far)
  expect(plan == nil and why:find("out of reach") and why:find("leaning and crouching"), tostring(why))
end)

test("reach leans for a point the arm alone misses, and crouches for a low one", function()
  local ann = troupe.actor{ name = "ann" }
  local r = ann:reach{ hand = "right", target = {-0.2, 0.95, 0.7}, duration = 1 }
  expect(r:wait() == "completed", "lean: " .. tostring(r.error))
  local bob = troupe.actor{ name = "bob", at = {3, 0, 0} }
  local low = bob:reach{ hand = "right", target = {2.8, 0.25, 0.35}, duration = 1.2 }
  expect(low:wait() == "completed", "crouch: " .. tostring(low.error))
  expect(bob:position()[2] < 0.9 and bob:dof("r_knee_flexion") > 0.3, "crouched: " .. bob:position()[2])
  run(0.5)
  expect(bob:position()[2] < 0.9, "the body holds the crouch after the reach")
  local cal = troupe.actor{ name = "cal", at = {6, 0, 0} }
  local fixed = cal:reach{ hand = "right", target = {5.8, 0.95, 0.7}, scope = "right_arm", duration = 1 }
  expect(fixed:wait() == "failed", "right_arm only does not lean")
end)

test("a crouch to the floor keeps every sole point on the floor: an adult, a child, a low place", function()
  -- The ankles bend 30° at most: lowering the pelvis straight down, past 0.1 m, with the
  -- heels down, the foot turned about the ankle and the toes went 8-11 cm into the floor.
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.1, at = {0, 0.1, 0.4}, mass = 0.5 }
  local kid = troupe.actor{ name = "kid", template = "child", at = {3, 0, 0} }
  local small = troupe.object{ name = "small", shape = "sphere", radius = 0.07, at = {3, 0.07, 0.3}, mass = 0.2 }
  local cal = troupe.actor{ name = "cal", at = {6, 0, 0} }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1,
                             at = {6.25, 0.95, 0.3}, mass = 0.3 }
  troupe.object{ name = "stand", shape = "cylinder", radius = 0.1, height = 0.9, at = {6.25, 0.45, 0.3},
                 mass = 10, obstacle = false }
  troupe.object{ name = "step", shape = "box", size = {0.4, 0.05, 0.3}, at = {6, 0.025, 0.45} }
  local feet = { ann = feet_standing(ann), kid = feet_standing(kid), cal = feet_standing(cal) }
  report("a child's ball on the floor", troupe.plan_grasp(kid, small))
  grasped(cal, cup, { hand = "right" })
  local g = { ann = ann:grasp{ object = ball }, kid = kid:grasp{ object = small },
              cal = cal:place{ object = cup, at = {6, 0.1, 0.45} } }
  local low = { ann = 1, kid = 1, cal = 1 }
  local deepest = { ann = 0, kid = 0, cal = 0 }
  local actors = { ann = ann, kid = kid, cal = cal }
  run_until(function()
    local active = false
    for name, a in pairs(actors) do
      low[name] = math.min(low[name], lowest_sole(a, feet[name]))
      deepest[name] = math.min(deepest[name], a:dof("root_y"))
      active = active or g[name].status == "active"
    end
    return not active
  end, 6)
  run_until(function()
    for name, a in pairs(actors) do low[name] = math.min(low[name], lowest_sole(a, feet[name])) end
    return false
  end, 0.5)
  for _, name in ipairs({ "ann", "kid", "cal" }) do
    print(string.format("%s (%s, crouched %.2f m): the lowest sole point %.3f m", name,
                        g[name].kind, -deepest[name], low[name]))
    expect(g[name].status == "completed", name .. ": " .. g[name].status .. " " .. tostring(g[name].error))
    expect(deepest[name] < -0.25, string.format("%s crouched: %.3f m", name, deepest[name]))
    expect(low[name] > -0.005, string.format("%s's soles stay on the floor: %.3f m", name, low[name]))
  end
end)

test("a crouch keeps the feet on the floor however it ends: stopped, completed, placing", function()
  -- A cup on a 0.75 m table at the left: the grasp crouches. Interpolating the knees with
  -- the pelvis, the soles sank 10 cm halfway and stayed there when the grasp stopped.
  local ann = troupe.actor{ name = "ann" }
  local feet = feet_standing(ann)
  troupe.object{ name = "table", shape = "box", size = {0.6, 0.75, 0.5}, at = {-0.8, 0.375, 0.45} }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1,
                             at = {-0.65, 0.8, 0.35} }
  local plan = troupe.plan_grasp(ann, cup, { hand = "left" })
  expect(plan ~= nil and plan.crouch > 0, "the grasp crouches")
  local g = ann:grasp{ object = cup, hand = "left", duration = 1.2 }
  local t0 = troupe.time()
  local low = lowest_sole_until(ann, feet, function() return troupe.time() - t0 >= 0.5 end, 1)
  g:stop()
  low = math.min(low, lowest_sole_until(ann, feet, function() return false end, 1))
  print(string.format("stopped crouching grasp: pelvis %.3f m, lowest sole point %.3f m",
                      ann:position()[2], low))
  expect(ann:position()[2] < 0.95, "stopped halfway down: " .. ann:position()[2])
  expect(low > -0.005, string.format("the soles stay on the floor: %.3f m", low))

  -- Completed, then put down on a low table: every tick, the feet stay where they stand.
  local bob = troupe.actor{ name = "bob", at = {3, 0, 0} }
  feet = feet_standing(bob)
  troupe.object{ name = "table2", shape = "box", size = {0.6, 0.75, 0.5}, at = {2.2, 0.375, 0.45} }
  local cup2 = troupe.object{ name = "cup2", shape = "cylinder", radius = 0.04, height = 0.1,
                              at = {2.35, 0.8, 0.35} }
  local g2 = bob:grasp{ object = cup2, hand = "left" }
  low = lowest_sole_until(bob, feet, function() return g2.status ~= "active" end, 4)
  expect(g2.status == "completed", "grasp: " .. tostring(g2.error))
  local p = bob:place{ object = cup2, at = {2.3, 0.8, 0.5} }
  low = math.min(low, lowest_sole_until(bob, feet, function() return p.status ~= "active" end, 4))
  expect(p.status == "completed", "place: " .. tostring(p.error))
  print(string.format("crouching grasp and place: lowest sole point %.3f m", low))
  expect(low > -0.005, string.format("grasp and place: the lowest sole point %.3f m", low))

  -- A hand reach to a low point crouches along its path, the soles on the floor too.
  local cal = troupe.actor{ name = "cal", at = {6, 0, 0} }
  feet = feet_standing(cal)
  local r = cal:reach{ hand = "right", target = {5.8, 0.25, 0.35}, duration = 1.2 }
  low = lowest_sole_until(cal, feet, function() return r.status ~= "active" end, 3)
  expect(r.status == "completed", "reach: " .. tostring(r.error))
  print(string.format("crouching reach: lowest sole point %.3f m", low))
  expect(low > -0.005, string.format("reach: the lowest sole point %.3f m", low))
end)

test("a box held in both hands is placed on a sideboard, both hands on it all the way", function()
  for i, d in ipairs({ 0.45, 0.55, 0.7 }) do
    local x = i * 3
    local a = troupe.actor{ name = "a" .. i, at = {x, 0, 0} }
    troupe.object{ name = "sb" .. i, shape = "box", size = {0.8, 0.7, 0.45}, at = {x, 0.35, d + 0.025} }
    local box = troupe.object{ name = "box" .. i, shape = "box", size = {0.4, 0.3, 0.3}, at = {x, 1.0, 0.35},
                               mass = 2, obstacle = false }
    grasped(a, box, { hand = "both" })
    local function gap()
      local l, r = a:joint_position("l_wrist"), a:joint_position("r_wrist")
      return math.sqrt((l[1] - r[1])^2 + (l[2] - r[2])^2 + (l[3] - r[3])^2)
    end
    local held, drift = gap(), 0
    local p = a:place{ object = box, at = {x, 0.85, d + 0.1} }
    run_until(function()
      if box.holder == a then drift = math.max(drift, math.abs(gap() - held)) end
      return p.status ~= "active"
    end, 4)
    local b = box:position()
    local tilt = math.deg(math.acos(box:up()[2]))
    print(string.format("box on a sideboard %.2f m ahead: place %s, the wrists' gap drifted %.3f m, box at (%.3f, %.3f, %.3f), tilt %.1f°",
                        d - 0.2, p.status, drift, b[1] - x, b[2], b[3], tilt))
    expect(p.status == "completed", "place " .. i .. ": " .. tostring(p.error))
    expect(box.holder == nil, "both hands let go")
    expect(math.abs(b[1] - x) < 0.01 and math.abs(b[2] - 0.85) < 0.01 and math.abs(b[3] - d - 0.1) < 0.01,
           string.format("the box went down where asked: (%.3f, %.3f, %.3f)", b[1] - x, b[2], b[3]))
    expect(tilt < 1, "upright: " .. tilt)
    expect(drift < 0.01, string.format("the hands kept their grip: the wrists' gap changed %.3f m", drift))
  end
end)

test("a cup held in the other hand stays upright where it was while a place leans", function()
  local w = troupe.actor{ name = "w" }
  troupe.object{ name = "table", shape = "box", size = {0.6, 0.75, 0.6}, at = {0, 0.375, 0.75} }
  local c1 = troupe.object{ name = "c1", shape = "cylinder", radius = 0.04, height = 0.1, at = {-0.25, 1.05, 0.3} }
  local c2 = troupe.object{ name = "c2", shape = "cylinder", radius = 0.04, height = 0.1, at = {0.25, 1.05, 0.3} }
  grasped(w, c1, { hand = "right" })
  grasped(w, c2, { hand = "left" })
  local function rel() local p, r = c1:position(), w:position(); return { p[1] - r[1], p[2] - r[2], p[3] - r[3] } end
  local tilt = function() return math.deg(math.acos(c1:up()[2])) end
  local before, worst, moved = rel(), 0, 0
  local p = w:place{ object = c2, at = {0.12, 0.80, 0.65} }
  run_until(function()
    local now = rel()
    worst = math.max(worst, tilt())
    moved = math.max(moved, math.sqrt((now[1] - before[1])^2 + (now[2] - before[2])^2 + (now[3] - before[3])^2))
    return p.status ~= "active"
  end, 4)
  print(string.format("placing with the left hand, leaning %.1f°: the right-hand cup tilted at most %.1f°, moved %.3f m on the body",
                      math.deg(w:dof("vl5_flexion")), worst, moved))
  expect(p.status == "completed", "place: " .. tostring(p.error))
  expect(worst < 3, string.format("the other cup stays upright: %.1f°", worst))
  expect(moved < 0.01, string.format("and where it was on the body: %.3f m", moved))
end)

test("out of reach names what limited the reach, not the tolerance", function()
  local w = troupe.actor{ name = "w" }
  troupe.object{ name = "counter", shape = "box", size = {1.4, 1.0, 0.5}, at = {0, 0.5, 1.3} }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1, at = {-0.3, 1.05, 1.15} }
  local plan, why = troupe.plan_grasp(w, cup, { hand = "right" })
  print("a cup 1.15 m ahead on a counter: " .. tostring(why))
  expect(plan == nil and why:find("out of reach"), tostring(why))
  expect(why:find("misses by 0.005") == nil, "not the tolerance: " .. why)
  expect(why:find("leaning the trunk") or why:find("centre of mass"), "names the limit: " .. why)
  local g = w:grasp{ object = cup, hand = "right" }
  expect(g:wait() == "failed" and g.error == why, "the grasp says the same: " .. tostring(g.error))
end)
