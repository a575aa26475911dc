-- Whole-body reach (issue 16): grasp, receive and plan_grasp lean with the spine and, for
-- low targets, bend the knees with the heels down, keeping the centre of mass over the
-- feet, before they call a target out of reach. Each case prints how far the body leans
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

-- Heels down: both ankles where they were standing, within 1 cm.
local function ankles_stay(ann, before)
  for i, j in ipairs({ "l_ankle", "r_ankle" }) do
    local p = ann:joint_position(j)
    local d = math.sqrt((p[1] - before[i][1])^2 + (p[2] - before[i][2])^2 + (p[3] - before[i][3])^2)
    expect(d < 0.01, string.format("%s moved %.3f m", j, d))
  end
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

test("a ball on the floor 0.4 m ahead: bends the knees, heels down", function()
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.1, at = {0, 0.1, 0.4} }
  local plan = troupe.plan_grasp(ann, ball)
  expect(plan ~= nil and plan.crouch > 0, "planned by crouching")
  report("ball on the floor", plan)
  local ankles = { ann:joint_position("l_ankle"), ann:joint_position("r_ankle") }
  grasped(ann, ball, {})
  expect(ann:position()[2] < 0.9, "the pelvis went down: " .. ann:position()[2])
  expect(ann:dof("l_knee_flexion") > 0.3, "knees bent: " .. ann:dof("l_knee_flexion"))
  ankles_stay(ann, ankles)
  -- Walking off with the ball, the body rises smoothly and the feet stay on the floor.
  local w = ann:walk{ to = {0, 0, 1.5}, speed = 0.8 }
  local y, jump, lowest = ann:position()[2], 0, 1
  expect(run_until(function()
    local now = ann:position()[2]
    jump = math.max(jump, math.abs(now - y))
    y = now
    lowest = math.min(lowest, ann:joint_position("l_ankle")[2], ann:joint_position("r_ankle")[2])
    return w.status ~= "active"
  end, 8), "walked")
  expect(w.status == "completed", "walk: " .. w.status .. " " .. tostring(w.error))
  expect(jump < 0.03, string.format("the pelvis rose by at most %.3f m a tick", jump))
  expect(lowest > 0.05, "no ankle went into the floor: " .. lowest)
  expect(ball.holder == ann, "still holds the ball")
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
